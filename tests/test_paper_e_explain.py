"""paper-e-explain (paper E §5.1): the diagnostics hook changes nothing, the three exps of
a run start from one network, roughness is the RMS second difference, and a tiny sweep
writes its table and Figs. 7–10."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from skinny_mj.experiments.paper_e_explain import study as pee
from toy import toy

from skinny_mj.engine.experiment import run_seed, run_sweep
from skinny_mj.engine.study import Quick
from skinny_mj.training.loop import build_run, evaluate, train_batch, train_run

TINY = {"method.epochs": 1, "esn.n_reservoir": 20}


def _config(exp: str, changes: dict):
    """Exp ``exp``'s training (the study's row) with ``changes``."""
    return pee.STUDY.config(exp).override(changes)


@pytest.fixture(scope="module")
def short(tmp_path_factory) -> dict:
    """TINY on the first 1.5 s of YMCA (75 steps): fast enough for the default run."""
    from skinny_mj.trajectories.ymca import ymca

    path = ymca(4).save(tmp_path_factory.mktemp("movement") / "ymca.npz")
    return {**TINY, "movement.trajectory": f"{path}@start=0,duration=1.5"}


def test_roughness_of_known_signals():
    t = np.arange(50.0)
    assert pee.roughness(np.c_[0.3 * t - 1]) == pytest.approx(0.0, abs=1e-12)  # a line
    assert pee.roughness(np.c_[0.01 * t**2]) == pytest.approx(0.02)  # d2 = 2 * 0.01
    zigzag = np.c_[(-1.0) ** t, np.zeros(50)]  # d2 = ±4 on one signal, 0 on the other
    assert pee.roughness(zigzag) == pytest.approx(2.0)
    batch = np.stack([np.c_[0.01 * t**2], np.c_[0.02 * t**2]])  # (R, T, n) -> (R,)
    np.testing.assert_allclose(pee.roughness(batch), [0.02, 0.04])


def _seed_of(row, seed: int) -> dict:
    return {"seed": float(seed)}


def _load(results: dict, out_dir) -> list[dict]:
    from skinny_mj.engine.stats import load_runs

    assert results["n_ok"] == 9
    return load_runs(out_dir)


def test_the_three_exps_of_a_run_start_from_one_network(tmp_path):
    seeds = toy("seeds", pee.STUDY.build().rows, _seed_of, runs=3)
    runs = [r for r in _load(run_sweep(seeds, tmp_path, workers=1, progress=False), tmp_path)]
    for k in range(3):  # row 1's seed of run k, in all three rows
        assert {r["row"]: r["metrics"]["seed"] for r in runs if r["run_index"] == k} == \
            dict.fromkeys(pee.EXPS, float(run_seed(0, pee.EXPS[0], k)))
    engine = [run_seed(0, pee.EXPS[0], 2)]
    nets = [build_run(_config(e, TINY), [engine[0]]).esn for e in pee.EXPS]
    for esn in nets[1:]:
        for name in ("W", "W_in", "W_back", "W_out"):
            np.testing.assert_array_equal(getattr(esn, name), getattr(nets[0], name))
    assert not np.any(nets[0].W_out)  # the initial readout is zero (SPEC §5)
    assert [n.cfg.noise_level for n in nets] == [0.03, 0.03, 0.2]  # paper E's levels


def test_the_hook_changes_no_result_and_measures_the_blend(short):
    cfg = _config("5", short)
    seed = run_seed(0, pee.EXPS[0], 0)
    plain = train_batch(cfg, [seed])[0]
    run = build_run(cfg, [seed])
    diag = pee.EpochDiagnostics(run.true_commands, run.desired, len(run.trajectory), 1,
                                cfg.method.epochs, cfg.learning_cycles)
    trained = train_run(run, observe=diag).fel
    test = evaluate(run)[0]
    np.testing.assert_array_equal(run.esn.W_out, plain.esn.W_out)
    assert trained.to_dict()["position_nrmse"][0] == plain.train.position_nrmse
    assert (test.position_nrmse, test.motor_nrmse) == (
        plain.test.position_nrmse, plain.test.motor_nrmse)
    m = diag.metrics(0, None)
    assert np.shape(m["est_rough_per_cycle"]) == (1, 3)  # (epochs, learning cycles)
    # β = 0.1 with a smooth previous output: the fitted target is smoother than y_est
    assert m["used_rough"][0] < m["est_rough"][0]
    assert m["esn_nrmse"][0] == pytest.approx(float(np.mean(np.sqrt(np.mean(
        (run.esn.readout(trained.last_rollout.states) - run.true_commands) ** 2, axis=1))
    ) / 2), abs=1e-6)  # the eval cycle's output, scored against the true commands


def _record(row: str, k: int, **series) -> dict:
    metrics = {"true_rough": 0.001, "diverged": 0, **series}
    return {"row": row, "run_index": k, "status": "ok", "metrics": metrics}


def test_claims_pair_runs_of_the_same_network():
    from skinny_mj.experiments.paper_e_explain.report import claims, table

    # run 0: y_used smoother than y_est; run 1: not; run 2 of exp 5 has no partner
    by_row = {"1": [], "2": [], "5": [
        _record("5", 0, est_rough=[0.2], used_rough=[0.1]),
        _record("5", 1, est_rough=[0.2], used_rough=[0.3])]}
    lines = claims(by_row, epochs=1)
    line = next(x for x in lines if "y_used is less noisy" in x)
    assert "[holds in 1 of 2 runs]" in line and "1 / 2 runs)" in line
    assert all(x.startswith("- [no runs]") for x in lines if "exp 1" in x and "Fig. 7" in x)
    assert "| y_used roughness | 5 | 0.2000 (0.1000) |" in table(by_row, epochs=1)


@pytest.mark.slow
def test_tiny_sweep_writes_table_and_figures(short, tmp_path):
    study = dataclasses.replace(pee.STUDY, quick=Quick(short, runs=1))
    exp = study.build(quick=True)
    results = run_sweep(exp, tmp_path, workers=1, progress=False)
    assert results["n_ok"] == 3
    text = exp.report(results, tmp_path)
    assert "y_est roughness" in text and "Fig. 9" in text
    for name in ("fig7_exp1", "fig8_reps", "fig9_exp5", "fig10_teacher_forcing"):
        assert (tmp_path / f"{name}.png").stat().st_size > 10_000
    # original method: the fitted target is the estimate itself
    from skinny_mj.engine.stats import load_runs

    exp1 = [r for r in load_runs(tmp_path) if r["row"] == "1"][0]["metrics"]
    assert exp1["used_rough"] == exp1["est_rough"] and exp1["series"]["epochs"] == [1]
