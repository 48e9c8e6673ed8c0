"""Every relative link and image in the docs and the README points at a file of the repository: a figure
that a command draws (the scorecard's, the HMI's screenshots) or a page that moved shows here."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
LINK = re.compile(r"\]\(([^)\s#]+)(?:#[^)\s]*)?\)")
EXTERNAL = ("http://", "https://", "mailto:")


def _targets(page: Path) -> list[str]:
    text = re.sub(r"```.*?```", "", page.read_text(encoding="utf-8"), flags=re.DOTALL)
    return [t for t in LINK.findall(text) if not t.startswith(EXTERNAL)]


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_relative_links_point_at_files(page: Path) -> None:
    missing = [t for t in _targets(page) if not (page.parent / t).exists()]
    assert not missing, f"{page.relative_to(ROOT)}: links to missing files: {missing}"


def test_the_drawn_figures_are_among_the_links() -> None:
    """The HMI's screenshots (drawn by the browser tests) and the scorecard's figures (by `thermost
    scorecard --markdown`) are linked from their pages, so the check above covers them."""
    for page in ("hmi.md", "scorecard.md"):
        assert any(t.endswith(".png") for t in _targets(ROOT / "docs" / page)), f"docs/{page} links no figure"
