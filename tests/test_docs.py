"""The documentation runs: every ```python block of README.md and docs/**/*.md executes
(blocks of one file in order, in one namespace, in a scratch folder), and the MkDocs site
builds with ``--strict`` when the ``docs`` extra is installed.

A block preceded by a ``<!-- no-run -->`` line is skipped: keep that for blocks that need
something this machine may lack (a display), and keep the list tiny.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
_BLOCK = re.compile(r"(?ms)^(?P<before>[^\n]*)\n```python\n(?P<code>.*?)^```\s*$")
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]


def python_blocks(text: str) -> list[tuple[int, str, bool]]:
    """(line number, code, skipped) of each ```python block in a Markdown text."""
    out = []
    for m in _BLOCK.finditer("\n" + text):
        line = text.count("\n", 0, max(m.start("code") - 1, 0)) + 1
        out.append((line, m.group("code"), m.group("before").strip() == "<!-- no-run -->"))
    return out


def test_block_finder_sees_blocks_and_the_skip_marker():
    text = "intro\n```python\nx = 1\n```\n<!-- no-run -->\n```python\nopen_window()\n```\n"
    blocks = python_blocks(text)
    assert [(code, skipped) for _, code, skipped in blocks] == [
        ("x = 1\n", False), ("open_window()\n", True)]


@pytest.mark.parametrize("path", [p for p in DOCS if python_blocks(p.read_text())],
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_python_blocks_run(path, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # anything a block writes lands in the scratch folder
    namespace: dict = {"__name__": "__docs__"}
    for line, code, skipped in python_blocks(path.read_text()):
        if skipped:
            continue
        try:
            exec(compile(code, f"{path.name}:{line}", "exec"), namespace)
        except Exception as err:  # name the block, keep the traceback
            raise AssertionError(f"{path.relative_to(ROOT)} block at line {line} failed: "
                                 f"{type(err).__name__}: {err}") from err


@pytest.mark.slow  # .ci/run builds the site itself (mkdocs build --strict)
@pytest.mark.skipif(shutil.which("mkdocs") is None, reason="needs the docs extra "
                    "(pip install -e '.[docs]')")
def test_site_builds_strict(tmp_path):
    result = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir",
                             str(tmp_path / "site")], cwd=ROOT, capture_output=True, text=True,
                            timeout=300, env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    assert result.returncode == 0, result.stderr[-3000:]
    site = tmp_path / "site"
    for page in ("index.html", "model/skinny/index.html", "task/index.html",
                 "papers/paper-e/index.html", "RESULTS/index.html"):
        assert (site / page).is_file(), page
    paper_e = (site / "papers/paper-e/index.html").read_text()
    assert "<table>" in paper_e  # the RESULTS.md section was pulled in
    assert (site / "model/skinny/skinny_2d.png").is_file()
