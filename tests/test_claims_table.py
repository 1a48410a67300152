"""The claims table's count (skinny_mj.experiments.claims.tally) and the page that states it."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from skinny_mj.experiments.claims import tally, tally_lines

PAGE = Path(__file__).resolve().parents[1] / "docs" / "results" / "claims.md"

TWO = """| # | claim | ours | verdict (default; thesis reading) |
|---|---|---|---|
| E1 | a \\| b | 1 | holds; holds |
| E2 | c | 2 | does not hold; weak |
| E3 | d | 3 | weak; not run |

Extensions (not a claim row):

| # | claim | verdict |
|---|---|---|
| A1 | e | does not hold |
| x | not a claim id | holds |
"""


def test_tally_counts_each_reading_and_a_single_verdict_under_both():
    counts = tally(TWO)
    assert dict(counts["default"]) == {"holds": 1, "does not hold": 2, "weak": 1}
    assert dict(counts["thesis reading"]) == {"holds": 1, "weak": 1, "not run": 1,
                                              "does not hold": 1}
    assert tally_lines(counts)[1] == ("thesis reading: 2 of 4 hold (1 of them weak), 1 do not "
                                      "hold, 1 not run")


@pytest.mark.parametrize("row, message", [("| E1 | a | 1 | holds; maybe |", "unknown verdict"),
                                          ("| E1 | a | 1 | holds |", "1 verdicts for 2")])
def test_tally_refuses_a_verdict_it_cannot_count(row, message):
    table = TWO.splitlines()[:2] + [row]
    with pytest.raises(ValueError, match=message):
        tally("\n".join(table))


def test_the_page_states_the_tables_own_count():
    text = PAGE.read_text(encoding="utf-8")
    stated = dict(re.findall(r"^- \*\*([a-z ]+)\*\*: (.+)$", text, flags=re.M))
    counted = dict(line.split(": ", 1) for line in tally_lines(tally(text)))
    assert stated == counted
