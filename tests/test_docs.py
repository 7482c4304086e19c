"""The documentation's own links: every relative link in README.md, docs/ and bench/README.md
names a file the repository holds, and every #anchor a heading of the page it points to (GitHub's
anchor rules)."""
from __future__ import annotations

import functools
import re
import shutil
import subprocess
import unicodedata
from pathlib import Path
from urllib.parse import unquote

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = sorted([ROOT / "README.md", *(ROOT / "docs").glob("*.md"), ROOT / "bench" / "README.md"])
# [text](target) or [text](target "title"); the text may hold one level of brackets ([`a[0]`](x.md))
TEXT = r"(?:[^\[\]]|\[[^\[\]]*\])*"
LINK = re.compile(r"\[" + TEXT + r"\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
FENCE = re.compile(r"^\s*(```|~~~)")
CODE_SPAN = re.compile(r"(`+)(?!`).*?(?<!`)\1(?!`)", re.S)


def _fenced_out(text: str) -> list[str]:
    """The page's lines outside its fenced code blocks."""
    out, fenced = [], False
    for line in text.splitlines():
        if FENCE.match(line):
            fenced = not fenced
        elif not fenced:
            out.append(line)
    return out


def _prose(text: str) -> str:
    """The page without its fenced code blocks and inline code spans (links there are code)."""
    return CODE_SPAN.sub("", "\n".join(_fenced_out(text)))


def slug(heading: str) -> str:
    """GitHub's anchor for a heading's text: the text as shown (links as their text, code and
    emphasis marks and HTML tags dropped), lower case, every character but letters, digits, marks,
    spaces, hyphens and underscores dropped, spaces as hyphens."""
    text = re.sub(r"\[(" + TEXT + r")\]\([^)]*\)", r"\1", heading)  # [text](url) -> text
    text = re.sub(r"<[^>]+>", "", text).replace("`", "").replace("*", "")
    kept = "".join(c for c in text.strip().lower() if c in " -_" or unicodedata.category(c)[0] in "LNM")
    return kept.replace(" ", "-")


@functools.lru_cache(maxsize=None)
def anchors(page: Path) -> frozenset[str]:
    """The anchors GitHub makes for the page's ATX headings (a repeated one numbered -1, -2, ...)."""
    seen: dict[str, int] = {}
    out = set()
    for line in _fenced_out(page.read_text(encoding="utf-8")):
        m = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if not m:
            continue
        s = slug(m.group(1))
        n = seen.get(s, 0)
        seen[s] = n + 1
        out.add(s if n == 0 else f"{s}-{n}")
    return frozenset(out)


def links(page: Path) -> list[str]:
    return [t for t in LINK.findall(_prose(page.read_text(encoding="utf-8")))
            if not re.match(r"^[a-z][a-z0-9+.-]*:", t)]  # http:, https:, mailto: ... are not checked


def _tracked() -> set[Path] | None:
    """The files git holds (a link to an ignored or untracked file would be broken in a clone),
    or None where this is no git checkout."""
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        return None
    r = subprocess.run(["git", "-C", str(ROOT), "ls-files", "-z"], capture_output=True, timeout=60)
    if r.returncode != 0:
        return None
    return {(ROOT / p).resolve() for p in r.stdout.decode().split("\0") if p}


TRACKED = _tracked()


def _held(dest: Path) -> bool:
    """``dest`` is a file, or a folder holding files, of the repository."""
    if not dest.is_relative_to(ROOT) or not dest.exists():
        return False
    if TRACKED is None:
        return True
    return dest in TRACKED or (dest.is_dir() and any(p.is_relative_to(dest) for p in TRACKED))


def test_pages_are_found():
    assert ROOT / "README.md" in PAGES and ROOT / "docs" / "performance.md" in PAGES


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_relative_links_resolve(page: Path):
    broken = []
    for target in links(page):
        path, _, anchor = unquote(target).partition("#")
        dest = (page.parent / path).resolve() if path else page
        if not _held(dest):
            broken.append(f"{target}: no file {path} in the repository")
        elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
            broken.append(f"{target}: no heading with anchor #{anchor} in {dest.relative_to(ROOT)}")
    assert not broken, f"{page.relative_to(ROOT)}: " + "; ".join(broken)


def test_the_rules_on_the_kinds_the_pages_use(tmp_path):
    p = tmp_path / "x.md"
    p.write_text("# A title\n## What remains, and the next steps\n### `paper`'s Phase 2 ≥ 100,000 µs × 2\n"
                 "## Notes\n## Notes\n## See [the skins](skins.md) *now*\n```\n# not a heading\n```\n",
                 encoding="utf-8")
    assert anchors(p) == {"a-title", "what-remains-and-the-next-steps", "papers-phase-2--100000-µs--2", "notes",
                          "notes-1", "see-the-skins-now"}
    p.write_text('[a](one.md) [b](two.md "title") [`c[0]`](three.md#x) `[d](code.md)` [e](https://x.org)\n'
                 "```\n[f](fenced.md)\n```\n", encoding="utf-8")
    assert links(p) == ["one.md", "two.md", "three.md#x"]
    if TRACKED is not None:  # what git does not hold is no target: a clone would lack it
        assert _held(ROOT / "README.md") and _held(ROOT / "docs") and not _held(ROOT / ".venv")
        assert not _held(ROOT.parent)
