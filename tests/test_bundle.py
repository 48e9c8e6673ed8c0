"""`thermost bundle`: one file, dependency order, shims of other targets left out, deterministic."""

from __future__ import annotations

from pathlib import Path

import pytest

from plc.bundle import bundle_declarations, bundle_sources, bundle_text, split_declarations
from plc.cli import UserError, main

CONFIG = """CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    TASK task0(INTERVAL := T#10ms, PRIORITY := 0);
    PROGRAM inst0 WITH task0 : P_Main;
  END_RESOURCE
END_CONFIGURATION
"""

FILES = {
    # names chosen so that alphabetical order differs from dependency order
    "st_lib/types/ST_Alpha.st": "(* ST_Alpha: uses E_Zulu *)\nTYPE\n  ST_Alpha : STRUCT\n    eMode : E_Zulu;"
                                "\n    fX : REAL;\n  END_STRUCT;\nEND_TYPE\n",
    "st_lib/types/E_Zulu.st": "(* E_Zulu *)\nTYPE\n  E_Zulu : (eOff, eAuto);\nEND_TYPE\n",
    "st_lib/lib/FC_Aaa.st": "(* FC_Aaa calls FC_Bbb; the words FUNCTION_BLOCK FB_Fake in a comment"
                            " are ignored *)\n"
                            "FUNCTION FC_Aaa : REAL\n  VAR_INPUT fIn : REAL; END_VAR\n"
                            "  FC_Aaa := FC_Bbb(fIn := fIn) * 2.0;\nEND_FUNCTION\n",
    "st_lib/lib/FC_Bbb.st": "FUNCTION FC_Bbb : REAL\n  VAR_INPUT fIn : REAL; END_VAR\n"
                            "  FC_Bbb := fIn + 1.0;\nEND_FUNCTION\n",
    "st_lib/lib/FB_Aaa.st": "FUNCTION_BLOCK FB_Aaa\n  VAR inner : FB_Bbb; s : ST_Alpha; END_VAR\n"
                            "  inner(fIn := FC_Aaa(fIn := 1.0));\n  s.eMode := E_Zulu#eAuto;\n"
                            "END_FUNCTION_BLOCK\n",
    "st_lib/lib/FB_Bbb.st": "FUNCTION_BLOCK FB_Bbb\n  VAR_INPUT fIn : REAL; END_VAR\n"
                            "  VAR_OUTPUT fOut : REAL; END_VAR\n  fOut := fIn;\nEND_FUNCTION_BLOCK\n",
    "st_lib/shim/openplc/FC_Shim.st": "FUNCTION FC_Shim : REAL\n  VAR_INPUT t : TIME; END_VAR\n"
                                     "  FC_Shim := TIME_TO_REAL(t);\nEND_FUNCTION\n",
    "st_lib/shim/twincat/FC_Shim.st": "FUNCTION FC_Shim : REAL\n  VAR_INPUT t : TIME; END_VAR\n"
                                      "  FC_Shim := TIME_TO_REAL(t) / 1000.0;\nEND_FUNCTION\n",
    "plc/app/main.st": "PROGRAM P_Main\n  VAR fb : FB_Aaa; x AT %MD0 : REAL; END_VAR\n"
                       "  fb();\n  x := FC_Shim(t := T#1s);\nEND_PROGRAM\n\n" + CONFIG,
}


def make_tree(root: Path, files: dict[str, str]) -> None:
    for relative, text in files.items():
        path = root / relative
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)


def names(root: Path) -> list[str]:
    return [d.names[0] for d in bundle_declarations(root)]


def test_dependency_order_and_kind_groups(tmp_path):
    make_tree(tmp_path, FILES)
    assert names(tmp_path) == ["E_Zulu", "ST_Alpha", "FC_Bbb", "FC_Aaa", "FC_Shim", "FB_Bbb", "FB_Aaa",
                               "P_Main", "Config0"]


def test_only_the_matiec_shim_is_bundled(tmp_path):
    make_tree(tmp_path, FILES)
    sources = [p.relative_to(tmp_path).as_posix() for p in bundle_sources(tmp_path)]
    assert "st_lib/shim/openplc/FC_Shim.st" in sources
    assert not any("twincat" in s for s in sources)
    assert "/ 1000.0" not in bundle_text(tmp_path)


def test_comments_are_kept_with_their_declaration_and_output_is_deterministic(tmp_path):
    make_tree(tmp_path, FILES)
    text = bundle_text(tmp_path)
    assert text.startswith("(* ThermoST bundle for OpenPLC v3")
    assert "(* ST_Alpha: uses E_Zulu *)\nTYPE\n  ST_Alpha" in text
    assert text.index("(* E_Zulu *)") < text.index("(* ST_Alpha")
    assert text.rstrip().endswith("END_CONFIGURATION")
    assert bundle_text(tmp_path) == text
    other = tmp_path / "again"
    make_tree(other, dict(reversed(list(FILES.items()))))  # files created in another order
    assert bundle_text(other) == text


def test_bundle_compiles_with_the_soft_plc(tmp_path):
    make_tree(tmp_path, FILES)
    from plc.st.compiler import load_application

    app = load_application([("<bundle>", bundle_text(tmp_path))])
    app.scan()
    assert app.get("inst0.x") == 1.0


def test_cycles_and_duplicates_are_errors(tmp_path):
    make_tree(tmp_path, {
        "st_lib/FC_A.st": "FUNCTION FC_A : INT\n VAR_INPUT n : INT; END_VAR\n"
                          " FC_A := FC_B(n := n);\nEND_FUNCTION\n",
        "st_lib/FC_B.st": "FUNCTION FC_B : INT\n VAR_INPUT n : INT; END_VAR\n"
                          " FC_B := FC_A(n := n);\nEND_FUNCTION\n",
    })
    with pytest.raises(UserError, match="circular dependency between: FC_A, FC_B"):
        bundle_text(tmp_path)
    duplicate = "FUNCTION fc_a : INT\n VAR_INPUT n : INT; END_VAR\n fc_a := n;\nEND_FUNCTION\n"
    make_tree(tmp_path, {"st_lib/FC_B.st": duplicate})
    with pytest.raises(UserError, match="declared twice"):
        bundle_text(tmp_path)


def test_type_block_with_several_types_and_strings():
    source = ("TYPE\n  A : (a1, a2);\n  B : STRUCT m : A; n : ARRAY[0..2] OF INT; END_STRUCT;\n"
              "END_TYPE\nFUNCTION F : INT\n VAR_INPUT s : STRING; END_VAR\n"
              " F := LEN(s); (* 'PROGRAM' *)\nEND_FUNCTION\n")
    decls = split_declarations("x.st", source)
    assert [(d.kind, d.names) for d in decls] == [("TYPE", ["A", "B"]), ("FUNCTION", ["F"])]


def test_repository_bundle_and_cli(tmp_path, capsys):
    text = bundle_text()
    declared = [n.upper() for d in bundle_declarations() for n in d.names]
    assert len(declared) == len(set(declared)) > 0
    assert "twincat" not in text.lower().split("*)", 1)[0]  # header lists no other-target shim
    out = tmp_path / "out" / "thermost_openplc.st"
    assert main(["bundle", "-o", str(out)]) == 0
    assert out.read_text() == text
    from plc.st.compiler import typecheck

    assert [str(d) for d in typecheck([("<bundle>", text)])] == []


def test_speed_shortens_the_task_interval_only():
    import pytest

    from plc.bundle import bundle_text, with_speed
    from plc.cli import UserError

    text = bundle_text()
    fast = with_speed(text, 10)
    assert "INTERVAL := T#10ms" in fast and "INTERVAL := T#100ms" in text
    assert fast.replace("T#10ms", "T#100ms") == text
    with pytest.raises(UserError):
        with_speed(text, 3)  # 100 ms is not a multiple of 3
