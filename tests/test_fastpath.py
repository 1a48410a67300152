"""The fast path (R runs in lockstep on BatchPlant) computes what the slow paths compute.

- ``train_batch`` == ``train(plant="env")`` (dm_control) run by run;
- ``train_batch`` == ``train`` one seed at a time (bitwise), for FEL and true target;
- the engine's ``run_batch`` path writes the same run files as ``run_one``;
- float32 stays within a stated tolerance of float64.
No test here asserts on time: timings live in ``skinny bench``.
"""

from __future__ import annotations

import dataclasses
import functools
import json

import numpy as np
import pytest
from skinny_mj.controllers import fel
from skinny_mj.controllers.esn import ESN
from skinny_mj.controllers.metrics import position_nrmse
from toy import toy

from skinny_mj.cli import bench
from skinny_mj.engine.experiment import Row, RunFailed, execute_batch, run_sweep
from skinny_mj.engine.plan import Experiment
from skinny_mj.plant.adapters import BatchPlant, EnvPlant
from skinny_mj.plant.task import load
from skinny_mj.training.loop import TrainConfig, train, train_batch

# new method, 2 epochs of 4 cycles, 313 steps
TINY = TrainConfig().override(method__epochs=2, method__cycles=1)


def _same_outcome(a, b, atol: float = 0.0) -> None:
    for key in ("position_nrmse", "motor_nrmse"):
        np.testing.assert_allclose(getattr(a.test, key), getattr(b.test, key),
                                   rtol=0, atol=atol)
        np.testing.assert_allclose(np.asarray(getattr(a.train, key), float),
                                   np.asarray(getattr(b.train, key), float), rtol=0, atol=atol)
    np.testing.assert_allclose(a.esn.W_out, b.esn.W_out, rtol=0, atol=atol)
    np.testing.assert_allclose(a.test.rollout.commands, b.test.rollout.commands, rtol=0,
                               atol=atol)
    assert a.failed == b.failed


def test_fast_path_equals_dm_control_path_per_seed():
    seeds = [5, 6]
    fast = train_batch(TINY, seeds)
    for seed, outcome in zip(seeds, fast, strict=True):
        slow = train(TINY.override(plant__backend="env"), seed)
        # Same operations on the same numbers: bitwise in practice; 1e-9 is the contract.
        _same_outcome(outcome, slow, atol=1e-9)
        assert outcome.lockstep_runs == len(seeds)


@pytest.mark.parametrize("cfg", [
    TINY,
    TrainConfig().override(method="original", method__epochs=2, movement__reps=2),
    TrainConfig().override(method="true-target", method__cycles=3),
    TrainConfig().override(plant__signals="joint", method__epochs=1),
])
def test_lockstep_equals_one_at_a_time_bitwise(cfg):
    seeds = [1, 2, 3]
    for outcome, seed in zip(train_batch(cfg, seeds), seeds, strict=True):
        single = train(cfg, seed)
        _same_outcome(outcome, single)
        assert outcome.seed == seed
        assert outcome.config.to_dict() == single.config.to_dict()


def test_batch_esn_slice_continues_like_the_single_network():
    cfg = TINY
    batch = train_batch(cfg, [4, 9])[1]
    single = train(cfg, 9)
    u = np.random.default_rng(0).uniform(-1, 1, (1, 20, batch.esn.cfg.n_inputs))
    np.testing.assert_array_equal(batch.esn.run(u)[0], single.esn.run(u)[0])


def test_batch_plant_noise_blocks_cross_their_boundary_like_env():
    from skinny_mj.trajectories import get

    traj = get("ymca", 4)  # 313 steps > the 128-vector noise block
    batch = BatchPlant(4, "cartesian", traj, n_runs=2, seeds=[3, 4])
    envs = [EnvPlant(load(4, "cartesian", traj, seed=s)) for s in (3, 4)]
    u = np.random.default_rng(1).uniform(-1, 1, (len(traj) - 1, 2, 4))
    np.testing.assert_array_equal(batch.reset(), np.concatenate([e.reset() for e in envs]))
    for step in u:
        got = batch.step(step)
        want = np.concatenate([e.step(step[r:r + 1]) for r, e in enumerate(envs)])
        np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(batch.command_jacobian(),
                                  np.concatenate([e.command_jacobian() for e in envs]))


@pytest.mark.parametrize("signals", ["cartesian", "cartesian-elbow", "joint"])
def test_batch_plant_step_into_writes_what_step_and_the_reads_return(signals):
    from skinny_mj.trajectories import get

    traj = get("ymca", 4)
    a, b = (BatchPlant(4, signals, traj, n_runs=2, seeds=[3, 4]) for _ in range(2))
    np.testing.assert_array_equal(a.reset(), b.reset())
    sensed, true, angles = np.zeros((2, a.n_signals)), np.zeros((2, a.n_signals)), np.zeros((2, 4))
    for command in np.random.default_rng(1).uniform(-1.2, 1.2, (140, 2, 4)):  # > a noise block
        b.step_into(command, sensed, true, angles)
        np.testing.assert_array_equal(sensed, a.step(command))
        np.testing.assert_array_equal(true, a.true_signals())
        np.testing.assert_array_equal(angles, a.joint_angles())
        np.testing.assert_array_equal(b.command_jacobian(), a.command_jacobian())


def test_float32_state_loop_and_closed_loop_within_tolerance():
    """float32 (stated tolerance): reservoir states within 1e-5 of float64 over 300
    steps; after one readout fit, the closed-loop position NRMSE within 10 % (the pinv
    fit amplifies the rounding, so single commands may differ by ~0.1-0.3)."""
    _, _, desired, esn64, plant = bench._lockstep_parts(3, 312)
    esn32 = ESN(dataclasses.replace(esn64.cfg, dtype="float32"), n_runs=3, seed=0)
    u = np.random.default_rng(2).uniform(-1, 1, (3, 300, esn64.cfg.n_inputs))
    x64 = esn64.run(u, noise=False)[1]
    x32 = esn32.run(u, noise=False)[1]
    assert x32.dtype == np.float32
    assert np.max(np.abs(x64 - x32)) < 1e-5
    nrmse = {}
    for name, esn in (("64", esn64), ("32", esn32)):
        esn.reset()
        ro = fel.rollout(esn, plant, desired, 1.0)
        esn.fit(ro.states, 0.1 * ro.y_est + 0.9 * ro.y_esn)
        nrmse[name] = position_nrmse(fel.rollout(esn, plant, desired, 0.5,
                                                 noise=False).true_signals, desired)
    np.testing.assert_allclose(nrmse["32"], nrmse["64"], rtol=0.1)


# -- the engine ---------------------------------------------------------------------------
def _toy_one(row: Row, seed: int) -> dict:
    if seed % 7 == 0:
        raise RunFailed("diverged")
    rng = np.random.default_rng(seed)
    return {"value": float(rng.random() + row.params["shift"])}


def _toy_batch(config, row: Row, seeds: list[int]) -> list:
    out: list = []
    for seed in seeds:
        try:
            out.append(_toy_one(row, seed))
        except RunFailed as exc:
            out.append(exc)
    return out


def _toy(run_batch, **study) -> Experiment:
    rows = (Row("a", params={"shift": 0.0}), Row("b", params={"shift": 1.0}))
    return toy("toy", rows, _toy_one, runs=7, run_batch=run_batch, **study)


def _run_files(out) -> dict:
    files = {}
    for path in sorted((out / "runs").glob("*.json")):
        rec = json.loads(path.read_text())
        files[path.name] = (rec["status"], rec["metrics"], rec["error"], rec["seed"])
    return files


@pytest.mark.parametrize("batch_size", [None, 3])
def test_engine_batches_write_the_same_run_files(tmp_path, batch_size):
    single = run_sweep(_toy(None), tmp_path / "single", workers=1, progress=False,
                       batch_size=0)
    batched = run_sweep(_toy(_toy_batch), tmp_path / "batch", workers=1, progress=False,
                        batch_size=batch_size)
    assert _run_files(tmp_path / "single") == _run_files(tmp_path / "batch")
    assert len(_run_files(tmp_path / "batch")) == 14
    for a, b in zip(single["rows"], batched["rows"], strict=True):  # all but wall times
        assert {k: v for k, v in a.items() if k != "wall_s"} == \
            {k: v for k, v in b.items() if k != "wall_s"}


def test_engine_batch_resume_and_raising_batch_falls_back(tmp_path):
    def broken(config, row, seeds):
        if len(seeds) > 1:
            raise MemoryError("too big")
        return _toy_batch(config, row, seeds)

    out = tmp_path / "sweep"
    run_sweep(_toy(broken), out, workers=1, progress=False, batch_size=4)
    first = _run_files(out)
    assert len(first) == 14 and any(s == "failed" for s, *_ in first.values())
    removed = sorted((out / "runs").glob("b-*.json"))[0]
    removed.unlink()
    calls = []

    def counting(config, row, seeds):
        calls.append(list(seeds))
        return _toy_batch(config, row, seeds)

    run_sweep(_toy(counting), out, workers=1, progress=False, resume=True)
    assert sum(len(c) for c in calls) == 1
    assert _run_files(out) == first


def test_default_batch_size_gives_every_worker_the_same_number_of_jobs():
    from skinny_mj.engine.experiment import default_batch_size

    assert default_batch_size(n_rows=6, runs=20, workers=2) == 20  # whole rows
    assert default_batch_size(n_rows=5, runs=50, workers=2) == 25  # 10 jobs
    assert default_batch_size(n_rows=1, runs=20, workers=2) == 10
    assert default_batch_size(n_rows=3, runs=4, workers=8) == 1  # runs bound the cut
    assert default_batch_size(n_rows=2, runs=7, workers=1) == 7


def test_costliest_batches_start_first_and_files_do_not_change(tmp_path):
    started = []

    def recording(config, row, seeds):
        started.append(row.id)
        return _toy_batch(config, row, seeds)

    plain = run_sweep(_toy(_toy_batch), tmp_path / "plain", workers=1, progress=False)
    exp = _toy(recording, cost=lambda config, row: 1.0 + row.params["shift"])
    costed = run_sweep(exp, tmp_path / "costed", workers=1, progress=False, batch_size=7)
    assert started == ["b", "a"]  # row b costs 2, row a 1
    assert _run_files(tmp_path / "plain") == _run_files(tmp_path / "costed")
    assert [r["row"] for r in plain["rows"]] == [r["row"] for r in costed["rows"]]


def test_execute_batch_refuses_mixed_rows():
    from skinny_mj.engine.experiment import RunSpec

    specs = [RunSpec(Row("a"), 0, 0, 1), RunSpec(Row("b"), 1, 0, 2)]
    with pytest.raises(ValueError):
        execute_batch(functools.partial(_toy_batch, None), _toy_one, specs, "toy")


# -- bench plumbing (no timing asserted) ----------------------------------------------------
def test_bench_summary_reads_goals_and_skips():
    figures = {"esn_run_vs_reservoirpy": [{"ratio": 2.5}, {"skipped": "no"}],
               "control_step_over_physics": {"ratio": 4.0}, "lockstep_speedup": {"ratio": 3.1},
               "fast_vs_naive": {"ratio": 6.5}, "paper_e_full_s": {"skipped": "--quick"},
               "mackey_glass": {"ours_log10_nrmse84": -4.6},
               "load_avg_start": (1.0, 1.0, 1.0), "load_avg_end": (2.0, 1.0, 1.0),
               "cpu_count": 2}
    summary = bench.summary(figures)
    assert summary["esn_run_vs_reservoirpy_N200"]["met"] is True
    assert summary["esn_run_vs_reservoirpy_N1000"]["met"] is None
    assert summary["control_step_over_physics"]["met"] is False
    assert summary["mackey_glass_log10_nrmse84"]["met"] is True
    figures["summary"] = summary
    assert "skipped" in bench.table(figures)


def test_bench_reservoirpy_comparison_runs_the_same_network():
    pytest.importorskip("reservoirpy")
    fig = bench.esn_run_vs_reservoirpy(50, 30, 1)
    assert fig["max_state_diff"] < 1e-12
    assert fig["ratio"] > 0


def test_bench_paper_e_figure_runs_through_the_engine(tmp_path):
    fig = bench.paper_e_full_s(workers=1, quick=True, out_dir=tmp_path, only=("5",))
    assert fig["runs"] == 2 and fig["workers"] == 1 and fig["wall_s"] > 0
    records = [json.loads(p.read_text()) for p in (tmp_path / "runs").glob("*.json")]
    assert all(r["status"] == "ok" for r in records)
    assert fig["peak_rss_self_mib"] > 0


def test_bench_control_step_figure_runs_and_reports_both_floors():
    fig = bench.control_step_over_physics(n_steps=12, repeats=1)
    assert fig["R"] == bench.N_RUNS and fig["substeps"] == 1
    for key in ("control_step_us", "physics_step_us", "batch_physics_step_us"):
        assert np.isfinite(fig[key]) and fig[key] > 0
    assert fig["ratio"] == pytest.approx(fig["control_step_us"] / fig["physics_step_us"])
    assert fig["ratio_vs_batch_physics"] == pytest.approx(
        fig["control_step_us"] / fig["batch_physics_step_us"])
    assert np.isfinite(fig["floor_step_us"]) and fig["floor_step_us"] > 0
    assert fig["floor_vs_batch_physics"] == pytest.approx(
        fig["floor_step_us"] / fig["batch_physics_step_us"])
    assert fig["python_lines_per_step"] > 10  # the loop runs the package's code every step


def test_rollout_buffers_are_reused_and_change_nothing():
    _, _, desired, esn, plant = bench._lockstep_parts(3, 40)
    _, _, _, esn_b, plant_b = bench._lockstep_parts(3, 40)  # the same, seed by seed
    loop = fel.Loop().with_buffers()
    for _ in range(2):
        plain = fel.rollout(esn, plant, desired, 0.5)
        reused = fel.rollout(esn_b, plant_b, desired, 0.5, loop)
        for name in ("commands", "y_esn", "u_error", "sensed", "true_signals", "angles",
                     "states"):
            np.testing.assert_array_equal(getattr(plain, name), getattr(reused, name))
    assert np.shares_memory(reused.states, loop.buffers["states"])
    assert reused.states.shape == (3, len(desired) - 1, esn.cfg.n_extended)


class _Idle:
    """An online learner that learns nothing: it only sends the rollout down its loop
    with every part."""

    def update(self, state, y_esn, y_est) -> None:
        pass


def test_lean_loop_equals_the_loop_with_every_part():
    _, _, desired, esn, plant = bench._lockstep_parts(3, 40)
    _, _, _, esn_b, plant_b = bench._lockstep_parts(3, 40)  # the same, seed by seed
    for delay in (0, 2):
        lean = fel.rollout(esn, plant, desired, 0.5, fel.Loop(delay_steps=delay))
        every = fel.rollout(esn_b, plant_b, desired, 0.5,
                            fel.Loop(delay_steps=delay, online=_Idle()))
        for name in ("commands", "y_esn", "u_error", "sensed", "true_signals", "angles",
                     "states"):
            np.testing.assert_array_equal(getattr(lean, name), getattr(every, name))
