"""The runs of :mod:`skinny_mj.experiments.rl_vs_fel.study`: one learner, one seed, one
learning curve: the test errors against the env steps and CPU seconds used so far.

A curve is a list of points ``{"steps", "cpu_s", "wall_s", "tests"}``: env steps taken
so far (every step the plant ran in training), the training CPU time of the run's
process and its wall time so far (the tests left out; CPU is the fair clock on a shared
machine), and per test column ``{"position_nrmse", "rms_error_deg"}`` (None for a test
that diverged). ESN + FEL points also carry ``tests_k1``: the same test with the teacher
left on (K = 1), the controller the residual policies are tested as.

- ESN + FEL (:func:`fel_curve`): the one training path (:func:`skinny_mj.training.loop.
  train_run`) tested after every epoch through FEL's ``observe`` hook (the test resets
  the reservoir state only, which the next epoch resets anyway, and draws no reservoir
  noise, so the training is the one :func:`skinny_mj.training.loop.train` runs). Env
  steps per epoch: (learning cycles + 2) x (T - 1).
- PPO and SAC (:func:`rl_segment`): stable-baselines3 on :class:`skinny_mj.experiments.
  rl_vs_fel.tracking.TrackingEnv` (plain, gain 0, or residual, gain 1), tested at the
  env steps of :func:`test_steps` with the deterministic policy on a fresh test env. A
  curve is trained in segments: segment [start, end) continues the checkpoint that the
  segment ending at ``start`` saved (:mod:`skinny_mj.experiments.rl_vs_fel.agents`),
  reseeded from (seed, start), with a new episode; its run file holds the whole curve
  so far.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from skinny_mj import training  # the training loop loads on first use
from skinny_mj.errors import SkinnyInputError
from skinny_mj.training.config import TrainConfig

RL_EXTRA = "rl-vs-fel needs the rl extra: pip install -e '.[rl]'"


def require_rl() -> None:
    """Raise a one-line :class:`SkinnyInputError` when stable-baselines3 is missing."""
    try:
        import stable_baselines3  # noqa: F401
        import torch  # noqa: F401
    except ImportError:
        raise SkinnyInputError(RL_EXTRA) from None


class Clock:
    """Training wall time and this process's CPU time, the tests left out (:meth:`paused`),
    continuing from ``offset`` (wall s, CPU s) of earlier segments."""

    def __init__(self, offset: tuple[float, float] = (0.0, 0.0)) -> None:
        self.start = (time.perf_counter(), time.process_time())
        self.excluded = [-offset[0], -offset[1]]

    def elapsed(self) -> tuple[float, float]:
        """(wall s, CPU s) of training so far."""
        return (time.perf_counter() - self.start[0] - self.excluded[0],
                time.process_time() - self.start[1] - self.excluded[1])

    def paused(self, fn: Callable[[], Any]) -> Any:
        t0 = (time.perf_counter(), time.process_time())
        try:
            return fn()
        finally:
            self.excluded[0] += time.perf_counter() - t0[0]
            self.excluded[1] += time.process_time() - t0[1]


def point(steps: int, elapsed: tuple[float, float], tests: Mapping[str, Any],
          **more: Mapping[str, Any]) -> dict:
    """A curve's point: env steps, training (wall, CPU) seconds so far, test errors."""
    return {"steps": int(steps), "wall_s": float(elapsed[0]), "cpu_s": float(elapsed[1]),
            "tests": dict(tests), **{k: dict(v) for k, v in more.items()}}


def test_steps(budget: int, first: int = 1000) -> list[int]:
    """The env steps a curve is tested at: 0, then 1, 1.5, 2, 3, 5 and 7 x 10^k from
    ``first`` (log-spaced, for a log axis), and the budget."""
    grid = {int(m * 10 ** k) for k in range(3, 9) for m in (1, 1.5, 2, 3, 5, 7)}
    return [0, *sorted(s for s in grid if first <= s < budget), int(budget)]


# -- ESN + FEL ----------------------------------------------------------------------------
def _fel_tests(run, columns: Mapping[str, Any], gain: float | None = None) -> dict:
    if gain is not None:  # the same networks tested with another K
        import dataclasses

        run = dataclasses.replace(run, cfg=run.cfg.override({"test.gain": gain}))
    out = {}
    for col, trajectory in columns.items():
        test = training.evaluate(run, trajectory)[0]
        bad = test.failed or (test.torque is not None and test.torque["metrics"]["warnings"])
        out[col] = None if bad else {
            "position_nrmse": float(test.position_nrmse),
            "rms_error_deg": training.test_robot_metrics(run, test)["rms_error_deg"]}
    return out


def fel_curve(tc: TrainConfig, seed: int, columns: Mapping[str, Any]) -> tuple[list, dict]:
    """ESN + FEL's curve (tested before training and after every epoch on ``columns``:
    id -> trajectory, None for the training movement's one repetition) and facts:
    ``failed`` (diverged in training), ``steps_per_epoch``."""
    run = training.build_run(tc, [seed])
    steps_per_epoch = (tc.learning_cycles + 2) * (len(run.desired) - 1)
    last_cycle = tc.learning_cycles + 1
    clock = Clock()

    def tests() -> dict:
        return {"tests": _fel_tests(run, columns), "tests_k1": _fel_tests(run, columns, 1.0)}

    points = [point(0, (0.0, 0.0), **clock.paused(tests))]

    def observe(epoch: int, cycle: int, ro, y_used) -> None:
        if cycle == last_cycle:
            found = clock.paused(tests)
            points.append(point((epoch + 1) * steps_per_epoch, clock.elapsed(), **found))

    trained = training.train_run(run, observe=observe)
    failed = bool(trained.fel is not None and trained.fel.failed[0])
    return points, {"failed": failed, "steps_per_epoch": steps_per_epoch}


# -- PPO / SAC ----------------------------------------------------------------------------
def rl_segment(learner: str, gain: float, tc: TrainConfig, seed: int,
               columns: Mapping[str, Any], span: tuple[int, int], folder: Path | None,
               changes: Mapping[str, Any] | None = None, quick: bool = False,
               ) -> tuple[list, dict]:
    """Train ``learner`` ("ppo" or "sac") with the teacher's ``gain`` (0 plain, 1
    residual) on the movement of ``tc`` from env step ``span[0]`` to ``span[1]``, tested
    at :func:`test_steps` on ``columns`` (id -> trajectory, None: the training movement).
    ``folder``: the curve's checkpoints (``<folder>/<steps>``; None: none are read or
    written, a curve of one segment from 0). Returns the whole curve so far and facts."""
    import torch
    from skinny_mj.experiments.rl_vs_fel import agents
    from skinny_mj.experiments.rl_vs_fel.tracking import TrackingEnv, score
    from stable_baselines3.common.callbacks import BaseCallback

    torch.set_num_threads(1)
    start, end = span
    trajectory, _ = training.load_trajectory(tc)
    repeated = trajectory.repeat(tc.movement.reps) if tc.movement.reps > 1 else trajectory
    v_max = training.full_scale_speeds(tc, trajectory)
    plant_seed = training.run_streams(seed).plant_seed  # FEL's training and test plants' seed
    env = TrackingEnv(tc, repeated, v_max, plant_seed, gain)
    kwargs, norm = agents.settings(learner, dict(changes or {}), quick)
    venv = agents.vec_env(env, learner, norm, kwargs.get("gamma", 0.99))
    segment_seed = int(np.random.SeedSequence([seed, start]).generate_state(1)[0] >> 1)
    if start == 0:
        model, state = agents.make_model(learner, venv, segment_seed, kwargs), {
            "points": [], "offset": [0.0, 0.0], "diverged": 0}
    else:
        if folder is None or not (folder / str(start) / "state.json").is_file():
            raise SkinnyInputError(f"no checkpoint at {start} env steps in {folder}: run the "
                                   "curve's earlier segment first (the same checkpoints folder)")
        model, state = agents.load(folder / str(start), learner, venv, segment_seed)
    def test_env(t) -> TrackingEnv:  # a fresh plant each test: its noise restarts
        return TrackingEnv(tc, trajectory if t is None else t, v_max, plant_seed, gain,
                           test=True)

    washout = tc.test.washout_cycles
    due = [s for s in test_steps(end) if s > start or s == start == 0]

    class Curve(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.points: list[dict] = list(state["points"])
            self.clock = Clock(tuple(state["offset"]))

        def test(self) -> None:
            def predict(obs: np.ndarray) -> np.ndarray:
                return self.model.predict(venv.normalize_obs(obs), deterministic=True)[0]

            found = self.clock.paused(lambda: {c: score(predict, test_env(t), washout)
                                               for c, t in columns.items()})
            self.points.append(point(self.num_timesteps, self.clock.elapsed(), found))
            due.pop(0)

        def _on_training_start(self) -> None:
            self.clock = Clock(tuple(state["offset"]))
            if due and due[0] == self.num_timesteps:
                self.test()

        def _on_step(self) -> bool:
            if due and self.num_timesteps >= due[0]:
                self.test()
            return True

    curve = Curve()
    model.learn(end - start, callback=curve, reset_num_timesteps=start == 0)
    if due:  # the budget's own test, after the last update
        curve.test()
    diverged = state["diverged"] + env.diverged
    if folder is not None:
        agents.save(folder / str(end), learner, model, venv,
                    {"points": curve.points, "offset": list(curve.clock.elapsed()),
                     "diverged": diverged})
    return curve.points, {"failed": False, "diverged_episodes": diverged,
                          "segment": [start, end]}


# -- metrics of a curve ---------------------------------------------------------------------
def mean_error(p: dict, columns: Sequence[str], key: str = "position_nrmse",
               tests: str = "tests") -> float | None:
    """The mean of ``key`` over ``columns`` of point ``p`` (None if any test diverged)."""
    values = [(p[tests].get(c) or {}).get(key) for c in columns]
    return None if any(v is None for v in values) else float(np.mean(values))


def curve_metrics(points: list[dict], scores: Mapping[str, Sequence[str]],
                  thresholds: Sequence[float], tests: str = "tests") -> dict:
    """Per score (name -> the columns it averages): the final and best NRMSE, the final
    RMS joint error (deg) and, per threshold, the env steps and training CPU / wall time
    of the first test at or below it (None if none); the budget and training time."""
    out: dict[str, Any] = {"env_steps": points[-1]["steps"],
                           "train_wall_s": points[-1]["wall_s"],
                           "train_cpu_s": points[-1]["cpu_s"]}
    for name, cols in scores.items():
        errs = [mean_error(p, cols, tests=tests) for p in points]
        finite = [e for e in errs if e is not None]
        out[f"{name}__nrmse"] = errs[-1]
        out[f"{name}__best_nrmse"] = min(finite) if finite else None
        out[f"{name}__rms_error_deg"] = mean_error(points[-1], cols, "rms_error_deg", tests)
        for th in thresholds:
            first = next((p for p, e in zip(points, errs, strict=True)
                          if e is not None and e <= th), None)
            for what, key in (("steps", "steps"), ("cpu", "cpu_s"), ("wall", "wall_s")):
                out[f"{name}__{what}_to_{th:g}"] = None if first is None else first[key]
    return out
