"""Text a user reads speaks to users: no tracker numbers or work-diary words in the README,
the docs, the model card, the CLI's help or the studies' descriptions; and every Markdown
list renders as a list (Python-Markdown, which MkDocs uses, reads a list that follows a
paragraph line with no blank line between as more of that paragraph, and a nested block
indented by less than four spaces as text)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from skinny_mj.cli.parser import build_parser
from skinny_mj.engine import registry

ROOT = Path(__file__).resolve().parents[1]
MARKDOWN = [ROOT / "README.md", ROOT / "models/skinny/README.md",
            *sorted((ROOT / "docs").rglob("*.md"))]
#: Words of a work diary or a tracker, not of a user's manual.
DIARY = re.compile(r"\bissues?\b|\bsessions?\b|\bengineers?\b|\bthe team\b|\bwe tried\b",
                   re.IGNORECASE)
_ITEM = re.compile(r"\s*(?:[-*+]|\d+[.)])\s+\S")
#: The Markdown extensions of mkdocs.yml that change how blocks are read.
_EXTENSIONS = ["admonition", "tables", "toc", "pymdownx.superfences", "pymdownx.highlight"]


def diary_words(text: str) -> list[str]:
    """Each line of ``text`` holding a diary word, with its line number."""
    return [f"{i}: {line.strip()[:120]}" for i, line in enumerate(text.splitlines(), 1)
            if DIARY.search(line)]


def glued_lists(text: str) -> list[str]:
    """List items that render as text of a paragraph or an item above them: ``text`` is
    rendered as the site renders it (Python-Markdown: a list needs a blank line after a
    paragraph, and nested blocks four spaces of indent) and every ``<p>`` or ``<li>``
    line that reads like a list item is one."""
    markdown = pytest.importorskip("markdown")
    html = markdown.markdown(text, extensions=_EXTENSIONS)
    return [line.strip()[:80] for m in re.finditer(r"<(p|li)>(.*?)</\1>", html, re.S)
            for line in m.group(2).split("\n")[1:] if _ITEM.match(line)]


def test_the_checks_find_what_they_should():
    assert diary_words("Fine.\nAs issue 13 asks,\nthis session ran\nfour engineers\n") == [
        "2: As issue 13 asks,", "3: this session ran", "4: four engineers"]
    assert glued_lists("Text:\n- a\n- b\n\nText:\n\n- c\n\n```\nx\n- d\n```\n\n- e\n  more\n"
                       "- f\n\n# H\n- g\n\n- h\n\n  para\n  - i\n") == ["- a", "- b", "- i"]


@pytest.mark.parametrize("path", MARKDOWN, ids=lambda p: str(p.relative_to(ROOT)))
def test_markdown_speaks_to_users(path):
    assert diary_words(path.read_text()) == [], path.relative_to(ROOT)


@pytest.mark.parametrize("path", MARKDOWN, ids=lambda p: str(p.relative_to(ROOT)))
def test_markdown_lists_have_a_blank_line_before_them(path):
    assert glued_lists(path.read_text()) == [], (
        f"{path.relative_to(ROOT)}: list items glued to the paragraph above")


_SHELL = re.compile(r"^    (?:#|\$ |skinny |python|MUJOCO_GL=|OMP_|pip |xvfb|git |rerun |mkdocs "
                    r"|pytest|nohup |/usr/bin/time)")


def indented_commands(text: str) -> list[int]:
    """Lines starting an indented (4-space) block of shell commands, outside fences: after
    a list such a block is read as more of the list's last item, so commands go in
    fenced blocks."""
    lines, fenced, out = text.split("\n"), False, []
    for i, line in enumerate(lines):
        if re.match(r"^\s*(```|~~~)", line):
            fenced = not fenced
        elif not fenced and _SHELL.match(line) and (i == 0 or not lines[i - 1].strip()):
            out.append(i + 1)
    return out


@pytest.mark.parametrize("path", MARKDOWN, ids=lambda p: str(p.relative_to(ROOT)))
def test_commands_are_in_fenced_blocks(path):
    assert indented_commands(path.read_text()) == [], path.relative_to(ROOT)


def test_indented_command_finder():
    assert indented_commands("- a\n\n    skinny demo\n\n```\n\n    skinny x\n```\n") == [3]


def _help_texts(parser) -> dict[str, str]:
    out = {parser.prog: parser.format_help()}
    for action in parser._actions:  # argparse keeps sub-parsers on their action only
        if isinstance(action.choices, dict):
            for sub in action.choices.values():
                out.update(_help_texts(sub))
    return out


def test_cli_help_speaks_to_users():
    found = {prog: diary_words(text) for prog, text in _help_texts(build_parser()).items()}
    assert len(found) > 10  # every command and sub-command was seen
    assert {prog: hits for prog, hits in found.items() if hits} == {}


@pytest.mark.parametrize("name", registry.names())
def test_study_descriptions_speak_to_users(name):
    assert diary_words(registry.doc(name)) == []


@pytest.mark.parametrize("path", sorted((ROOT / "docs/results").glob("*.md")),
                         ids=lambda p: p.name)
def test_results_pages_say_when_and_on_what_machine(path):
    head = " ".join(path.read_text().split("\n\n")[:3])  # the title and the first paragraphs
    assert re.search(r"\b20\d\d-\d\d-\d\d\b", head), f"{path.name}: no date near the top"
    assert re.search(r"\b2-core\b|\b2 cores\b", head), f"{path.name}: no machine near the top"


#: A tracker's number ("issue 14", "issues 20-24"): it means nothing to a reader of the code.
TRACKER = re.compile(r"\bissues? #?\d+", re.IGNORECASE)
SOURCES = sorted(p for part in ("skinny_mj", "controllers", "experiments", "tests",
                                "benchmarks") for p in (ROOT / part).rglob("*.py"))


def tracker_numbers(source: str) -> list[str]:
    """The docstrings of ``source`` (module, classes, functions) that cite a tracker number."""
    import ast

    nodes = [n for n in ast.walk(ast.parse(source)) if isinstance(
        n, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef)]
    return [doc.split("\n")[0][:80] for n in nodes
            if (doc := ast.get_docstring(n)) and TRACKER.search(doc)]


def test_the_tracker_check_finds_a_number():
    assert tracker_numbers('"""Issue 14: the torque body."""\ndef f():\n    """As issues 3'
                           ' and 4 ask."""\n') == ["Issue 14: the torque body.",
                                                  "As issues 3 and 4 ask."]
    assert tracker_numbers('"""An issue with the plant."""') == []


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: str(p.relative_to(ROOT)))
def test_docstrings_cite_no_tracker_numbers(path):
    assert tracker_numbers(path.read_text()) == []


# -- the README: lines that fit, commands that paste, an exit-code table that holds --------
README = ROOT / "README.md"
#: Longest prose line of the README (tables and code blocks aside), and of a table row.
PROSE_CHARS, TABLE_CHARS = 100, 200


def long_lines(text: str) -> list[str]:
    """Lines of ``text`` longer than :data:`PROSE_CHARS` outside fenced code and tables, or
    longer than :data:`TABLE_CHARS` in a table."""
    out, fenced = [], False
    for i, line in enumerate(text.splitlines(), 1):
        if line.lstrip().startswith(("```", "~~~")):
            fenced = not fenced
            continue
        limit = None if fenced else TABLE_CHARS if line.startswith("|") else PROSE_CHARS
        if limit is not None and len(line) > limit:
            out.append(f"{i}: {len(line)} characters: {line[:60]}")
    return out


def piped_commands(text: str) -> list[str]:
    """Shell code (lines of fenced bash/sh blocks, inline code spans) holding a ``|``:
    pasted, ``a | b`` alternatives run a pipeline (``skinny experiment paper-a | paper-b``
    starts paper A)."""
    shell, prose, fence = [], [], None
    for line in text.splitlines():
        if line.lstrip().startswith("```"):
            fence = line.strip()[3:] if fence is None else None
        elif fence is None:
            prose.append(line)
        elif fence in ("", "bash", "sh", "console"):
            shell.append(line)
    spans = re.findall(r"`([^`]+)`", "\n".join(prose))
    return [code.strip() for code in [*shell, *spans] if "|" in code]


def test_the_readme_checks_find_what_they_should():
    text = ("short\n" + "x" * 101 + "\n| " + "t" * 150 + " |\n```bash\n" + "c" * 120
            + "\nskinny experiment paper-a | paper-b\n```\nSee `--dof 4|8` and `skinny demo`.\n")
    assert [line.split(":")[0] for line in long_lines(text)] == ["2"]
    assert piped_commands(text) == ["skinny experiment paper-a | paper-b", "--dof 4|8"]


def test_readme_lines_fit():
    assert long_lines(README.read_text()) == []


def test_readme_commands_paste_without_a_pipe():
    assert piped_commands(README.read_text()) == []


def _readme_exit_codes() -> dict[int, str]:
    text = README.read_text()
    table = text[text.index("| code | meaning |"):].split("\n\n")[0]
    return {int(m[1]): m[2] for m in re.finditer(r"(?m)^\| (\d+) \| (.+) \|$", table)}


def _codes_main_returns() -> set[int]:
    """The exit codes ``skinny_mj.cli.parser.main`` returns as constants, and argparse's 2."""
    import ast
    import inspect

    from skinny_mj.cli import parser

    tree = ast.parse(inspect.getsource(parser.main))
    return {node.value.value for node in ast.walk(tree) if isinstance(node, ast.Return)
            and isinstance(node.value, ast.Constant)} | {2}


def test_readme_exit_code_table_is_the_clis(monkeypatch, capsys):
    from skinny_mj.cli import commands, parser
    from skinny_mj.errors import SkinnyEnvironmentError

    documented = _readme_exit_codes()
    assert set(documented) == _codes_main_returns() == {0, 1, 2, 130, 143}
    assert parser.main(["trajectory", "list"]) == 0
    assert parser.main(["trajectory", "show", "no-such-movement"]) == 2
    assert "bad input" in documented[2] and "interrupted" in documented[130]
    for raised, code in ((SkinnyEnvironmentError("the disk is full"), 1),
                         (KeyboardInterrupt(), 130), (parser.Terminated(), 143)):
        def fail(args, raised=raised):
            raise raised
        monkeypatch.setattr(commands, "cmd_trajectory", fail)
        assert parser.main(["trajectory", "list"]) == code, raised
    capsys.readouterr()
