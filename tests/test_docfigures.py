"""Docs derive their figures: every `<!-- figures:NAME -->` block of docs/*.md names a registered producer,
and every block whose figures do not depend on the machine is exactly what its producer returns today
(the seed 003 block re-runs the default scenario, stepped, about 5 s; the self-tuning study's table is
checked beside its tests, in tests/test_lib_tuning_study.py). Stale: run `make docs`."""

from __future__ import annotations

import pytest

from modbus_bridge import docfigures


def all_blocks() -> list[tuple[str, str, str]]:
    out = []
    for page in docfigures.pages():
        for name, body in docfigures.blocks(page.read_text(encoding="utf-8")):
            out.append((page.name, name, body))
    return out


def test_every_block_has_a_producer():
    found = all_blocks()
    assert found, "no figures blocks in docs/"
    for page, name, _ in found:
        assert name in docfigures.PRODUCERS, f"{page}: figures:{name} has no producer"


# checked beside the tests whose results they show, in the process that holds those results
CHECKED_BESIDE_THEIR_TESTS = {
    "tuning-study": "tests/test_lib_tuning_study.py",
    "fuzzy-oracle": "tests/test_fuzzy_inference.py",
    "heatup-oven-band": "tests/test_lib_heatup_oven_band.py",
}


CHECKED_HERE = [b for b in all_blocks() if b[1] not in docfigures.MEASURED | set(CHECKED_BESIDE_THEIR_TESTS)]


@pytest.mark.parametrize(("page", "name", "body"), CHECKED_HERE, ids=[f"{b[0]}:{b[1]}" for b in CHECKED_HERE])
def test_block_is_current(page, name, body):
    assert body == docfigures.PRODUCERS[name]().rstrip("\n") + "\n", (
        f"docs/{page}: figures:{name} disagrees with the code: run `make docs`"
    )


def test_measured_blocks_are_filled():
    for page, name, body in all_blocks():
        if name in docfigures.MEASURED:
            assert body.strip(), f"docs/{page}: figures:{name} was never generated: run `make docs`"


def test_render_replaces_only_the_block(monkeypatch):
    monkeypatch.setitem(docfigures.PRODUCERS, "demo", lambda: "- figure 42\n")
    page = "intro\n<!-- figures:demo -->\n- figure 41 (stale)\n<!-- /figures:demo -->\noutro\n"
    expected = "intro\n<!-- figures:demo -->\n- figure 42\n<!-- /figures:demo -->\noutro\n"
    assert docfigures.render(page) == expected
    with pytest.raises(KeyError, match="no producer"):
        docfigures.render("<!-- figures:nobody -->\n<!-- /figures:nobody -->\n")


@pytest.mark.parametrize("name", sorted(CHECKED_BESIDE_THEIR_TESTS))
def test_a_block_left_to_its_tests_is_checked_there(name):
    checker = docfigures.ROOT / CHECKED_BESIDE_THEIR_TESTS[name]
    assert f'docfigures.render(text, {{"{name}"}})' in checker.read_text(encoding="utf-8"), (
        f"figures:{name} is left to {checker.name}, which does not check it"
    )
