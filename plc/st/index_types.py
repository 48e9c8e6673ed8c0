"""Stage 2, the index's types: named TYPEs, type specifications and constant array bounds.

`TypeIndex` builds a `Type` from a declaration's type node once and keeps it by name: aliases and
subranges are their base type (MatIEC's type rules), enums register their members, structs and
arrays carry their initialisers. `Index` (plc.st.index) adds the POUs, variables and globals.
"""

from __future__ import annotations

from tree_sitter import Node

from plc.st import stdfbs
from plc.st.literals import int_literal
from plc.st.model import CompileError, Pou, Var
from plc.st.parser import ParsedSource
from plc.st.types import ELEMENTARY, STRING, UNKNOWN, Type


class TypeIndex:
    """Named types and type specifications (the part of the index that builds `Type`s)."""

    lenient: bool
    types: dict[str, Type]
    type_nodes: dict[str, tuple[Node, ParsedSource]]
    enum_members: dict[str, list[Type]]
    pous: dict[str, Pou]
    globals: dict[str, Var]
    _resolving: set[str]

    def err(self, src: ParsedSource, node: Node, msg: str) -> CompileError:
        return CompileError(src.diag(node, msg))

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
                if self.lenient:
                    return Type(tn, UNKNOWN)
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

    def declared_type(self, spec: Node, src: ParsedSource) -> Type:
        """The type a declaration names; in the lenient index one it cannot build is UNKNOWN."""
        try:
            return self.type_from_spec(spec, src)
        except CompileError:
            if not self.lenient:
                raise
            return Type(src.node_text(spec).upper(), UNKNOWN)
