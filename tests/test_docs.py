"""The documentation: README.md for users (at most 15,000 bytes), everything else in docs/, built by MkDocs.

* every relative link of README.md and docs/**/*.md points to an existing file, and a link with an anchor into a
  page of docs/ to one of that page's headings (no MkDocs needed);
* every page of docs/ is in mkdocs.yml's nav;
* where MkDocs (Material) is installed (``pip install '.[docs]'``), ``mkdocs build --strict`` passes without a
  warning (CI installs it and builds the site after the tests).
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import unicodedata
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]
DOCS = ROOT / "docs"
PAGES = [ROOT / "README.md"] + sorted(DOCS.rglob("*.md"))
README_LIMIT_BYTES = 15_000

_FENCE = re.compile(r"^[ \t]*```.*?^[ \t]*```[ \t]*$", re.S | re.M)
_CODE = re.compile(r"`[^`\n]*`")
_LINK = re.compile(r"!?\[[^\]\n]*\]\(\s*([^)\s]+)\s*\)")
_HEADING = re.compile(r"^#{1,6}[ \t]+(.+?)[ \t]*#*[ \t]*$", re.M)


def _prose(text: str) -> str:
    """The page without its code: fenced blocks and inline code hold no links."""
    return _CODE.sub("", _FENCE.sub("", text))


def _slug(heading: str) -> str:
    """The anchor MkDocs' toc extension gives a heading (its default slugify, markup removed)."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading)          # a link's text only
    text = unicodedata.normalize("NFKD", text).encode("ascii", "ignore").decode("ascii")
    text = re.sub(r"[^\w\s-]", "", text).strip().lower()
    return re.sub(r"[-\s]+", "-", text)


def _anchors(page: Path) -> set[str]:
    return {_slug(h) for h in _HEADING.findall(_FENCE.sub("", page.read_text(encoding="utf-8")))}


def _links(page: Path) -> list[str]:
    return _LINK.findall(_prose(page.read_text(encoding="utf-8")))


def test_readme_is_at_most_15000_bytes():
    size = len((ROOT / "README.md").read_bytes())
    assert size <= README_LIMIT_BYTES, f"README.md has {size} bytes; move details to docs/"


def test_every_relative_link_points_to_an_existing_file_and_heading():
    broken, checked = [], 0
    for page in PAGES:
        for target in _links(page):
            if re.match(r"[a-z][a-z0-9+.-]*:", target):          # http:, https:, mailto:, file:
                continue
            path, _, anchor = target.partition("#")
            dest = (page.parent / path).resolve() if path else page
            checked += 1
            if not dest.is_file():
                broken.append((page.relative_to(ROOT).as_posix(), target, "no such file"))
            elif anchor and dest.suffix == ".md" and DOCS in dest.parents and anchor not in _anchors(dest):
                broken.append((page.relative_to(ROOT).as_posix(), target, "no such heading"))
    assert broken == []
    assert checked >= 50


def test_the_readme_links_every_page_and_the_nav_lists_every_page():
    readme = {(ROOT / t.partition("#")[0]).resolve() for t in _links(ROOT / "README.md")}
    pages = [p for p in DOCS.rglob("*.md") if p.name != "index.md"]
    assert [p.relative_to(ROOT).as_posix() for p in pages if p.resolve() not in readme] == []
    nav = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    assert [p for p in DOCS.rglob("*.md") if not re.search(rf":\s*{re.escape(p.relative_to(DOCS).as_posix())}\s*$",
                                                           nav, re.M)] == []


def test_the_docs_extra_pins_mkdocs_material_to_a_major_version():
    import tomllib
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    assert "mkdocs-material>=9,<10" in extras["docs"]


def test_mkdocs_build_strict_has_no_warning(tmp_path):
    try:
        import material  # noqa: F401
        import mkdocs  # noqa: F401
    except ImportError as exc:
        pytest.skip(f"MkDocs Material is not installed ({exc}); pip install '.[docs]'")
    proc = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(ROOT / "mkdocs.yml"),
                           "-d", str(tmp_path / "site")], cwd=ROOT, capture_output=True, text=True, timeout=300,
                          env=dict(os.environ, NO_MKDOCS_2_WARNING="1"))
    assert proc.returncode == 0, proc.stderr[-4000:]
    assert "WARNING" not in proc.stderr, proc.stderr[-4000:]
    assert (tmp_path / "site" / "index.html").is_file()
    assert (tmp_path / "site" / "guide" / "diagnose" / "index.html").is_file()
