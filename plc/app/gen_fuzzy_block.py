"""The fuzzy gain adapter's part of plc/app/P_ThermoST.st (helper 'fuzzy'), one block per zone.

plc/app/gen_p_thermost.py calls `fuzzy_decls(z)` and `fuzzy_body(z)` from its hooks; only `z.n` is used.
Registers of zone n start at %MD(200 + 50 (n - 1)); coils %QX4.0 + n - 1 (enable), %QX4.2 + n - 1 (load),
%QX4.4 + n - 1 (plant scaling). Parameter registers are applied on the self-resetting coil
bFuzzyLoadZone<n> (or automatically after a TUNE when bFuzzyPlantScalingZone<n> is set) and then show
the values in use. docs/fuzzy.md describes every register.
"""

from __future__ import annotations

from typing import Protocol

MD_BASE = 200
MD_ZONE_STRIDE = 50
MD_PARAM_OFFSET = 30
COIL_BYTE = 4


class ZoneLike(Protocol):
    n: int


# (suffix, type, comment) read-only explainability registers, offset = index
READ_ONLY: list[tuple[str, str, str]] = [
    ("E", "REAL", "fuzzy: control error e = W - X, degC"),
    ("Ec", "REAL", "fuzzy: filtered error rate ec = -dX/dt, degC/s"),
    ("Eq", "REAL", "fuzzy: quantised E = Ke * e on [-U, U]"),
    ("Ecq", "REAL", "fuzzy: quantised EC = Kec * ec on [-U, U]"),
    ("DKp", "REAL", "fuzzy: dKp of this cycle"),
    ("DKi", "REAL", "fuzzy: dKi of this cycle"),
    ("DKd", "REAL", "fuzzy: dKd of this cycle"),
    ("Kp", "REAL", "fuzzy: effective Kp written to the controller, %/degC"),
    ("Tn", "REAL", "fuzzy: effective Tn = Kp / Ki, s"),
    ("Tv", "REAL", "fuzzy: effective Tv = Kd / Kp, s"),
    ("Td", "REAL", "fuzzy: effective Td, s"),
    ("KpBase", "REAL", "fuzzy: base Kp from the tuner, %/degC"),
    ("TnBase", "REAL", "fuzzy: base Tn, s"),
    ("TvBase", "REAL", "fuzzy: base Tv, s"),
    ("TdBase", "REAL", "fuzzy: base Td, s"),
    ("KpRatio", "REAL", "fuzzy: effective / base Kp"),
    ("KiRatio", "REAL", "fuzzy: effective / base Ki"),
    ("KdRatio", "REAL", "fuzzy: effective / base Kd"),
    ("Rule1Strength", "REAL", "fuzzy: firing strength of the strongest rule (0 .. 1)"),
    ("Rule2Strength", "REAL", "fuzzy: strength of the 2nd strongest rule"),
    ("Rule3Strength", "REAL", "fuzzy: strength of the 3rd strongest rule"),
    ("Rule4Strength", "REAL", "fuzzy: strength of the 4th strongest rule"),
    ("Rule1", "DINT", "fuzzy: strongest rule, 10 * E set + EC set (sets 0 NB .. 6 PB)"),
    ("Rule2", "DINT", "fuzzy: 2nd strongest rule (same code)"),
    ("Rule3", "DINT", "fuzzy: 3rd strongest rule (same code)"),
    ("Rule4", "DINT", "fuzzy: 4th strongest rule (same code)"),
    (
        "ErrorId",
        "DINT",
        "fuzzy: 0 ok, 1 Ke/Kec, 2 rule table, 3 W/X not finite, 4 base set, 5 parameter, 6 cycle",
    ),
    ("Status", "DINT", "fuzzy: bit 0 active, bit 1 error, bit 2 query table ready"),
]
# (suffix, type, comment, ST_FuzzyParameter field or "" = special handling); offset MD_PARAM_OFFSET + index
PARAMS: list[tuple[str, str, str, str]] = [
    ("Ke", "REAL", "fuzzy: quantisation factor Ke, 1/degC (> 0)", "fKe"),
    ("Kec", "REAL", "fuzzy: quantisation factor Kec, s/degC (> 0)", "fKec"),
    ("EcFilter", "REAL", "fuzzy: ec filter time, s", "fEcFilterTime"),
    ("OutKp", "REAL", "fuzzy: dKp range +-, (relative)", "fOutKp"),
    ("OutKi", "REAL", "fuzzy: dKi range +-", "fOutKi"),
    ("OutKd", "REAL", "fuzzy: dKd range +-", "fOutKd"),
    ("RatioMin", "REAL", "fuzzy: lower bound of effective / base gain (Kp, Ki, Kd)", ""),
    ("RatioMax", "REAL", "fuzzy: upper bound of effective / base gain (Kp, Ki, Kd)", ""),
    ("MaxStep", "REAL", "fuzzy: largest output step a gain change may cause per cycle, %", "fMaxOutputStep"),
    ("Universe", "REAL", "fuzzy: half width U of the universe", "fUniverse"),
    ("GaussWidth", "REAL", "fuzzy: Gaussian sigma / set spacing", "fGaussWidth"),
    ("Membership", "DINT", "fuzzy: 0 triangular, 1 Gaussian, 2 mixed (seed 003)", ""),
    ("Defuzz", "DINT", "fuzzy: 0 centroid, 1 weighted average", ""),
    ("Preset", "DINT", "fuzzy: rule preset 0 textbook, 1 seed 000, 2 seed 003 (loaded when changed)", ""),
    ("Query", "DINT", "fuzzy: 1 query-table mode (cheap scan), 0 rule inference every cycle", ""),
    ("RuleAddr", "DINT", "fuzzy: rule mailbox: 100 * output (0 Kp 1 Ki 2 Kd) + 10 * E + EC (0 NB..6 PB)", ""),
    ("RuleValue", "DINT", "fuzzy: rule mailbox value -3 (NB) .. 3 (PB); write it before RuleAddr", ""),
]
COILS: list[tuple[str, int, str]] = [
    ("bFuzzy", 0, "fuzzy gain adapter on (off = fixed PID from the tuner)"),
    ("bFuzzyLoad", 2, "write TRUE: apply the fuzzy parameter registers (self-resetting)"),
    ("bFuzzyPlantScaling", 4, "Ke, Kec, ec filter from the identified plant (on load and after TUNE)"),
]
DIRECT_FIELDS = [(s, f) for s, _t, _c, f in PARAMS if f]


def md(z: ZoneLike, offset: int) -> int:
    return MD_BASE + MD_ZONE_STRIDE * (z.n - 1) + offset


def fuzzy_decls(z: ZoneLike) -> tuple[list[str], list[str]]:
    n = z.n
    loc = []
    for i, (suffix, typ, comment) in enumerate(READ_ONLY):
        loc.append(
            f"    fFuzzy{suffix}Zone{n} AT %MD{md(z, i)} : {typ}; (* {comment} *)"
            if typ == "REAL"
            else f"    nFuzzy{suffix}Zone{n} AT %MD{md(z, i)} : {typ}; (* {comment} *)"
        )
    for i, (suffix, typ, comment, _f) in enumerate(PARAMS):
        prefix = "f" if typ == "REAL" else "n"
        loc.append(
            f"    {prefix}Fuzzy{suffix}Zone{n} AT %MD{md(z, MD_PARAM_OFFSET + i)} : {typ}; (* {comment} *)"
        )
    for name, bit, comment in COILS:
        loc.append(f"    {name}Zone{n} AT %QX{COIL_BYTE}.{bit + n - 1} : BOOL; (* {comment} *)")
    internal = [
        f"    sFuzzyParZone{n} : ST_FuzzyParameter;",
        f"    fbFuzzyZone{n} : FB_FuzzyGainAdapter;",
        f"    bFuzzyInitZone{n} : BOOL;",
        f"    bFuzzyLoadReqZone{n} : BOOL;",
        f"    bFuzzyOkZone{n} : BOOL;",
        f"    nFuzzyPresetLoadedZone{n} : DINT := -1;",
        f"    fFuzzyTuPrevZone{n} : REAL;",
        f"    fFuzzyEcFilterRatioZone{n} : REAL := 0.25; (* ec filter time / dead time *)",
        f"    nFuzzyDefaultPresetZone{n} : DINT := 2; (* seed 003's table *)",
    ]
    return loc, internal


def _registers_from_params(n: int) -> list[str]:
    p = f"sFuzzyParZone{n}"
    lines = [f"    f{'Fuzzy'}{s}Zone{n} := {p}.{f};" for s, f in DIRECT_FIELDS]
    lines += [
        f"    fFuzzyRatioMinZone{n} := {p}.fKpRatioMin;",
        f"    fFuzzyRatioMaxZone{n} := {p}.fKpRatioMax;",
    ]
    return lines


def fuzzy_body(z: ZoneLike) -> list[str]:
    n = z.n
    p = f"sFuzzyParZone{n}"
    b = [
        f"  (* ---- fuzzy gain adapter, zone {n} (plc/app/gen_fuzzy_block.py, docs/fuzzy.md) ---- *)",
        f"  IF NOT bFuzzyInitZone{n} THEN",
        f"    {p}.bQueryTable := TRUE;",
        *_registers_from_params(n),
        f"    nFuzzyMembershipZone{n} := 0;",
        f"    nFuzzyDefuzzZone{n} := 0;",
        f"    nFuzzyPresetZone{n} := nFuzzyDefaultPresetZone{n};",
        f"    nFuzzyQueryZone{n} := 1;",
        f"    nFuzzyRuleAddrZone{n} := -1;",
        f"    bFuzzyPlantScalingZone{n} := TRUE;",
        f"    bFuzzyLoadReqZone{n} := TRUE;",
        f"    bFuzzyInitZone{n} := TRUE;",
        "  END_IF;",
        f"  IF nFuzzyRuleAddrZone{n} >= 0 THEN",
        f"    bFuzzyOkZone{n} := FC_FuzzySetRule(nOutput := DINT_TO_INT(nFuzzyRuleAddrZone{n} / 100),",
        f"      nSetE := DINT_TO_INT((nFuzzyRuleAddrZone{n} / 10) MOD 10) - 3,",
        f"      nSetEc := DINT_TO_INT(nFuzzyRuleAddrZone{n} MOD 10) - 3,",
        f"      nValue := DINT_TO_INT(LIMIT(-99, nFuzzyRuleValueZone{n}, 99)), sRules := {p}.sRules);",
        f"    nFuzzyRuleAddrZone{n} := -1;",
        "  END_IF;",
        f"  IF bFuzzyPlantScalingZone{n} AND (sParZone{n}.fTu <> fFuzzyTuPrevZone{n}) THEN",
        "    (* a new identification from TUNE: rescale Ke, Kec from the plant *)",
        f"    bFuzzyLoadReqZone{n} := TRUE;",
        "  END_IF;",
        f"  fFuzzyTuPrevZone{n} := sParZone{n}.fTu;",
        f"  IF bFuzzyLoadZone{n} OR bFuzzyLoadReqZone{n} THEN",
    ]
    b += [f"    {p}.{f} := fFuzzy{s}Zone{n};" for s, f in DIRECT_FIELDS]
    for gain in ("Kp", "Ki", "Kd"):
        b.append(f"    {p}.f{gain}RatioMin := fFuzzyRatioMinZone{n};")
        b.append(f"    {p}.f{gain}RatioMax := fFuzzyRatioMaxZone{n};")
    b += [
        f"    CASE nFuzzyMembershipZone{n} OF",
        f"      1: {p}.eMembership := eFUZZY_MF_GAUSSIAN;",
        f"      2: {p}.eMembership := eFUZZY_MF_MIXED;",
        "    ELSE",
        f"      {p}.eMembership := eFUZZY_MF_TRIANGULAR;",
        "    END_CASE;",
        f"    IF nFuzzyDefuzzZone{n} = 1 THEN",
        f"      {p}.eDefuzz := eFUZZY_DEFUZZ_WEIGHTED;",
        "    ELSE",
        f"      {p}.eDefuzz := eFUZZY_DEFUZZ_CENTROID;",
        "    END_IF;",
        f"    {p}.bQueryTable := nFuzzyQueryZone{n} <> 0;",
        f"    IF nFuzzyPresetZone{n} <> nFuzzyPresetLoadedZone{n} THEN",
        f"      CASE nFuzzyPresetZone{n} OF",
        f"        1: bFuzzyOkZone{n} := FC_FuzzyLoadPreset(ePreset := eFUZZY_PRESET_SEED000,",
        f"             sRules := {p}.sRules);",
        f"        2: bFuzzyOkZone{n} := FC_FuzzyLoadPreset(ePreset := eFUZZY_PRESET_SEED003,",
        f"             sRules := {p}.sRules);",
        "      ELSE",
        f"        bFuzzyOkZone{n} := FC_FuzzyLoadPreset(ePreset := eFUZZY_PRESET_TEXTBOOK,",
        f"          sRules := {p}.sRules);",
        "      END_CASE;",
        f"      nFuzzyPresetLoadedZone{n} := nFuzzyPresetZone{n};",
        "    END_IF;",
        f"    IF bFuzzyPlantScalingZone{n} THEN",
        f"      bFuzzyOkZone{n} := FC_FuzzyScalingFromPlant(fEcFilterRatio := fFuzzyEcFilterRatioZone{n},"
        f" sCtrlParam := sParZone{n}, sFuzzyParam := {p});",
        "    END_IF;",
        *[line.replace("    ", "    ", 1) for line in _registers_from_params(n)],
        "  END_IF;",
        f"  fbFuzzyZone{n}(bEnable := bFuzzyZone{n} AND (fbZone{n}.eCtrlState = eCTRL_STATE_ACTIVE),",
        f"    bLoad := bFuzzyLoadZone{n} OR bFuzzyLoadReqZone{n}, fW := fbZone{n}.fW, fX := fXZone{n},",
        f"    sCtrlParam := sParZone{n}, sFuzzyParam := {p});",
        f"  bFuzzyLoadZone{n} := FALSE;",
        f"  bFuzzyLoadReqZone{n} := FALSE;",
    ]
    f = f"fbFuzzyZone{n}"
    outputs = {
        "E": "fE",
        "Ec": "fEc",
        "Eq": "fEq",
        "Ecq": "fEcq",
        "DKp": "fDeltaKp",
        "DKi": "fDeltaKi",
        "DKd": "fDeltaKd",
        "Kp": "fKpEff",
        "Tn": "fTnEff",
        "Tv": "fTvEff",
        "Td": "fTdEff",
        "KpBase": "fKpBase",
        "TnBase": "fTnBase",
        "TvBase": "fTvBase",
        "TdBase": "fTdBase",
        "KpRatio": "fKpRatio",
        "KiRatio": "fKiRatio",
        "KdRatio": "fKdRatio",
    }
    b += [f"  fFuzzy{s}Zone{n} := {f}.{o};" for s, o in outputs.items()]
    for k in range(4):
        b.append(f"  fFuzzyRule{k + 1}StrengthZone{n} := {f}.aRuleStrength[{k}];")
        b.append(
            f"  nFuzzyRule{k + 1}Zone{n} := INT_TO_DINT(10 * ({f}.aRuleE[{k}] + 3) + {f}.aRuleEc[{k}] + 3);"
        )
    b += [
        f"  nFuzzyErrorIdZone{n} := INT_TO_DINT({f}.nErrorId);",
        f"  nFuzzyStatusZone{n} := 0;",
        f"  IF {f}.bActive THEN nFuzzyStatusZone{n} := nFuzzyStatusZone{n} + 1; END_IF;",
        f"  IF {f}.bError THEN nFuzzyStatusZone{n} := nFuzzyStatusZone{n} + 2; END_IF;",
        f"  IF {f}.bTableReady THEN nFuzzyStatusZone{n} := nFuzzyStatusZone{n} + 4; END_IF;",
    ]
    return b
