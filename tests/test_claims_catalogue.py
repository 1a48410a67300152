"""The claims catalogue (experiments/claims_catalogue.py): every entry quotes the thesis
exactly at (or within 3 lines of) its cited line, ids are unique, its rules, run counts and
readings are declared in claims_rules, and the rows it reads exist in the named study's
plan (a missing row only with ``needs_row=True``)."""

from __future__ import annotations

import ast
import os
import re
from functools import cache
from pathlib import Path

import pytest
from skinny_mj.experiments import claims_catalogue as cat
from skinny_mj.experiments import claims_rules
from skinny_mj.experiments.claims_rules import READINGS, RULES, RUNS

from skinny_mj.engine import registry

THESIS = Path(os.environ.get("SKINNY_THESIS", cat.THESIS))
SLACK = 3  # lines either side of the cited one


def _norm(text: str) -> str:
    """Whitespace collapsed, a word hyphenated across a line break joined."""
    text = re.sub(r"(\w)-[ \t]*\n\s*(\w)", r"\1\2", text)
    return " ".join(text.split())


@cache
def _lines() -> list[str]:
    if not THESIS.is_file():
        pytest.skip(f"the thesis text is not at {THESIS} (set SKINNY_THESIS)")
    return THESIS.read_text(encoding="utf-8").splitlines()


@cache
def _study_rows(name: str) -> frozenset[str]:
    return frozenset(r.id for r in registry.get(name).build().rows)


def _rows_read(comp: cat.Comparison) -> list[str]:
    rows = [comp.a]
    if isinstance(comp.b, str):
        rows.append(comp.b)
    elif isinstance(comp.b, tuple) and all(isinstance(r, str) for r in comp.b):
        rows.extend(comp.b)
    return rows


@pytest.mark.parametrize("module", [cat, claims_rules], ids=lambda m: m.__name__)
def test_the_module_is_not_a_study(module):
    path = Path(module.__file__)
    tree = ast.parse(path.read_text(encoding="utf-8"))
    names = {t.id for s in tree.body if isinstance(s, ast.Assign)
             for t in s.targets if isinstance(t, ast.Name)}
    assert "NAME" not in names and "STUDY" not in names
    assert registry.declared_name(path) is None


def test_sixty_four_distinct_claims_with_a8_merged_into_a12():
    ids = [c.id for c in cat.CATALOGUE]
    assert len(ids) == len(set(ids)) == 64
    assert "A8" not in ids and cat.BY_ID["A12"].merged == ("A8",)
    assert {c.paper for c in cat.CATALOGUE} == set("ABCDES")


@pytest.mark.parametrize("check", cat.CATALOGUE, ids=lambda c: c.id)
def test_the_quote_is_at_its_line(check):
    lines = _lines()
    assert 1 <= check.line <= len(lines)
    window = "\n".join(lines[max(0, check.line - 1 - SLACK): check.line + SLACK])
    assert _norm(check.quote) in _norm(window), \
        f"{check.id}: quote not within {SLACK} lines of L{check.line}"


@pytest.mark.parametrize("check", cat.CATALOGUE, ids=lambda c: c.id)
def test_rules_runs_and_readings_are_declared(check):
    assert check.comparisons
    assert check.runs in RUNS
    for comp in check.comparisons:
        assert comp.rule in RULES, comp.rule
        kind = RULES[comp.rule].kind
        assert comp.relation in (("<", ">") if kind in ("better", "best", "threshold",
                                                        "extremes") else ("~",))
        if kind == "best":
            assert isinstance(comp.b, tuple) and len(comp.b) >= 1
        if kind == "threshold":
            assert isinstance(comp.b, int | float)
        assert comp.transform in ("", "abs")
    for column in check.columns:
        assert column and all(r in READINGS for r in column)
        assert all(check.paper in READINGS[r].papers for r in column), (check.id, column)
    counted = check.counted_column()
    assert all(READINGS[r].counted for r in counted)
    assert not any(READINGS[r].status == "fitted" for r in counted)


@pytest.mark.parametrize("check", cat.CATALOGUE, ids=lambda c: c.id)
def test_the_rows_exist_in_the_studys_plan(check):
    missing = [(comp.study or check.study, row) for comp in check.comparisons
               for row in _rows_read(comp)
               if row not in _study_rows(comp.study or check.study)]
    if missing:
        assert check.needs_row, f"{check.id}: rows not in the plan {missing}"
    else:
        assert not check.needs_row, f"{check.id}: needs_row set but every row exists"


def test_no_verdicts_or_result_numbers_in_the_catalogue():
    body = Path(cat.__file__).read_text(encoding="utf-8").split('"""', 2)[2]
    for word in (r"\bholds\b", r"does not hold", r"\bweak\b", r"not testable"):
        assert not re.search(word, body), word


def test_counted_columns_use_the_thesis_supported_readings():
    assert cat.BY_ID["E1"].counted_column() == ("recorded",)
    assert cat.BY_ID["D3"].counted_column() == ("recorded", "tt-clean")
    assert cat.BY_ID["A3"].counted_column() == ("recorded", "mean-abs-difference")
    assert cat.BY_ID["B8"].counted_column() == ("b-noise-free",)
    assert cat.BY_ID["E15"].counted_column() == ("default",)


def test_paper_bs_selection_row_is_read_by_no_claim():
    sel = claims_rules.B_SELECTION
    assert sel.row in _study_rows(sel.study)
    read = {row for check in cat.CATALOGUE if check.study == sel.study
            for comp in check.comparisons for row in _rows_read(comp)}
    assert read and sel.row not in read
