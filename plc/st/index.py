"""Stage 2: the index of every declaration.

Every TYPE (aliases, subranges, enums, structs, arrays with their initialisers), every POU with
its variables (section, declared type, initial value, location, CONSTANT), the CONFIGURATION's
VAR_GLOBALs and the enum members by name. Array bounds and other constant values are evaluated
here (`const_int`). The generators and the application loader read this index; it holds no code.
"""

from __future__ import annotations

from tree_sitter import Node

from plc.st import stdfbs
from plc.st.diagnostics import Diagnostic
from plc.st.index_types import TypeIndex
from plc.st.model import PY_PREFIX, SECTION_OF, CompileError, Pou, Var
from plc.st.parser import ParsedSource
from plc.st.types import ELEMENTARY, UNKNOWN, Type, has_unknown


class Index(TypeIndex):
    """`lenient` (the checker's mode): a type name declared in no given file is an UNKNOWN type, and
    every POU that depends on one is left out of typing instead of being reported - a file checked
    alone may use the library's types, and nothing is guessed about them."""

    def __init__(self, sources: list[ParsedSource], lenient: bool = False):
        self.sources = sources
        self.lenient = lenient
        self.diags: list[Diagnostic] = []
        self.types: dict[str, Type] = {}
        self.type_nodes: dict[str, tuple[Node, ParsedSource]] = {}
        self.enum_members: dict[str, list[Type]] = {}
        self.pous: dict[str, Pou] = {}
        self.config: tuple[Node, ParsedSource] | None = None
        self.globals: dict[str, Var] = {}
        self._resolving: set[str] = set()

    def build(self) -> None:
        """Globals first (array bounds may name a VAR_GLOBAL CONSTANT), then types and POUs."""
        self.collect_globals_first()
        self.collect()
        self.check_externals()

    def collect_globals_first(self) -> None:
        """Globals are needed for array bounds (VAR_GLOBAL CONSTANT) before the POUs are declared."""
        for src in self.sources:
            for node in src.tree.root_node.named_children:
                if node.type == "configuration_declaration" and not (self.lenient and node.has_error):
                    self.config = (node, src)
        # type references in globals may need TYPEs: collect type nodes first
        for src in self.sources:
            for node in src.tree.root_node.named_children:
                if node.type == "type_declaration" and not (self.lenient and node.has_error):
                    for td in node.named_children:
                        if td.type == "type_definition":
                            self.type_nodes[src.node_text(td.named_children[0]).upper()] = (td, src)
                elif node.type == "function_block_declaration":
                    name = src.node_text(node.named_children[0]).upper()
                    self.pous.setdefault(name, Pou("function_block", name, node, src, pyname=f"FB_{name}"))
        try:
            self.collect_globals()
        except CompileError as e:
            self.diags.append(e.diag)

    def collect(self) -> None:
        for src in self.sources:
            for node in src.tree.root_node.named_children:
                t = node.type
                if t == "type_declaration" and not (self.lenient and node.has_error):
                    for td in node.named_children:
                        if td.type == "type_definition":
                            name = src.node_text(td.named_children[0]).upper()
                            self.type_nodes[name] = (td, src)
                elif t in ("function_declaration", "function_block_declaration", "program_declaration"):
                    kind = t.replace("_declaration", "")
                    name = src.node_text(node.child_by_field_name("name") or node.named_children[0]).upper()
                    if name in self.pous and self.pous[name].node == node:
                        continue  # declared by the globals pre-pass
                    if name in self.pous:
                        self.diags.append(src.diag(node, f"duplicate POU '{name}'"))
                        continue
                    self.pous[name] = Pou(kind, name, node, src, pyname=f"{PY_PREFIX[kind]}_{name}")
                elif t == "configuration_declaration" and not (self.lenient and node.has_error):
                    self.config = (node, src)
        for name in list(self.type_nodes):
            try:
                self.resolve_named(name)
            except CompileError as e:
                self.diags.append(e.diag)
        for pou in self.pous.values():
            try:
                self.declare_pou(pou)
            except CompileError as e:
                self.diags.append(e.diag)
                pou.failed = True
            except (IndexError, AttributeError, KeyError):
                if not (self.lenient and pou.node.has_error):
                    raise
                pou.failed = True  # what could be declared of a POU that did not parse stays
            if self.lenient and pou.node.has_error:
                pou.failed = True  # its statements are left to the syntax rules
        if self.lenient:
            self.leave_out_unknowns()

    def leave_out_unknowns(self) -> None:
        """Mark POUs that use an UNKNOWN type, or name a POU so marked, as not to be typed."""
        out = {name for name, pou in self.pous.items() if any(map(has_unknown, pou.types()))}
        names = {name: pou.src.identifiers_in(pou.node) for name, pou in self.pous.items()}
        while True:
            more = {name for name, used in names.items() if name not in out and out & used}
            if not more:
                break
            out |= more
        for name in out:
            self.pous[name].failed = True

    def collect_globals(self) -> None:
        if self.config is None:
            return
        node, src = self.config
        for block in node.named_children:
            if block.type == "resource_declaration":
                for b in block.named_children:
                    if b.type == "var_global":
                        self._globals_block(b, src)
            if block.type == "var_global":
                self._globals_block(block, src)

    def _globals_block(self, block: Node, src: ParsedSource) -> None:
        order: list[str] = []
        try:
            self.declare_vars(block, src, self.globals, order)
        except CompileError as e:
            self.diags.append(e.diag)

    def declare_vars(self, block: Node, src: ParsedSource, into: dict[str, Var], order: list[str]) -> None:
        section = SECTION_OF.get(block.type, "var")
        qualifiers = " ".join(
            self_text.upper()
            for self_text in (src.node_text(c) for c in block.children if c.type == "var_qualifier_list")
        )
        constant = "CONSTANT" in qualifiers.split() or any(c.type == "CONSTANT" for c in block.children)
        for decl in block.named_children:
            if decl.type != "variable_declaration":
                continue
            names: list[str] = []
            name_nodes: list[Node] = []
            location = None
            spec = None
            init: object = None
            state = "names"
            kids = decl.children
            for i, c in enumerate(kids):
                if state == "names":
                    if c.type == "identifier":
                        names.append(src.node_text(c))
                        name_nodes.append(c)
                    elif c.type == "AT":
                        state = "at"
                    elif c.type == ":":
                        state = "type"
                elif state == "at":
                    if c.type == "direct_address":
                        location = src.node_text(c).upper()
                    elif c.type == ":":
                        state = "type"
                elif state == "type":
                    if c.is_named and c.type != "comment":
                        spec = c
                        state = "after"
                elif state == "after" and c.type == ":=":
                    nxt = kids[i + 1] if i + 1 < len(kids) else None
                    init = ("array", decl, i + 1) if nxt is not None and nxt.type == "[" else nxt
                    break
            if spec is None:
                raise self.err(src, decl, "variable declaration without a type")
            t = self.declared_type(spec, src)
            for written, name_node in zip(names, name_nodes, strict=True):
                n = written.lower()
                if n in into:
                    if self.lenient:
                        continue  # the first declaration stands; the checker names the clash
                    raise self.err(src, decl, f"duplicate variable '{written}'")
                into[n] = Var(n, t, section, init, location, constant, src, written, name_node)
                order.append(n)

    def declare_pou(self, pou: Pou) -> None:
        src = pou.src
        if pou.kind == "function":
            rt_node = pou.node.named_children[1]
            if rt_node.type in SECTION_OF or src.node_text(rt_node).upper() == "VOID":
                if self.lenient:  # its variables are still declared, for the checker's rules
                    pou.ret = Type("VOID", UNKNOWN)
                    for block in pou.node.named_children:
                        if block.type in SECTION_OF:
                            self.declare_vars(block, src, pou.vars, pou.order)
                raise self.err(
                    src,
                    pou.node,
                    f"FUNCTION '{pou.name}' needs a return type (VOID functions "
                    "need iec2c -b, which OpenPLC does not pass)",
                )
            pou.ret = self.declared_type(rt_node, src)
        for block in pou.node.named_children:
            if block.type in SECTION_OF:
                self.declare_vars(block, src, pou.vars, pou.order)

    def check_externals(self) -> None:
        for pou in self.pous.values():
            for v in pou.vars.values():
                if v.section != "ext":
                    continue
                g = self.globals.get(v.name)
                if g is None:
                    self.diags.append(
                        v.src.diag(
                            pou.node,
                            f"VAR_EXTERNAL '{v.name}' of '{pou.name}' has no VAR_GLOBAL in the CONFIGURATION",
                        )
                    )
                elif g.constant and not v.constant:
                    self.diags.append(
                        v.src.diag(
                            pou.node,
                            f"VAR_EXTERNAL '{v.name}' must be declared CONSTANT: "
                            "it maps to a constant global variable",
                        )
                    )

    def fb_members(self, t: Type) -> dict[str, tuple[Type, str]]:
        if isinstance(t.pou, str):
            _, members = stdfbs.STANDARD_FBS[t.pou]
            return {k: (ELEMENTARY[v[0]], v[1]) for k, v in members.items()}
        pou: Pou = t.pou
        return {n: (v.type, v.section) for n, v in pou.vars.items()}
