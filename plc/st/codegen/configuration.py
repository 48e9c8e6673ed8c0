"""CONFIGURATION: the Globals class (VAR_GLOBAL) and the program instances with their TASK
intervals.
"""

from __future__ import annotations

from tree_sitter import Node

from plc.st.codegen.context import Generator
from plc.st.model import CompileError


class ConfigGen(Generator):
    def gen_config(self) -> list[tuple[str, str, int]]:
        """Globals class + program instances: [(instance, class, interval_ns)]."""
        instances: list[tuple[str, str, int]] = []
        tasks: dict[str, int] = {}
        self.ctx.pou = None
        self.ctx.mode = "config"
        self.ctx.indent = 0
        if self.index.config is None:
            programs = [p for p in self.index.pous.values() if p.kind == "program"]
            self.ctx.emit("class Globals:")
            self.ctx.emit("    pass")
            if len(programs) == 1:
                instances.append(("inst0", programs[0].pyname, 10_000_000))
            return instances
        node, src = self.index.config
        self.ctx.src = src
        names = list(self.index.globals)
        self.ctx.emit("class Globals:")
        self.ctx.emit(f"    __slots__ = ({''.join(repr('v_' + n) + ', ' for n in names)})")
        self.ctx.emit("    def __init__(self):")
        self.ctx.indent = 2
        for n in names:
            v = self.index.globals[n]
            try:
                self.ctx.emit(f"self.v_{n} = {self.inits.init_code(v.type, v.init)}")
            except CompileError as e:
                self.ctx.diags.append(e.diag)
        self.ctx.emit("pass")
        self.ctx.indent = 0

        def walk(n: Node) -> None:
            for c in n.named_children:
                if c.type == "task_declaration":
                    tname = src.node_text(c.named_children[0]).lower()
                    interval = 0
                    for p in c.named_children[1:]:
                        if (
                            p.type == "task_parameter"
                            and src.node_text(p.named_children[0]).upper() == "INTERVAL"
                        ):
                            interval = self.exprs.expr(p.named_children[-1]).const or 0
                    tasks[tname] = interval
                elif c.type == "program_assignment":
                    ids = [src.node_text(x) for x in c.named_children if x.type == "identifier"]
                    inst = ids[0].lower()
                    ptype = ids[-1].upper()
                    task = ids[1].lower() if len(ids) == 3 else None
                    if ptype not in self.index.pous or self.index.pous[ptype].kind != "program":
                        self.ctx.diags.append(src.diag(c, f"unknown PROGRAM '{ids[-1]}'"))
                        continue
                    instances.append((inst, self.index.pous[ptype].pyname, tasks.get(task, 0) if task else 0))
                elif c.type == "resource_declaration":
                    walk(c)

        walk(node)
        return instances
