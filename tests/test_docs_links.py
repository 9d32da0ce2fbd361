"""The reference pages stay reference: every relative link and picture in README.md and docs/*.md points at a
file of the repository, and no page speaks of work sessions (experiment history lives in git) or of paths in
the git-ignored runs/ folder, which a clone does not have."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SKIPPED_DIRS = {".git", "data", "runs", "build", "dist", ".venv", "node_modules", ".pytest_cache", ".ruff_cache"}

# [text](target) and ![alt](target), with an optional "title"; <img src="target">
LINK = re.compile(r"!?\[(?:[^\]\[]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
IMG_TAG = re.compile(r"<img\s[^>]*src=\"([^\"]+)\"", re.IGNORECASE)
SESSION = re.compile(r"\bsessions? [0-9]+", re.IGNORECASE)
RUNS_PATH = re.compile(r"(?<![\w$-])runs/")


def _reference_pages() -> list[Path]:
    return [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]


def _all_pages() -> list[Path]:
    """Every Markdown file of the tree outside ignored or generated folders."""
    pages = []
    for path in sorted(REPO.rglob("*.md")):
        parts = set(path.relative_to(REPO).parts[:-1])
        if parts & SKIPPED_DIRS or any(p.endswith(".egg-info") for p in parts):
            continue
        pages.append(path)
    return pages


def _without_code(text: str) -> str:
    """The page without its fenced code blocks and inline code, where link-like text is not a link."""
    text = re.sub(r"^```.*?^```", "", text, flags=re.MULTILINE | re.DOTALL)
    return re.sub(r"`[^`\n]*`", "", text)


def relative_targets(text: str) -> list[str]:
    """The relative link and picture targets of a Markdown text (no URLs, no in-page anchors)."""
    prose = _without_code(text)
    targets = LINK.findall(prose) + IMG_TAG.findall(prose)
    return [t for t in targets if not re.match(r"^([a-z][a-z0-9+.-]*:|#)", t, re.IGNORECASE)]


@pytest.mark.parametrize("page", _reference_pages(), ids=lambda p: str(p.relative_to(REPO)))
def test_every_relative_link_and_picture_resolves(page: Path):
    dead = []
    for target in relative_targets(page.read_text(encoding="utf-8")):
        path = (page.parent / target.split("#", 1)[0]).resolve()
        if not path.exists() or not path.is_relative_to(REPO):
            dead.append(target)
    assert not dead, f"{page.relative_to(REPO)} links to what a clone does not have: {dead}"


@pytest.mark.parametrize("page", _all_pages(), ids=lambda p: str(p.relative_to(REPO)))
def test_no_page_counts_sessions(page: Path):
    found = SESSION.findall(page.read_text(encoding="utf-8"))
    assert not found, f"{page.relative_to(REPO)} speaks of work sessions: {found}"


@pytest.mark.parametrize(
    "page",
    [*_reference_pages(), REPO / "ssn_engine" / "models" / "MODEL_CARD.md"],
    ids=lambda p: str(p.relative_to(REPO)),
)
def test_no_reference_page_names_a_run_folder_path(page: Path):
    lines = [line for line in page.read_text(encoding="utf-8").splitlines() if RUNS_PATH.search(line)]
    assert not lines, f"{page.relative_to(REPO)} names paths under the git-ignored runs/ folder: {lines[:5]}"


def test_the_checks_catch_what_they_are_for():
    text = 'See [a](missing.md), ![b](img/x.png "t"), [web](https://x.org), [top](#use) and `[c](code.md)`.'
    assert relative_targets(text) == ["missing.md", "img/x.png"]
    numbered = "measured in session " + "23"  # written apart, so that a grep of the tree finds no such line
    assert SESSION.search(numbered) and not SESSION.search("one gimp-console session")
    assert RUNS_PATH.search("python -m training.train --run runs/sr") and not RUNS_PATH.search('--run "$WORK/sr"')
