"""Compile IEC 61131-3 ST (MatIEC dialect and semantics) to Python source, once, in stages.

1. parse (`plc.st.parser`): tree-sitter tree of each source;
2. index (`plc.st.index`): every TYPE, POU, variable and global with its declared type;
3. generate (`plc.st.codegen`): every expression is typed once as it is generated - its IEC type
   (MatIEC's type rules, `plc.st.typerules`) and the C class MatIEC's code gives it (float/double,
   integer promotion) - and becomes Python: one class per STRUCT / FUNCTION_BLOCK / PROGRAM, one
   function per FUNCTION; literals and constant folding live in `plc.st.literals`;
4. load (`load_application`): run the module, build the program instances and located variables.

The generated module's scan calls the program instances' `_run()` methods.
"""

from __future__ import annotations

import functools
import re
from dataclasses import dataclass
from types import CodeType

from plc.st import rt, stdfbs
from plc.st.app import Application, LocatedVar, Location
from plc.st.codegen import Instances, generate
from plc.st.diagnostics import Diagnostic, StError
from plc.st.index import Index
from plc.st.model import Pou, Var
from plc.st.parser import ParsedSource, parse_source
from plc.st.types import REAL, Type


class Compiler:
    """The stages on a list of parsed sources; `pous`, `globals` and `diags` come from the index."""

    def __init__(self, sources: list[ParsedSource], lenient: bool = False):
        self.index = Index(sources, lenient)
        self.diags = self.index.diags
        self.pous: dict[str, Pou] = self.index.pous
        self.globals: dict[str, Var] = self.index.globals

    def compile(self) -> tuple[str, Instances]:
        for src in self.index.sources:
            self.diags.extend(src.syntax_errors())
        if self.diags:
            return "", []
        self.index.build()
        return generate(self.index)


RUNTIME_NAMES = (
    "f32 ws8 ws16 ws32 ws64 wu8 wu16 wu32 wu64 idiv imod fdiv ix real_to_sint real_to_uint trunc time_mul "
    "time_div time_to_lreal time_to_int real_to_time int_to_time shl shr rol ror sqrt exp ln log10 sin cos "
    "tan asin acos atan expt limit mux abs_int abs_float INF NAN"
).split()


def _mk(obj, **kw):
    for k, v in kw.items():
        setattr(obj, k, v)
    return obj


def _copy_array(a: list) -> list:
    if a and hasattr(a[0], "_copy"):
        return [e._copy() for e in a]
    if a and isinstance(a[0], list):
        return [_copy_array(e) for e in a]
    return a[:]


def _namespace() -> dict:
    ns: dict = {name: getattr(rt, name) for name in RUNTIME_NAMES}
    ns["f32"] = rt.scan_f32()
    ns.update(
        {
            "mk": _mk,
            "copy_array": _copy_array,
            "Ref": rt.Ref,
            "deref": rt.deref,
            "Clock": stdfbs.Clock,
            "min": min,
            "max": max,
        }
    )
    for name, (cls, _) in stdfbs.STANDARD_FBS.items():
        ns[name] = cls
    return ns


def _parse_all(sources: list[tuple[str, str]]) -> list[ParsedSource]:
    return [parse_source(text, filename, blank_pragmas=True) for filename, text in sources]


def typecheck(sources: list[tuple[str, str]]) -> list[Diagnostic]:
    comp = Compiler(_parse_all(sources))
    comp.compile()
    return sorted(set(comp.diags))


def analyse(parsed: list[ParsedSource]) -> tuple[Index, list[Diagnostic]]:
    """The checker's view: the lenient index of the sources and the type findings of every POU that
    could be typed (declared only in terms of known types; a POU with a syntax error is left to the
    syntax rules). The same index and typing rules the compiler generates code with."""
    index = Index(parsed, lenient=True)
    index.build()
    declared = len(index.diags)
    generate(index)
    return index, sorted(set(index.diags[declared:]))


def compile_to_python(sources: list[tuple[str, str]]) -> tuple[str, Compiler, list]:
    comp = Compiler(_parse_all(sources))
    code, instances = comp.compile()
    if comp.diags:
        raise StError(sorted(set(comp.diags)))
    return code, comp, instances


# distinct applications a process keeps compiled: the bundle, a controller test program, a few more
COMPILED_KEPT = 8
LOCATION = re.compile(r"%([IQM])([XBWDL])?(\d+)(?:\.(\d+))?")


@dataclass(frozen=True)
class _LocatedDecl:
    """A located variable of a compilation: where it is declared (its attribute, v_<name> lower-case, on a
    program instance or the CONFIGURATION's globals) and what it is."""

    attr: str
    type: Type
    location: Location


@dataclass(frozen=True)
class _Compiled:
    """What loading needs of a compilation (not its parse trees): loading it again costs one module run."""

    code: str
    module: CodeType
    instances: Instances
    located: tuple[_LocatedDecl, ...]


def _located_decls(comp: Compiler, instances: Instances) -> tuple[_LocatedDecl, ...]:
    owners: list[tuple[str, dict[str, Var]]] = [("", comp.globals)]
    owners += [(inst, comp.pous[cls.split("_", 1)[1]].vars) for inst, cls, _ in instances]
    decls = []
    for inst, table in owners:
        for name, v in table.items():
            m = LOCATION.fullmatch(v.location) if v.location else None
            if m is None:
                continue
            bit = int(m.group(4)) if m.group(4) is not None else None
            where = Location(v.decl_name or name, inst, v.location, m.group(1), m.group(2) or "X",
                             int(m.group(3)), bit, v.type.name)
            decls.append(_LocatedDecl(f"v_{name}", v.type, where))
    return tuple(decls)


@functools.lru_cache(maxsize=COMPILED_KEPT)
def _compiled(sources: tuple[tuple[str, str], ...]) -> _Compiled:
    code, comp, instances = compile_to_python(list(sources))
    module = compile(code, "<thermost-st>", "exec")
    return _Compiled(code, module, instances, _located_decls(comp, instances))


def load_application(sources: list[tuple[str, str]]) -> Application:
    """A fresh application (its own instances, clock and located variables) of these sources. The same
    sources are compiled once per process (a forked process inherits what its parent compiled)."""
    comp = _compiled(tuple((name, text) for name, text in sources))
    ns = _namespace()
    clk = stdfbs.Clock()
    ns["CLK"] = clk
    try:
        exec(comp.module, ns)  # noqa: S102 - our own generated code
        G = ns["Globals"]()
        ns["G"] = G
        programs = {inst: ns[cls]() for inst, cls, _ in comp.instances}
    except rt.PlcRuntimeError as exc:
        raise StError([Diagnostic(sources[0][0], 1, 1, f"initialisation fault: {exc}")]) from None
    intervals = {inst: iv for inst, _, iv in comp.instances}
    located = [_located_var(d, programs.get(d.location.instance, G)) for d in comp.located]
    return Application(clk, programs, intervals, located, G, comp.code)


def _setter(obj, attr: str, t: Type):
    if t.kind == "int":
        wrap = rt.WRAP[(t.bits, t.signed)]
        return lambda v: setattr(obj, attr, wrap(int(v)))
    if t.kind == "real":
        if t is REAL:
            return lambda v: setattr(obj, attr, rt.f32(float(v)))
        return lambda v: setattr(obj, attr, float(v))
    if t.kind == "bool":
        return lambda v: setattr(obj, attr, bool(v))
    return lambda v: setattr(obj, attr, int(v))


def _located_var(d: _LocatedDecl, obj) -> LocatedVar:
    return LocatedVar(
        **vars(d.location),
        get=(lambda o=obj, a=d.attr: getattr(o, a)),
        set=_setter(obj, d.attr, d.type),
    )
