"""MkDocs hooks (``mkdocs.yml`` ``hooks:``): pages made from files that live elsewhere.

- ``index.md`` is the top-level ``README.md``, its links rewritten for the site;
- ``model/skinny/README.md`` (+ its pictures) is the model card ``models/skinny/README.md``.

So nothing is copied by hand: the site always shows the files the repository holds.
"""

from __future__ import annotations

import re
from pathlib import Path

from mkdocs.structure.files import File

ROOT = Path(__file__).resolve().parents[1]
MODEL_CARD = ROOT / "models" / "skinny"
_LINK = re.compile(r"(!?\[[^\]]*\]\()([^)\s#]+)(#[^)]*)?\)")


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
