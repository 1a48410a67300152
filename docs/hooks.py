"""MkDocs hooks (``mkdocs.yml`` ``hooks:``): pages made from files that live elsewhere.

- ``index.md`` is the top-level ``README.md``, its links rewritten for the site;
- ``model/skinny/README.md`` (+ its pictures) is the model card ``models/skinny/README.md``;
- ``<!-- results: HEADING -->`` in a page is replaced by that ``##`` section of
  ``docs/RESULTS.md`` (its headings one level down, its links made relative to the page).

So nothing is copied by hand: the site always shows the files the repository holds.
"""

from __future__ import annotations

import posixpath
import re
from pathlib import Path

from mkdocs.structure.files import File

ROOT = Path(__file__).resolve().parents[1]
MODEL_CARD = ROOT / "models" / "skinny"
_LINK = re.compile(r"(!?\[[^\]]*\]\()([^)\s#]+)(#[^)]*)?\)")
_RESULTS = re.compile(r"<!--\s*results:\s*(.+?)\s*-->")


def _readme_for_site(text: str) -> str:
    """README links point into the repository; on the site ``docs/`` is the root."""
    def fix(m: re.Match) -> str:
        target = m.group(2)
        if target.startswith("docs/"):
            target = target[len("docs/"):]
        elif target == "models/skinny/README.md":
            target = "model/skinny/README.md"
        return f"{m.group(1)}{target}{m.group(3) or ''})"
    return _LINK.sub(fix, text)


def on_files(files, config):
    files.append(File.generated(config, "index.md",
                                content=_readme_for_site((ROOT / "README.md").read_text())))
    files.append(File.generated(config, "model/skinny/README.md",
                                content=(MODEL_CARD / "README.md").read_text()))
    for png in sorted(MODEL_CARD.glob("*.png")):
        files.append(File.generated(config, f"model/skinny/{png.name}",
                                    abs_src_path=str(png)))
    return files


def results_section(heading: str, page_dir: str) -> str:
    """The ``## heading`` section of docs/RESULTS.md, for a page in ``page_dir``."""
    text = (ROOT / "docs" / "RESULTS.md").read_text()
    parts = re.split(r"(?m)^(?=## )", text)
    found = [p for p in parts if p.startswith(f"## {heading}")]
    if not found:
        raise ValueError(f"docs/RESULTS.md has no section '## {heading}'")
    section = re.sub(r"(?m)^(#+) ", lambda m: "#" + m.group(1) + " ", found[0])

    def rel(m: re.Match) -> str:
        target = m.group(2)
        if "://" in target or target.startswith("/"):
            return m.group(0)
        return f"{m.group(1)}{posixpath.relpath(target, page_dir or '.')}{m.group(3) or ''})"
    return _LINK.sub(rel, section)


def on_page_markdown(markdown, page, config, files):
    page_dir = posixpath.dirname(page.file.src_uri)
    return _RESULTS.sub(lambda m: results_section(m.group(1), page_dir), markdown)
