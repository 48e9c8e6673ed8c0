"""Initial values: defaults per type, declared initial values, struct and array initialisers,
and the Python classes of STRUCT types.
"""

from __future__ import annotations

from tree_sitter import Node

from plc.st.codegen.context import Generator
from plc.st.model import CompileError
from plc.st.parser import ParsedSource, parse_source
from plc.st.typerules import convert_store
from plc.st.types import Type


class InitGen(Generator):
    def __init__(self) -> None:
        self.struct_done: set[str] = set()
        self.struct_pending: list[tuple[str, Type]] = []

    def default_code(self, t: Type) -> str:
        k = t.kind
        if k in ("int", "enum"):
            return "0"
        if k == "real":
            return "0.0"
        if k == "bool":
            return "False"
        if k == "time":
            return "0"
        if k == "string":
            return "''"
        if k == "ref":
            return "None"
        if k == "struct":
            return f"{self.struct_class(t)}()"
        if k == "fb":
            if isinstance(t.pou, str):
                return f"{t.pou}(CLK)"
            return f"{t.pou.pyname}()"
        if k == "array":
            if t.init is not None:
                return self.init_code(t, t.init)
            elem = self.default_code(t.elem)
            if t.elem.kind in ("struct", "fb", "array"):
                return f"[{elem} for _ in range({t.size})]"
            return f"[{elem}] * {t.size}"
        raise ValueError(k)

    def init_code(self, t: Type, init) -> str:
        if init is None:
            return self.default_code(t)
        if isinstance(init, tuple) and len(init) == 2 and isinstance(init[0], str):
            node, src = self.snippet_initializer(init[0], init[1])
            return self.ctx.with_src(src, lambda: self.init_code(t, node))
        if isinstance(init, tuple) and len(init) == 2:  # (node, src)
            return self.ctx.with_src(init[1], lambda: self.init_code(t, init[0]))
        if isinstance(init, tuple) and init[0] == "array":
            _, decl, start = init
            items = []
            for c in decl.children[start + 1 :]:
                if c.type == "]":
                    break
                if c.is_named and c.type != "comment":
                    items.append(c)
            return self.array_init(t, items, decl)
        node: Node = init
        if node.type == "structure_initializer":
            return self.struct_init(t, node)
        if t.kind == "array":
            return self.array_init(t, [node], node)
        saved = (self.ctx.pou, self.ctx.mode)
        self.ctx.pou, self.ctx.mode = None, "config"
        try:
            e = self.exprs.expr(node, t)
            return convert_store(self.ctx, e, t, node, what="initial value")
        finally:
            self.ctx.pou, self.ctx.mode = saved

    def snippet_initializer(self, text: str, origin: ParsedSource) -> tuple[Node, ParsedSource]:
        snippet = f"PROGRAM SNIPPET\nVAR\n  x : INT := {text};\nEND_VAR\nx := 0;\nEND_PROGRAM\n"
        src = parse_source(snippet, origin.filename)
        decl = src.tree.root_node.named_children[0].named_children[1].named_children[0]
        kids = decl.children
        i = next(i for i, c in enumerate(kids) if c.type == ":=")
        nxt = kids[i + 1]
        if nxt.type == "[":
            return ("array", decl, i + 1), src
        return nxt, src

    def struct_init(self, t: Type, node: Node) -> str:
        parts = []
        for f in node.named_children:
            if f.type != "structure_initializer_field":
                continue
            fname = self.ctx.src.node_text(f.named_children[0]).lower()
            value = f.named_children[-1]
            if t.kind == "struct":
                if fname not in t.fields:
                    raise self.ctx.err(self.ctx.src, f, f"'{t.name}' has no field '{fname}'")
                ft = t.fields[fname]
            elif t.kind == "fb":
                members = self.index.fb_members(t)
                if fname not in members:
                    raise self.ctx.err(self.ctx.src, f, f"'{t.name}' has no variable '{fname}'")
                ft = members[fname][0]
            else:
                raise self.ctx.err(self.ctx.src, node, f"structure initialiser for a value of type {t.name}")
            parts.append(f"v_{fname}={self.init_code(ft, value)}")
        return f"mk({self.default_code(t)}, {', '.join(parts)})"

    def array_init(self, t: Type, items: list[Node], where: Node) -> str:
        if t.kind != "array":
            raise self.ctx.err(self.ctx.src, where, f"array initialiser for a value of type {t.name}")
        codes: list[str] = []
        for it in items:
            if it.type == "array_repetition":
                count = self.index.const_int(it.named_children[0], self.ctx.src)
                val = it.named_children[1] if len(it.named_children) > 1 else None
                code = self.init_code(t.elem, val) if val is not None else self.default_code(t.elem)
                codes.extend([code] * count)
            elif it.type == "structure_initializer":
                codes.append(self.struct_init(t.elem, it))
            else:
                codes.append(self.init_code(t.elem, it))
        if len(codes) > t.size:
            raise self.ctx.err(
                self.ctx.src, where, f"array initialiser has {len(codes)} values for {t.size} elements"
            )
        rest = t.size - len(codes)
        if rest:
            codes.extend([self.default_code(t.elem)] * rest)
        return f"[{', '.join(codes)}]"

    def struct_class(self, t: Type) -> str:
        name = f"S_{t.name}" if t.name not in ("STRUCT",) else f"S_anon{id(t)}"
        if name not in self.struct_done:
            self.struct_done.add(name)
            self.struct_pending.append((name, t))
        return name

    def gen_structs(self) -> list[str]:
        lines: list[str] = []
        while self.struct_pending:
            name, t = self.struct_pending.pop(0)
            slots = ", ".join(repr(f"v_{f}") for f in t.fields)
            lines.append(f"class {name}:")
            lines.append(f"    __slots__ = ({slots}{',' if len(t.fields) == 1 else ''})")
            lines.append("    def __init__(self):")
            for f, ft in t.fields.items():
                init = t.field_inits.get(f)
                try:
                    lines.append(f"        self.v_{f} = {self.init_code(ft, init)}")
                except CompileError as e:
                    self.ctx.diags.append(e.diag)
                    lines.append(f"        self.v_{f} = {self.default_code(ft)}")
            if not t.fields:
                lines.append("        pass")
            lines.append("    def _copy(self):")
            lines.append(f"        n = {name}.__new__({name})")
            for f, ft in t.fields.items():
                lines.append(f"        n.v_{f} = {self.copy_code(ft, f'self.v_{f}')}")
            lines.append("        return n")
            lines.append("")
        return lines

    @staticmethod
    def copy_code(t: Type, code: str) -> str:
        if t.kind in ("struct", "fb"):
            return f"{code}._copy()"
        if t.kind == "array":
            return f"copy_array({code})"
        return code
