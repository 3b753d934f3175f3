"""The docs site stands alone: every page under docs/ (records aside) is in the mkdocs nav, and every link of the
README to a file of the repository names a page of the site (a Markdown page in the nav, not a folder)."""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import yaml

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _pages(node: Any) -> Iterator[str]:
    if isinstance(node, list):
        for item in node:
            yield from _pages(item)
    elif isinstance(node, dict):
        for value in node.values():
            yield from _pages(value)
    else:
        yield node


def _nav() -> set[str]:
    config = yaml.load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"), Loader=yaml.BaseLoader)  # !!python tags
    return set(_pages(config["nav"]))


def test_every_page_is_in_the_nav() -> None:
    pages = {str(p.relative_to(DOCS)) for p in DOCS.rglob("*.md") if "records" not in p.relative_to(DOCS).parts}
    nav = _nav()
    assert sorted(pages - nav) == [] and sorted(nav - pages) == []


def test_the_readme_links_pages_of_the_site() -> None:
    nav = _nav()
    readme = (ROOT / "README.md").read_text("utf-8")
    links = [link.split("#")[0] for link in re.findall(r"(?<!!)\[[^\]]*\]\(([^)]+)\)", readme)]
    for image in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", readme):  # a figure: a file of the site's folder
        assert image.startswith("docs/") and (ROOT / image).is_file(), f"README shows {image!r}: not a file in docs/"
    local = [link for link in links if not re.match(r"[a-z]+:", link)]
    assert local, "the README links no page"
    for link in local:
        assert link.startswith("docs/") and link.endswith(".md"), f"README links {link!r}: not a page of the site"
        assert link.removeprefix("docs/") in nav, f"README links {link!r}, which the mkdocs nav does not hold"
