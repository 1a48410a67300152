"""fidelity-a: one long training's checkpoints equal short trainings; the chained forward
model's input; the report on a tiny sweep."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from skinny_mj.experiments import paper_a
from skinny_mj.experiments.fidelity_a import study as fidelity_a

from skinny_mj.engine.study import Row
from skinny_mj.errors import SkinnyInputError
from skinny_mj.training.config import TrainConfig

#: Small networks on the short movement Y (the rows' runs in a fraction of a second).
TINY = {"esn.n_reservoir": 30, "forward.reservoir": 20, "method.cycles": 1,
        "movement.trajectory": "y"}
SEEDS = [11, 12]


def _run(arch: str, delay: int, epochs: int, seeds: list[int],
         forward_input: str = "sensed") -> list:
    """fidelity-a's run of the row, on :data:`TINY`, with checkpoints 1 and 2."""
    row = fidelity_a.plan_row(arch, forward_input, delay, epochs)
    config = paper_a.MODEL.override({**row.overrides, **TINY})
    return fidelity_a.STUDY.run(config, Row(row.id, params={"checkpoints": (1, 2)}), seeds)


def _numbers(out: dict, suffix: str) -> dict:
    return {k: v for k, v in out.items() if k.endswith(suffix)}


@pytest.mark.parametrize("arch,forward_input", [("hybrid", "sensed"), ("serial", "chained")])
def test_a_short_run_equals_the_long_runs_checkpoint(arch, forward_input):
    """A 1-epoch run = the 2-epoch run's epoch-1 record, bit for bit; the 2-epoch record is
    paper A's own last-epoch metrics of a 2-epoch run, and the K = 0 tests at the
    checkpoints leave the training curve as it is without them."""
    short = _run(arch, 3, 1, SEEDS, forward_input)
    long = _run(arch, 3, 2, SEEDS, forward_input)
    for s, g in zip(short, long, strict=True):
        first = _numbers(s, "_e1")
        assert len(first) >= 10 and first == _numbers(g, "_e1")  # NaN-free, bit for bit
        assert s["curve_train_nrmse"] == g["curve_train_nrmse"][:1]
        assert set(_numbers(g, "_e2")) == {k.replace("_e1", "_e2") for k in first}
    if forward_input == "chained":
        return
    pa_row = paper_a.STUDY.row(f"{arch}-d3")
    theirs = paper_a.STUDY.run(paper_a.STUDY.config(pa_row.id).override(
        {**TINY, "method.epochs": 2}), pa_row, SEEDS)
    for o, t in zip(long, theirs, strict=True):
        assert o["curve_train_nrmse"] == t["curve_performance_nrmse"]
        assert o["train_nrmse_e2"] == t["performance_nrmse"]
        assert o["train_mad_e2"] == t["performance_mae"]
        assert o["train_share_e2"] == t["feedback_share"]
        assert o["train_pred_nrmse_e2"] == t["prediction_nrmse"]
        assert o["pretrain_prediction_nrmse"] == t["pretrain_prediction_nrmse"]


def test_chained_forward_model_is_fed_its_own_prediction():
    from skinny_mj.training.loop import build_run, train_run

    cfg = paper_a.MODEL.override({**TINY, "method.epochs": 1, "plant.delay": 3,
                                  "forward": "parallel"})
    for forward_input in ("sensed", "chained"):
        run = build_run(cfg.override({"forward.input": forward_input}), SEEDS[:1])
        ro = train_run(run).fel.last_rollout
        n_res, n_sig = run.forward.esn.cfg.n_reservoir, run.desired.shape[1]
        fed = ro.fm_states[:, :, n_res:n_res + n_sig]  # the position part of its input
        t = np.arange(fed.shape[1])
        expected = ro.predictions[:, t] if forward_input == "chained" \
            else ro.sensed[:, np.maximum(t - 3, 0)]
        np.testing.assert_array_equal(fed, expected)


def test_chained_without_delay_is_the_sensed_forward_model():
    a = _run("hybrid", 0, 1, SEEDS[:1], "chained")
    b = _run("hybrid", 0, 1, SEEDS[:1], "sensed")
    assert a == b
    with pytest.raises(SkinnyInputError, match="forward.input"):
        TrainConfig().override({"forward.input": "chained"})  # no forward model to chain


@pytest.mark.slow  # ~6 s CPU: the report on a tiny sweep
def test_quick_sweep_writes_tables_and_figures(tmp_path):
    from skinny_mj.engine.experiment import run_sweep

    study = replace(fidelity_a.STUDY, base=paper_a.MODEL.override(
        {**TINY, "esn.n_reservoir": 10, "forward.reservoir": 10}), runs=2,
        rows=tuple(fidelity_a.plan_row(a, "sensed", 2, 1) for a in paper_a.ARCHITECTURES),
        params={"checkpoints": (1,)}, columns=("train_nrmse_e1",))
    exp = study.build()
    results = run_sweep(exp, tmp_path, workers=1, progress=False)
    text = exp.report(results, tmp_path)
    assert "highest prediction error" in text and "parallel ≈ hybrid" in text
    assert "| serial-d2 | 1 | 2 |" in (tmp_path / "tables.md").read_text()
    assert (tmp_path / "fig5_band.png").stat().st_size > 1000
