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
import types
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
    from skinny_mj.plant import body
    from skinny_mj.training import fits

    monkeypatch.chdir(tmp_path)  # anything a block writes lands in the scratch folder
    # a page may register a body or a learning rule: for this test only
    for module, name in ((body, "BODIES"), (fits, "FITS")):
        monkeypatch.setattr(module, name, dict(getattr(module, name)))
    page = types.ModuleType("__docs__")  # a module of its own: a page may define a dataclass
    monkeypatch.setitem(sys.modules, page.__name__, page)
    namespace: dict = page.__dict__
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
    assert "<table>" in paper_e  # the measured table
    assert (site / "model/skinny/skinny_2d.png").is_file()


# -- the docs match the code: commands parse, named files exist ---------------------------
_TOP = ("skinny_mj/", "experiments/", "controllers/", "tests/", "benchmarks/", "docs/",
        "models/", ".ci/")


def shell_commands(text: str) -> list[str]:
    """The ``skinny ...`` command lines of a Markdown text's code blocks (fenced or
    indented): continuation lines joined, comments and ``[optional]`` brackets dropped,
    ``a | b`` alternatives cut to the first."""
    fenced = r"(?ms)^```(?:bash|sh|console)?\n(.*?)^```"
    blocks = re.findall(fenced, text)
    blocks += re.findall(r"(?m)((?:^    \S.*\n)+)", re.sub(r"(?ms)^```.*?^```", "", text))
    out = []
    for block in blocks:
        for line in block.replace("\\\n", "").splitlines():  # as the shell joins them
            line = re.sub(r"^\s*(?:[A-Z_]+=\S+\s+)*(?:nice -n \d+\s+)?", "", line)
            line = re.split(r"\s+#|\s+\|\s+", line)[0].strip()
            if line.startswith("skinny "):
                out.append(re.sub(r"\[([^\]]*)\]", r"\1", line))
    return out


def test_command_finder_reads_blocks_as_a_shell_would():
    text = ("```bash\nskinny demo --seed 1   # note\nMUJOCO_GL=egl skinny render \\\n"
            "    --out x.png\nskinny bench [--quick]\nskinny experiment paper-a | paper-b\n"
            "```\n\n    skinny view run.rrd\n")
    assert shell_commands(text) == ["skinny demo --seed 1", "skinny render     --out x.png",
                                    "skinny bench --quick", "skinny experiment paper-a",
                                    "skinny view run.rrd"]


@pytest.mark.parametrize("path", DOCS, ids=lambda p: str(p.relative_to(ROOT)))
def test_documented_commands_parse_and_name_real_studies(path, capsys):
    import shlex

    from skinny_mj.cli.parser import build_parser
    from skinny_mj.engine import registry

    for cmd in shell_commands(path.read_text()):
        try:
            args = build_parser().parse_args(shlex.split(cmd)[1:])
        except SystemExit:
            pytest.fail(f"{path.relative_to(ROOT)}: `{cmd}`: {capsys.readouterr().err}")
        if args.command == "experiment":
            assert args.name in [*registry.names(), "list"], (path.name, cmd)


@pytest.mark.parametrize("path", DOCS, ids=lambda p: str(p.relative_to(ROOT)))
def test_documented_repository_paths_exist(path):
    tops = "|".join(map(re.escape, _TOP))
    named = re.findall(rf"`((?:{tops})[\w./-]+)`", path.read_text())
    missing = [p for p in named if not (ROOT / p.rstrip("/")).exists()
               and not (ROOT / f"{p.rsplit('.', 1)[0]}.py").exists()]  # module.attribute
    assert missing == [], f"{path.relative_to(ROOT)} names files that do not exist"


def test_every_built_in_movement_is_named_in_the_docs():
    from skinny_mj.trajectories import library

    listed = (ROOT / "docs/adding-a-movement.md").read_text()
    missing = [n for n in library.names()
               if f"`{n}`" not in listed and not (n.startswith("bimanual-")
                                                  and "`bimanual-*`" in listed)]
    assert missing == []


def test_every_extra_is_named_in_getting_started():
    import tomllib

    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"]
    text = (ROOT / "docs/getting-started.md").read_text()
    assert [e for e in extras if f"`.[{e}]`" not in text] == []


def test_diagrams_are_committed_svg_with_no_network_reference():
    """The site loads nothing from the network: no mermaid fence (Material would fetch
    mermaid.js from a CDN); each diagram's source ``docs/diagrams/NAME.mmd`` has its
    rendered ``NAME.svg`` beside it, and every page that shows one links the SVG."""
    fences = [p.name for p in DOCS if "```mermaid" in p.read_text()]
    assert fences == []
    sources = sorted((ROOT / "docs/diagrams").glob("*.mmd"))
    assert sources
    shown = "".join(p.read_text() for p in DOCS)
    for src in sources:
        svg = src.with_suffix(".svg")
        text = svg.read_text()
        assert text.lstrip().startswith("<svg") and "</svg>" in text, svg.name
        links = set(re.findall(r"(?:href|src)=\"(https?://[^\"]+)", text))
        links |= set(re.findall(r"url\((https?://[^)]+)\)|@import", text))
        assert links == set(), (svg.name, links)
        assert f"diagrams/{svg.name}" in shown, svg.name
