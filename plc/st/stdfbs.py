"""IEC standard function blocks with MatIEC's behaviour (ieclib's ST sources, scan for scan).

Timers read the PLC clock (`clock.ns`), which advances by the task interval per scan.
Variable names are the IEC ones, lower-case with the `v_` prefix the compiler uses.
"""

from __future__ import annotations


class Clock:
    __slots__ = ("ns",)

    def __init__(self) -> None:
        self.ns = 0


class _Timer:
    __slots__ = ("clk", "v_in", "v_pt", "v_q", "v_et", "state", "prev_in", "start")
    INPUTS = {"in": "TIME_IN", "pt": "TIME"}

    def __init__(self, clk: Clock) -> None:
        self.clk = clk
        self.v_in = False
        self.v_pt = 0
        self.v_q = False
        self.v_et = 0
        self.state = 0
        self.prev_in = False
        self.start = 0

    def _copy(self):
        new = type(self)(self.clk)
        for k in self.__slots__[1:]:
            setattr(new, k, getattr(self, k))
        return new


class TON(_Timer):
    __slots__ = ()

    def _run(self) -> None:
        now = self.clk.ns
        if self.state == 0 and not self.prev_in and self.v_in:
            self.state = 1
            self.v_q = False
            self.start = now
        elif not self.v_in:
            self.v_et = 0
            self.v_q = False
            self.state = 0
        elif self.state == 1:
            if self.start + self.v_pt <= now:
                self.state = 2
                self.v_q = True
                self.v_et = self.v_pt
            else:
                self.v_et = now - self.start
        self.prev_in = self.v_in


class TOF(_Timer):
    __slots__ = ()

    def _run(self) -> None:
        now = self.clk.ns
        if self.state == 0 and self.prev_in and not self.v_in:
            self.state = 1
            self.start = now
        elif self.v_in:
            self.v_et = 0
            self.state = 0
        elif self.state == 1:
            if self.start + self.v_pt <= now:
                self.state = 2
                self.v_et = self.v_pt
            else:
                self.v_et = now - self.start
        self.v_q = bool(self.v_in or self.state == 1)
        self.prev_in = self.v_in


class TP(_Timer):
    __slots__ = ()

    def _run(self) -> None:
        now = self.clk.ns
        if self.state == 0 and not self.prev_in and self.v_in:
            self.state = 1
            self.v_q = True
            self.start = now
        elif self.state == 1:
            if self.start + self.v_pt <= now:
                self.state = 2
                self.v_q = False
                self.v_et = self.v_pt
            else:
                self.v_et = now - self.start
        if self.state == 2 and not self.v_in:
            self.v_et = 0
            self.state = 0
        self.prev_in = self.v_in


class _Plain:
    __slots__ = ()
    FIELDS: tuple[tuple[str, object], ...] = ()

    def __init__(self, clk: Clock | None = None) -> None:
        for name, value in self.FIELDS:
            setattr(self, name, value)

    def _copy(self):
        new = type(self)()
        for name, _ in self.FIELDS:
            setattr(new, name, getattr(self, name))
        return new


class R_TRIG(_Plain):
    __slots__ = ("v_clk", "v_q", "m")
    FIELDS = (("v_clk", False), ("v_q", False), ("m", False))

    def _run(self) -> None:
        self.v_q = bool(self.v_clk and not self.m)
        self.m = self.v_clk


class F_TRIG(_Plain):
    __slots__ = ("v_clk", "v_q", "m")
    FIELDS = (
        ("v_clk", False),
        ("v_q", False),
        ("m", True),
    )  # M holds NOT CLK, starts TRUE: no edge in scan 1

    def _run(self) -> None:
        self.v_q = bool(not self.v_clk and not self.m)
        self.m = not self.v_clk


class SR(_Plain):
    __slots__ = ("v_s1", "v_r", "v_q1")
    FIELDS = (("v_s1", False), ("v_r", False), ("v_q1", False))

    def _run(self) -> None:
        self.v_q1 = bool(self.v_s1 or (not self.v_r and self.v_q1))


class RS(_Plain):
    __slots__ = ("v_s", "v_r1", "v_q1")
    FIELDS = (("v_s", False), ("v_r1", False), ("v_q1", False))

    def _run(self) -> None:
        self.v_q1 = bool(not self.v_r1 and (self.v_s or self.v_q1))


class CTU(_Plain):
    __slots__ = ("v_cu", "v_r", "v_pv", "v_q", "v_cv", "m")
    FIELDS = (("v_cu", False), ("v_r", False), ("v_pv", 0), ("v_q", False), ("v_cv", 0), ("m", False))

    def _run(self) -> None:
        edge = self.v_cu and not self.m
        self.m = self.v_cu
        if self.v_r:
            self.v_cv = 0
        elif edge and self.v_cv < self.v_pv:
            self.v_cv += 1
        self.v_q = self.v_cv >= self.v_pv


class CTD(_Plain):
    __slots__ = ("v_cd", "v_ld", "v_pv", "v_q", "v_cv", "m")
    FIELDS = (("v_cd", False), ("v_ld", False), ("v_pv", 0), ("v_q", False), ("v_cv", 0), ("m", False))

    def _run(self) -> None:
        edge = self.v_cd and not self.m
        self.m = self.v_cd
        if self.v_ld:
            self.v_cv = self.v_pv
        elif edge and self.v_cv > 0:
            self.v_cv -= 1
        self.v_q = self.v_cv <= 0


class CTUD(_Plain):
    __slots__ = ("v_cu", "v_cd", "v_r", "v_ld", "v_pv", "v_qu", "v_qd", "v_cv", "mu", "md")
    FIELDS = (
        ("v_cu", False),
        ("v_cd", False),
        ("v_r", False),
        ("v_ld", False),
        ("v_pv", 0),
        ("v_qu", False),
        ("v_qd", False),
        ("v_cv", 0),
        ("mu", False),
        ("md", False),
    )

    def _run(self) -> None:
        up = self.v_cu and not self.mu
        down = self.v_cd and not self.md
        self.mu = self.v_cu
        self.md = self.v_cd
        if self.v_r:
            self.v_cv = 0
        elif self.v_ld:
            self.v_cv = self.v_pv
        elif not (up and down):
            if up and self.v_cv < self.v_pv:
                self.v_cv += 1
            elif down and self.v_cv > 0:
                self.v_cv -= 1
        self.v_qu = self.v_cv >= self.v_pv
        self.v_qd = self.v_cv <= 0


#: name -> (class, {var: (iec type, section)})
STANDARD_FBS = {
    "TON": (TON, {"in": ("BOOL", "in"), "pt": ("TIME", "in"), "q": ("BOOL", "out"), "et": ("TIME", "out")}),
    "TOF": (TOF, {"in": ("BOOL", "in"), "pt": ("TIME", "in"), "q": ("BOOL", "out"), "et": ("TIME", "out")}),
    "TP": (TP, {"in": ("BOOL", "in"), "pt": ("TIME", "in"), "q": ("BOOL", "out"), "et": ("TIME", "out")}),
    "R_TRIG": (R_TRIG, {"clk": ("BOOL", "in"), "q": ("BOOL", "out")}),
    "F_TRIG": (F_TRIG, {"clk": ("BOOL", "in"), "q": ("BOOL", "out")}),
    "SR": (SR, {"s1": ("BOOL", "in"), "r": ("BOOL", "in"), "q1": ("BOOL", "out")}),
    "RS": (RS, {"s": ("BOOL", "in"), "r1": ("BOOL", "in"), "q1": ("BOOL", "out")}),
    "CTU": (
        CTU,
        {
            "cu": ("BOOL", "in"),
            "r": ("BOOL", "in"),
            "pv": ("INT", "in"),
            "q": ("BOOL", "out"),
            "cv": ("INT", "out"),
        },
    ),
    "CTD": (
        CTD,
        {
            "cd": ("BOOL", "in"),
            "ld": ("BOOL", "in"),
            "pv": ("INT", "in"),
            "q": ("BOOL", "out"),
            "cv": ("INT", "out"),
        },
    ),
    "CTUD": (
        CTUD,
        {
            "cu": ("BOOL", "in"),
            "cd": ("BOOL", "in"),
            "r": ("BOOL", "in"),
            "ld": ("BOOL", "in"),
            "pv": ("INT", "in"),
            "qu": ("BOOL", "out"),
            "qd": ("BOOL", "out"),
            "cv": ("INT", "out"),
        },
    ),
}
