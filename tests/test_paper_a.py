"""Paper A (delays + forward models): the run glue, the claims, and a --quick sweep."""

from __future__ import annotations

import numpy as np
import pytest
from skinny_mj.controllers.esn import ESN, ESNConfig
from skinny_mj.controllers.fel import Rollout
from skinny_mj.controllers.forward_model import ForwardModel
from skinny_mj.controllers.metrics import nrmse
from skinny_mj.experiments import get, paper_a
from toy import toy

from skinny_mj.engine.experiment import Row, run_sweep


def _tiny(arch: str, delay: int):
    """The row's run at --quick's network sizes, 1 epoch of 1 learning cycle."""
    forward = {} if arch == "inverse" else {"forward.reservoir": 50}
    return paper_a.STUDY.config(paper_a.row_id(arch, delay)).override(
        {"esn.n_reservoir": 100, "method.epochs": 1, "method.cycles": 1, **forward})


def _run(arch: str, delay: int, seeds: list[int], config=None) -> list:
    row = paper_a.STUDY.row(paper_a.row_id(arch, delay))
    return paper_a.STUDY.run(config or _tiny(arch, delay), row, seeds)


def _rows(delays: tuple[int, ...]) -> tuple[Row, ...]:
    """The engine's rows of paper A's ids for ``delays`` (the claims read only ids)."""
    return tuple(Row(paper_a.row_id(a, d), params={"architecture": a, "delay": d})
                 for a in paper_a.ARCHITECTURES for d in delays)


def _movement(n: int = 120) -> tuple[np.ndarray, np.ndarray]:
    t = np.linspace(0, 2 * np.pi, n)
    desired = 0.6 * np.stack([np.sin(t + k) for k in range(4)], axis=1)
    commands = np.clip(np.diff(desired, axis=0) * 10, -1, 1)
    return desired, commands


def test_pretrained_forward_model_beats_the_delayed_no_change_guess():
    desired, commands = _movement()
    fm = ForwardModel(ESN(ESNConfig(8, 4, n_reservoir=60, spectral_radius=0.1,
                                    noise_level=0.2), seed=3), "serial")
    for delay in (0, 3):
        err = fm.pretrain(desired, commands, delay, sensor_noise=0.01)
        stale = nrmse(desired[np.maximum(np.arange(len(commands)) - delay, 0)], desired[1:])
        assert err.shape == (1,)
        assert err[0] < 0.5 * stale


def test_pretraining_noise_comes_from_each_runs_own_stream():
    desired, commands = _movement()
    cfg = ESNConfig(8, 4, n_reservoir=40, spectral_radius=0.1, noise_level=0.2)
    both = ForwardModel(ESN(cfg, n_runs=2, seed=9), "serial")
    err_both = both.pretrain(desired, commands, 2, sensor_noise=0.01)
    alone = [ForwardModel(both.esn.select([r]), "serial") for r in range(2)]
    # a fresh selection of an untrained batch = the same networks and streams, unused
    fresh = ForwardModel(ESN(cfg, n_runs=2, seed=9), "serial")
    alone = [ForwardModel(fresh.esn.select([r]), "serial") for r in range(2)]
    for r, fm in enumerate(alone):
        assert fm.pretrain(desired, commands, 2, sensor_noise=0.01)[0] == err_both[r]


def test_feedback_share_is_a_fraction_and_correction_ratio_can_exceed_one():
    y_esn = np.full((1, 5, 4), 0.5)
    commands = np.full((1, 5, 4), 0.1)  # feedback -0.4 fights the ESN's 0.5
    ro = Rollout(commands, y_esn, np.zeros((1, 6, 4)), *(np.zeros((1, 6, 4)),) * 3,
                 states=np.zeros((1, 5, 3)))
    assert ro.correction_ratio[0] == pytest.approx(4.0)
    assert paper_a.feedback_share(ro)[0] == pytest.approx(0.4 / 0.9)


def test_run_is_reproducible_and_reports_the_metrics():
    (a,), (b,) = _run("serial", 2, [5]), _run("serial", 2, [5])
    for key in ("performance_nrmse", "feedback_share", "prediction_nrmse",
                "pretrain_prediction_nrmse", "test_position_nrmse"):
        assert a[key] == b[key], key
        assert np.isfinite(a[key])
    assert 0 <= a["feedback_share"] <= 1
    assert "prediction_nrmse" not in _run("inverse", 0, [5])[0]


@pytest.mark.parametrize("arch", paper_a.ARCHITECTURES)
def test_lockstep_batch_equals_each_seed_alone(arch):
    seeds = [11, 12, 13]
    batch = _run(arch, 3, seeds)
    for seed, out in zip(seeds, batch, strict=True):
        (alone,) = _run(arch, 3, [seed])
        assert {k: v for k, v in out.items() if k != "wall_s"} == \
            {k: v for k, v in alone.items() if k != "wall_s"}


def test_delay_hurts_the_inverse_only_architecture():
    quick = paper_a.STUDY.build(quick=True)  # the --quick sweep
    d0 = _run("inverse", 0, [1], quick.config("inverse-d0"))[0]["performance_nrmse"]
    d4 = _run("inverse", 4, [1], quick.config("inverse-d4"))[0]["performance_nrmse"]
    assert d4 > 2 * d0


def _fake(metrics_by_row: dict[str, list[dict]]):
    def run_one(row, seed):
        return metrics_by_row[row.id][seed % len(metrics_by_row[row.id])]
    return run_one


def test_claims_hold_and_fail_on_synthetic_runs(tmp_path):
    good = {"inverse": (0.15, 0.5), "parallel": (0.08, 0.3), "hybrid": (0.07, 0.3),
            "serial": (0.04, 0.2)}
    metrics = {}
    for row in _rows((0, 4)):
        arch, d = row.params["architecture"], row.params["delay"]
        err, share = good[arch] if d else (0.01, 0.3)
        metrics[row.id] = [{"performance_nrmse": err + k * 0.001, "correction_ratio": share,
                                "pretrain_prediction_nrmse": 0.08} for k in range(3)]
    exp = toy("fake-a", _rows((0, 4)), _fake(metrics), runs=3)
    run_sweep(exp, tmp_path / "good", workers=1, progress=False)
    lines = paper_a.claims(tmp_path / "good")
    assert len(lines) == 8
    assert sum("[holds]" in line for line in lines) == 7  # delay 10 was not run
    assert "[n/a]" in lines[-1]

    metrics["serial-d4"] = [{"performance_nrmse": 0.3, "correction_ratio": 0.9,
                             "pretrain_prediction_nrmse": 0.01}]
    run_sweep(exp, tmp_path / "bad", workers=1, progress=False)
    bad = paper_a.claims(tmp_path / "bad")
    assert sum("does NOT hold" in line for line in bad) == 4  # lower x2, serial best, worst<best


def test_serial_best_counts_a_tie_within_the_spread_and_not_a_clear_loss(tmp_path):
    rows = _rows((4,))
    spread = (0.0, 0.01, -0.01)

    def sweep(name, serial_offset):
        metrics = {r.id: [{"performance_nrmse": 0.08 + s + (serial_offset if
                                r.params["architecture"] == "serial" else 0.0),
                               "correction_ratio": 0.5} for s in spread] for r in rows}
        calls: dict[str, int] = {}

        def run_one(row, seed):  # the k-th run of a row gets spread[k], whatever its seed
            calls[row.id] = calls.get(row.id, -1) + 1
            return metrics[row.id][calls[row.id]]

        run_sweep(toy(name, rows, run_one, runs=3), tmp_path / name,
                  workers=1, progress=False)
        return next(x for x in paper_a.claims(tmp_path / name) if "serial has the" in x)

    tied = sweep("tie", 0.001)  # 0.001 behind, spread 0.01: Welch p ~0.9
    assert "[holds]" in tied and "tied: d4" in tied
    behind = sweep("behind", 0.05)  # 0.05 behind, spread 0.01: p < 0.05
    assert "does NOT hold" in behind and "behind: d4" in behind


def test_quick_sweep_end_to_end(tmp_path):
    exp = get("paper-a").build(quick=True)
    results = run_sweep(exp, tmp_path, rows=["inverse-d0", "serial-d4"], workers=1,
                        progress=False)
    assert [r["row"] for r in results["rows"]] == ["inverse-d0", "serial-d4"]
    assert all(r["n_ok"] == 2 and r["n_failed"] == 0 for r in results["rows"])
    text = exp.report(results, tmp_path)
    assert (tmp_path / "fig4_error.png").is_file()
    assert (tmp_path / "fig4_share.png").is_file()
    assert len(text.splitlines()) == 8


def test_full_config_matches_the_paper():
    study = paper_a.STUDY
    m = study.base
    assert (m.esn.n_reservoir, m.forward.reservoir) == (1000, 100)
    assert (m.esn.spectral_radius, m.esn.noise_level, m.method.gain_value) == (0.1, 0.2, 0.65)
    assert (m.plant.dof, m.plant.signals, m.method.gain_schedule) == (4, "joint", "fixed")
    assert (m.method.kind, m.learning_cycles, m.method.epochs) == ("original", 5, 10)
    assert study.runs == 10 and len(study.rows) == 44
    assert [r.id for r in study.rows[:11]] == [f"inverse-d{d}" for d in range(11)]
    tcfg = study.config("hybrid-d3")
    assert (tcfg.plant.delay, tcfg.forward.kind, tcfg.forward.reservoir) == (3, "hybrid", 100)
    assert study.config("inverse-d3").forward.kind == "none"
    quick = study.build(quick=True)
    assert quick.config("serial-d4").forward.reservoir == 50
    assert (quick.config("inverse-d4").esn.n_reservoir, quick.config("inverse-d4").method.epochs) \
        == (100, 2)


def test_dof_8_builds_a_3d_sweep():
    exp = paper_a.STUDY.build(quick=True, body=8, signals="cartesian")
    assert {(exp.config(r.id).plant.dof, exp.config(r.id).plant.signals)
            for r in exp.rows} == {(8, "cartesian")}
