"""Paper A (delays + forward models): the run glue, the claims, and a --quick sweep."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from controllers.esn import ESN, ESNConfig
from controllers.fel import Rollout
from controllers.forward_model import ForwardModel
from controllers.metrics import nrmse
from experiments import get, paper_a
from skinny_mj.delays import DelayConfig, feedback_share, pretrain_forward, run_delay
from skinny_mj.experiment import Experiment, run_sweep

TINY = replace(paper_a.quick_config().model, epochs=1, learning_cycles=1)


def _movement(n: int = 120) -> tuple[np.ndarray, np.ndarray]:
    t = np.linspace(0, 2 * np.pi, n)
    desired = 0.6 * np.stack([np.sin(t + k) for k in range(4)], axis=1)
    commands = np.clip(np.diff(desired, axis=0) * 10, -1, 1)
    return desired, commands


def test_pretrained_forward_model_beats_the_delayed_no_change_guess():
    desired, commands = _movement()
    fm = ForwardModel(ESN(ESNConfig(8, 4, n_reservoir=60, spectral_radius=0.1,
                                    noise_level=0.2), seed=3), "serial")
    rng = np.random.default_rng(0)
    for delay in (0, 3):
        err = pretrain_forward(fm, desired, commands, delay, 0.01, rng)
        stale = nrmse(desired[np.maximum(np.arange(len(commands)) - delay, 0)], desired[1:])
        assert err.shape == (1,)
        assert err[0] < 0.5 * stale


def test_feedback_share_is_a_fraction_and_correction_ratio_can_exceed_one():
    y_esn = np.full((1, 5, 4), 0.5)
    commands = np.full((1, 5, 4), 0.1)  # feedback -0.4 fights the ESN's 0.5
    ro = Rollout(commands, y_esn, np.zeros((1, 6, 4)), *(np.zeros((1, 6, 4)),) * 3,
                 states=np.zeros((1, 5, 3)))
    assert ro.correction_ratio[0] == pytest.approx(4.0)
    assert feedback_share(ro)[0] == pytest.approx(0.4 / 0.9)


def test_run_is_reproducible_and_reports_the_metrics():
    a = run_delay(TINY, "serial", 2, seed=5)
    b = run_delay(TINY, "serial", 2, seed=5)
    for key in ("performance_nrmse", "feedback_share", "prediction_nrmse",
                "pretrain_prediction_nrmse", "test_position_nrmse"):
        assert a[key] == b[key], key
        assert np.isfinite(a[key])
    assert 0 <= a["feedback_share"] <= 1
    assert "prediction_nrmse" not in run_delay(TINY, "inverse", 0, seed=5)


def test_delay_hurts_the_inverse_only_architecture():
    cfg = paper_a.quick_config().model
    d0 = run_delay(cfg, "inverse", 0, seed=1)["performance_nrmse"]
    d4 = run_delay(cfg, "inverse", 4, seed=1)["performance_nrmse"]
    assert d4 > 2 * d0


def test_bad_architecture():
    with pytest.raises(ValueError, match="architecture"):
        run_delay(TINY, "sideways", 0, seed=0)


def _fake(metrics_by_row: dict[str, list[dict]]):
    def run_one(row, seed):
        return metrics_by_row[row.row_id][seed % len(metrics_by_row[row.row_id])]
    return run_one


def test_claims_hold_and_fail_on_synthetic_runs(tmp_path):
    good = {"inverse": (0.15, 0.5), "parallel": (0.08, 0.3), "hybrid": (0.07, 0.3),
            "serial": (0.04, 0.2)}
    metrics = {}
    for row in paper_a.rows((0, 4)):
        arch, d = row.params["architecture"], row.params["delay"]
        err, share = good[arch] if d else (0.01, 0.3)
        metrics[row.row_id] = [{"performance_nrmse": err + k * 0.001, "feedback_share": share,
                                "pretrain_prediction_nrmse": 0.08} for k in range(3)]
    exp = Experiment("fake-a", paper_a.rows((0, 4)), _fake(metrics), runs=3)
    run_sweep(exp, tmp_path / "good", workers=1, progress=False)
    lines = paper_a.claims(tmp_path / "good")
    assert len(lines) == 8
    assert sum("[holds]" in line for line in lines) == 7  # delay 10 was not run
    assert "[n/a]" in lines[-1]

    metrics["serial-d4"] = [{"performance_nrmse": 0.3, "feedback_share": 0.9,
                             "pretrain_prediction_nrmse": 0.01}]
    run_sweep(exp, tmp_path / "bad", workers=1, progress=False)
    bad = paper_a.claims(tmp_path / "bad")
    assert sum("does NOT hold" in line for line in bad) == 4  # lower x2, serial best, worst<best


def test_quick_sweep_end_to_end(tmp_path):
    module = get("paper-a")
    exp = module.build(quick=True, only=("inverse-d0", "serial-d4"))
    assert [r.row_id for r in exp.rows] == ["inverse-d0", "serial-d4"]
    results = run_sweep(exp, tmp_path, workers=1, progress=False)
    assert all(r["n_ok"] == 2 and r["n_failed"] == 0 for r in results["rows"])
    text = module.report(results, tmp_path)
    assert (tmp_path / "fig4_error.png").is_file()
    assert (tmp_path / "fig4_share.png").is_file()
    assert len(text.splitlines()) == 8


def test_full_config_matches_the_paper():
    cfg = paper_a.Config()
    assert (cfg.model.inverse_reservoir, cfg.model.forward_reservoir) == (1000, 100)
    assert (cfg.model.spectral_radius, cfg.model.noise, cfg.model.gain) == (0.1, 0.2, 0.65)
    assert cfg.delays == tuple(range(11)) and cfg.runs == 10
    assert len(paper_a.rows()) == 44
    assert isinstance(cfg.model, DelayConfig)
    fcfg = cfg.model.fel_config(3)
    assert fcfg.delay_steps == 3 and np.all(fcfg.gains() == 0.65)
