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
from plc.st.literals import int_literal
from plc.st.model import PY_PREFIX, SECTION_OF, CompileError, Pou, Var
from plc.st.parser import ParsedSource
from plc.st.types import ELEMENTARY, STRING, Type


class Index:
    def __init__(self, sources: list[ParsedSource]):
        self.sources = sources
        self.diags: list[Diagnostic] = []
        self.types: dict[str, Type] = {}
        self.type_nodes: dict[str, tuple[Node, ParsedSource]] = {}
        self.enum_members: dict[str, list[Type]] = {}
        self.pous: dict[str, Pou] = {}
        self.config: tuple[Node, ParsedSource] | None = None
        self.globals: dict[str, Var] = {}
        self._resolving: set[str] = set()

    def err(self, src: ParsedSource, node: Node, msg: str) -> CompileError:
        return CompileError(src.diag(node, msg))

    def build(self) -> None:
        """Globals first (array bounds may name a VAR_GLOBAL CONSTANT), then types and POUs."""
        self.collect_globals_first()
        self.collect()
        self.check_externals()

    def collect_globals_first(self) -> None:
        """Globals are needed for array bounds (VAR_GLOBAL CONSTANT) before the POUs are declared."""
        for src in self.sources:
            for node in src.tree.root_node.named_children:
                if node.type == "configuration_declaration":
                    self.config = (node, src)
        # type references in globals may need TYPEs: collect type nodes first
        for src in self.sources:
            for node in src.tree.root_node.named_children:
                if node.type == "type_declaration":
                    for td in node.named_children:
                        if td.type == "type_definition":
                            self.type_nodes[src.node_text(td.named_children[0]).upper()] = (td, src)
                elif node.type in ("function_block_declaration",):
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
                if t == "type_declaration":
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
                elif t == "configuration_declaration":
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

    def resolve_named(self, name: str) -> Type:
        name = name.upper()
        if name in self.types:
            return self.types[name]
        if name in ELEMENTARY:
            return ELEMENTARY[name]
        if name in self.pous and self.pous[name].kind == "function_block":
            t = Type(name, "fb", pou=self.pous[name])
            self.types[name] = t
            return t
        if name in stdfbs.STANDARD_FBS:
            t = Type(name, "fb", pou=name)
            self.types[name] = t
            return t
        if name not in self.type_nodes:
            raise KeyError(name)
        td, src = self.type_nodes[name]
        spec = td.named_children[1]
        if spec.type in ("elementary_type", "identifier", "subrange_type"):
            if name in self._resolving:
                raise self.err(src, td, f"type '{name}' is defined in terms of itself")
            self._resolving.add(name)
            try:
                base = self.type_from_spec(spec, src, name)
            finally:
                self._resolving.discard(name)
            self.types[name] = base  # an alias / subrange is its base type for MatIEC's type rules
            return base
        t = Type(name, "pending")
        self.types[name] = t
        built = self.type_from_spec(spec, src, name)
        t.__dict__.update({k: v for k, v in built.__dict__.items()})
        for cands in self.enum_members.values():
            for i, c in enumerate(cands):
                if c is built:
                    cands[i] = t
        t.name = name
        init = self._type_init(td, src)
        if init is not None:
            t.init = init
        return t

    def _type_init(self, node: Node, src: ParsedSource):
        """Initialiser of a type definition or struct field (a node, or a blanked text)."""
        for off, text in src.type_initializers.items():
            if node.start_byte <= off <= node.end_byte + 2:
                return (text, src)
        kids = node.children
        for i, k in enumerate(kids):
            if k.type == ":=" and i + 1 < len(kids):
                return kids[i + 1]
        return None

    def type_from_spec(self, spec: Node, src: ParsedSource, name: str = "") -> Type:
        k = spec.type
        if k == "elementary_type":
            tname = src.node_text(spec).upper()
            if tname not in ELEMENTARY:
                raise self.err(src, spec, f"data type {tname} is not supported by MatIEC / the soft-PLC")
            return ELEMENTARY[tname]
        if k == "reference_type":
            target = self.type_from_spec(spec.named_children[-1], src)
            return Type(f"REF_TO {target.name}", "ref", elem=target)
        if k == "subrange_type":
            return self.type_from_spec(spec.named_children[0], src)
        if k == "identifier":
            tn = src.node_text(spec).upper()
            try:
                return self.resolve_named(tn)
            except KeyError:
                raise self.err(src, spec, f"unknown data type '{src.node_text(spec)}'") from None
        if k == "enumerated_type_inline":
            members = [src.node_text(e).upper() for e in spec.named_children]
            t = Type(name or "ENUM", "enum", 32, True, members=members)
            for m in members:
                self.enum_members.setdefault(m, []).append(t)
            return t
        if k == "structure_type_inline":
            t = Type(name or "STRUCT", "struct")
            for f in spec.named_children:
                if f.type != "structure_field":
                    continue
                fname = src.node_text(f.named_children[0]).lower()
                t.fields[fname] = self.type_from_spec(f.named_children[1], src)
                init = self._type_init(f, src)
                if init is not None:
                    t.field_inits[fname] = (init, src) if isinstance(init, Node) else init
            return t
        if k == "array_type":
            dims = []
            elem = None
            for c in spec.named_children:
                if c.type == "subrange":
                    lo, hi = (self.const_int(x, src) for x in c.named_children)
                    dims.append((lo, hi))
                else:
                    elem = self.type_from_spec(c, src)
            if elem is not None and elem.kind == "fb":
                raise self.err(src, spec, "arrays of function block instances are not supported by MatIEC")
            return Type("ARRAY", "array", elem=elem, dims=dims)
        if k == "string_type" or src.node_text(spec).upper().startswith("STRING"):
            return STRING
        raise self.err(src, spec, f"unsupported type specification '{src.node_text(spec)}'")

    def const_int(self, node: Node, src: ParsedSource) -> int:
        if node.type == "integer_literal":
            return int_literal(src.node_text(node))
        if node.type == "identifier":
            name = src.node_text(node).lower()
            g = self.globals.get(name)
            if g is not None and g.constant and g.init is not None:
                return self.const_int(g.init, g.src)
        if node.type == "unary_expression" and src.node_text(node.children[0]) == "-":
            return -self.const_int(node.named_children[-1], src)
        raise self.err(src, node, f"array bound '{src.node_text(node)}' is not a constant value")

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
            location = None
            spec = None
            init: object = None
            state = "names"
            kids = decl.children
            for i, c in enumerate(kids):
                if state == "names":
                    if c.type == "identifier":
                        names.append(src.node_text(c))
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
            t = self.type_from_spec(spec, src)
            for written in names:
                n = written.lower()
                if n in into:
                    raise self.err(src, decl, f"duplicate variable '{written}'")
                into[n] = Var(n, t, section, init, location, constant, src, written)
                order.append(n)

    def declare_pou(self, pou: Pou) -> None:
        src = pou.src
        if pou.kind == "function":
            rt_node = pou.node.named_children[1]
            if rt_node.type in SECTION_OF or src.node_text(rt_node).upper() == "VOID":
                raise self.err(
                    src,
                    pou.node,
                    f"FUNCTION '{pou.name}' needs a return type (VOID functions "
                    "need iec2c -b, which OpenPLC does not pass)",
                )
            pou.ret = self.type_from_spec(rt_node, src)
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
