"""The papers' full reproductions, on demand: ``pytest -m slow tests/test_reproductions.py``.

Each runs a paper's whole sweep (its rows, run counts and epochs; minutes to tens of
minutes on 2 cores) through the engine as ``skinny experiment NAME --workers 2`` does and
checks that it is complete: every run finished (ok or diverged, none errored), every
row holds the paper's run count, the table and the claims were written. The numbers
themselves are on docs/papers/ beside the thesis's; these tests do not pin them.
"""

from __future__ import annotations

import pytest

from skinny_mj.engine import registry
from skinny_mj.engine.experiment import run_sweep

PAPERS = ("paper-a", "paper-b", "paper-c", "paper-d", "paper-e")


@pytest.mark.slow
@pytest.mark.parametrize("name", PAPERS)
def test_full_sweep_is_complete(name, tmp_path):
    module = registry.get(name)
    exp = module.build()
    results = run_sweep(exp, tmp_path, workers=2, progress=False)
    assert results["n_error"] == 0
    for row, spec in zip(results["rows"], exp.rows, strict=True):
        assert row["n"] == (spec.runs or exp.runs), row["row"]
    claims = (exp.report or module.report)(results, tmp_path)  # a Study's, or the module's
    assert (tmp_path / "table.md").is_file() and "- [" in claims
