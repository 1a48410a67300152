"""A ``--quick`` sweep says, in its table, its claims and its output, that it is a smoke
test whose numbers and verdicts mean nothing; a full sweep says nothing of the kind."""

from __future__ import annotations

import types

import numpy as np
import pytest
from toy import toy

from skinny_mj.cli.parser import main
from skinny_mj.engine import registry
from skinny_mj.engine.experiment import Row
from skinny_mj.engine.plan import Experiment
from skinny_mj.engine.stats import SMOKE_NOTE


def _fake() -> Experiment:
    def run_one(row: Row, seed: int) -> dict:
        return {"value": float(np.random.default_rng(seed).normal())}

    def report(results, plan, out) -> str:
        return "- [does NOT hold] the fake claim"

    return toy("fake", (Row("a"),), run_one, runs=1, columns=("value",), report=report)


@pytest.mark.parametrize("quick", [True, False])
def test_a_quick_sweep_is_labelled_a_smoke_test_everywhere(quick, tmp_path, monkeypatch,
                                                           capsys):
    module = types.ModuleType("fake_study")
    module.build = lambda **options: _fake()  # type: ignore[attr-defined]
    monkeypatch.setattr(registry, "get", lambda name: module)
    out = tmp_path / "sweep"
    argv = ["experiment", "fake", "--workers", "1", "--quiet", "--out", str(out)]
    assert main(argv + (["--quick"] if quick else [])) == 0
    stdout = capsys.readouterr().out
    table, claims = (out / "table.md").read_text(), (out / "claims.md").read_text()
    assert "does NOT hold" in claims
    for text in (table, claims, stdout):
        assert (SMOKE_NOTE in text or "smoke test (--quick)" in text) == quick
