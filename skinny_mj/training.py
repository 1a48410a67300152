"""One training run of an ESN inverse model on the MuJoCo plant, and its test.

This is the glue between the pure-NumPy learning in ``controllers/`` and the plant:
it builds the movement, the plant (:class:`skinny_mj.plant.BatchPlant`, or the
dm_control environment through :class:`skinny_mj.plant.EnvPlant`), the ESN, runs
feedback-error learning (original or new β method) or the true-target architecture,
and tests the trained network with the feedback controller off (K = 0).

Seeds: a run's seed s spawns two streams, ``SeedSequence(s).spawn(2)``: the ESN's
Generator (weights, then reservoir noise) and the plant's sensor-noise seed. So a run
is reproduced from (config, seed) alone, whichever plant path runs it.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field, fields, replace
from typing import Any

import numpy as np

from controllers import fel
from controllers.esn import ESN, ESNConfig
from controllers.true_target import TrueTargetConfig, train_true_target
from skinny_mj.errors import SkinnyInputError

METHODS = ("original", "new", "true-target")
#: Learning cycles per epoch the paper derived from its Figure 3 (paper E, Table 1).
PAPER_CYCLES_FOR_BETA = {0.3: 2, 0.1: 3, 0.05: 6}
#: Reservoir noise the paper chose per method (paper E, Fig. 5).
DEFAULT_NOISE = {"original": 0.03, "new": 0.2, "true-target": 0.2}


@dataclass(frozen=True)
class TrainConfig:
    """One training run. Defaults: paper E experiment 5 (2D, Cartesian, N = 200,
    spectral radius 0.5, reservoir noise 0.2, β = 0.1 with 3 learning cycles per
    epoch, 10 epochs, K 1 → 0, sensor noise 0.01)."""

    dof: int = 4
    signals: str = "cartesian"
    trajectory: str = "ymca"
    asf: str | None = None
    speed: float = 1.0
    reps: int = 1
    method: str = "new"
    beta: float = 0.1
    cycles: int | None = None  # learning cycles per epoch (new method); None: from β
    epochs: int = 10
    reservoir: int = 200
    spectral_radius: float = 0.5
    noise: float | None = None  # reservoir noise ν; None: DEFAULT_NOISE[method]
    readout: str = "pinv"
    ridge: float = 1e-6
    sensor_noise: float = 0.01
    tt_cycles: int = 50  # true-target with β < 1: cycles (paper D: 50 rounds); β = 1: one fit
    max_speed_from: str | None = None  # movement whose speeds set full scale (None: this one)
    plant: str = "batch"  # "batch" (MjData stepped directly) or "env" (dm_control)

    def __post_init__(self) -> None:
        checks = [
            (self.method in METHODS, f"method must be one of {METHODS}, got {self.method!r}"),
            (0 < self.beta <= 1, f"--beta must be in (0, 1], got {self.beta}"),
            (self.cycles is None or self.cycles >= 1, f"--cycles must be >= 1, got {self.cycles}"),
            (self.epochs >= 1, f"--epochs must be >= 1, got {self.epochs}"),
            (self.reservoir >= 1, f"--reservoir must be >= 1, got {self.reservoir}"),
            (
                math.isfinite(self.spectral_radius) and self.spectral_radius >= 0,
                f"--spectral-radius must be >= 0, got {self.spectral_radius}",
            ),
            (
                self.noise is None or (math.isfinite(self.noise) and self.noise >= 0),
                f"--noise must be >= 0, got {self.noise}",
            ),
            (self.readout in ("pinv", "ridge"), f"--readout must be pinv or ridge, got "
             f"{self.readout!r}"),
            (self.ridge >= 0, f"--ridge must be >= 0, got {self.ridge}"),
            (self.reps >= 1, f"--reps must be >= 1, got {self.reps}"),
            (self.plant in ("batch", "env"), f"plant must be 'batch' or 'env', got {self.plant!r}"),
        ]
        for ok, message in checks:
            if not ok:
                raise SkinnyInputError(message)

    @property
    def noise_level(self) -> float:
        return DEFAULT_NOISE[self.method] if self.noise is None else self.noise

    @property
    def learning_cycles(self) -> int:
        """Learning cycles per epoch: 1 for the original method; for the new method the
        paper's Table 1 where it has β, else enough cycles for (1 − β)^n to fall below
        5 % over all epochs (which reproduces the table for β = 0.1 and 0.05)."""
        if self.cycles is not None:
            return self.cycles
        if self.method != "new":
            return 1
        for beta, cycles in PAPER_CYCLES_FOR_BETA.items():
            if abs(self.beta - beta) < 1e-12:
                return cycles
        if self.beta >= 1:
            return 1
        total = math.ceil(math.log(0.05) / math.log(1.0 - self.beta))
        return max(1, math.ceil(total / self.epochs))


def run_streams(seed: int) -> tuple[np.random.Generator, int]:
    """The ESN's Generator and the plant's sensor-noise seed for run ``seed``."""
    esn_ss, plant_ss = np.random.SeedSequence(seed).spawn(2)
    return np.random.default_rng(esn_ss), int(plant_ss.generate_state(1, np.uint64)[0])


def load_trajectory(cfg: TrainConfig):
    """The movement of one repetition (at cfg.speed) and its retarget report."""
    from skinny_mj.trajectories import load_movement

    return load_movement(cfg.trajectory, cfg.dof, asf=cfg.asf, speed=cfg.speed)


def make_plant(dof: int, signals: str, trajectory, seed: int | Sequence[int],
               sensor_noise: float, max_speed_rad_s: np.ndarray, kind: str = "batch"):
    """A plant imitating ``trajectory``: one run per seed (an int is one run).

    ``kind`` "batch": one :class:`skinny_mj.plant.BatchPlant` stepping every run in
    lockstep; "env": the dm_control environment (one run only).
    """
    from skinny_mj.plant import BatchPlant, EnvPlant
    from skinny_mj.task import load

    seeds = [int(seed)] if np.isscalar(seed) else [int(s) for s in seed]
    if kind == "env":
        if len(seeds) != 1:
            raise ValueError("the dm_control path steps one run per environment")
        env = load(dof, signals, trajectory, sensor_noise=sensor_noise, seed=seeds[0],
                   max_speed_rad_s=max_speed_rad_s)
        return EnvPlant(env)
    return BatchPlant(dof, signals, trajectory, n_runs=len(seeds), seeds=seeds,
                      sensor_noise=sensor_noise, max_speed_rad_s=max_speed_rad_s)


def esn_config(cfg: TrainConfig, n_signals: int) -> ESNConfig:
    try:
        return ESNConfig(
            n_inputs=2 * n_signals, n_outputs=cfg.dof, n_reservoir=cfg.reservoir,
            spectral_radius=cfg.spectral_radius, noise_level=cfg.noise_level,
            readout=cfg.readout, ridge_lambda=cfg.ridge,
        )
    except ValueError as err:
        raise SkinnyInputError(str(err)) from None


@dataclass
class TestOutcome:
    """A closed-loop test (K = 0) of a trained network on one movement."""

    position_nrmse: float | None
    motor_nrmse: float | None
    failed: bool
    fail_reason: str | None
    rollout: fel.Rollout = field(repr=False)
    trajectory: Any = field(repr=False)
    desired: np.ndarray = field(repr=False)
    true_commands: np.ndarray = field(repr=False)


def test_networks(esn: ESN, trajectory, signals: str, plant_seeds: Sequence[int],
                  sensor_noise: float, max_speed_rad_s: np.ndarray,
                  plant_kind: str = "batch") -> list[TestOutcome]:
    """Test R networks in lockstep (one plant run each, sensor noise from
    ``plant_seeds``): reset, one cycle with the feedback controller off, no learning,
    no reservoir noise."""
    from skinny_mj.ideal import true_commands

    plant = make_plant(trajectory.dof, signals, trajectory, plant_seeds, sensor_noise,
                       max_speed_rad_s, plant_kind)
    desired = trajectory.position_signals(signals)
    commands = true_commands(trajectory.angles, max_speed_rad_s, trajectory.dt)
    ev = fel.evaluate(esn, plant, desired, true_commands=commands)
    out = []
    for r in range(esn.n_runs):
        failed = bool(ev.failed[r])
        out.append(TestOutcome(
            position_nrmse=None if failed else float(ev.position_nrmse[r]),
            motor_nrmse=None if failed else float(ev.motor_nrmse[r]),
            failed=failed, fail_reason=ev.fail_reason[r], rollout=rollout_run(ev.rollout, r),
            trajectory=trajectory, desired=desired, true_commands=commands,
        ))
    return out


def test_network(esn: ESN, trajectory, signals: str, seed: int, sensor_noise: float,
                 max_speed_rad_s: np.ndarray, plant_kind: str = "batch") -> TestOutcome:
    """:func:`test_networks` for one network and one plant seed."""
    return test_networks(esn, trajectory, signals, [seed], sensor_noise, max_speed_rad_s,
                         plant_kind)[0]


@dataclass
class TrainOutcome:
    """Everything one run produced: metrics (JSON-ready), the network, the test."""

    config: TrainConfig
    seed: int
    metrics: dict
    esn: ESN = field(repr=False)
    test: TestOutcome = field(repr=False)
    max_speed_rad_s: np.ndarray = field(repr=False)

    @property
    def failed(self) -> bool:
        return bool(self.metrics["failed"])


def train(cfg: TrainConfig, seed: int = 0,
          progress: Callable[[int, int], None] | None = None) -> TrainOutcome:
    """Train one ESN inverse model with ``cfg`` and test it on one repetition.

    ``progress(done, total)`` is called after every cycle (for a progress bar).
    """
    return _train_runs(cfg, [seed], progress)[0]


def relative_cost(cfg: TrainConfig) -> float:
    """A training's size, for scheduling sweeps (longest first): its cycles through the
    movement (FEL: epochs x (learning cycles + washout + evaluation); true target: its
    cycles; x reps; + the test), x N / 200 for reservoirs above 200 units."""
    cycles = cfg.tt_cycles if cfg.method == "true-target" \
        else cfg.epochs * (cfg.learning_cycles + 2)
    return (cycles * cfg.reps + 1) * max(1.0, cfg.reservoir / 200)


def train_batch(cfg: TrainConfig, seeds: Sequence[int],
                progress: Callable[[int, int], None] | None = None) -> list[TrainOutcome]:
    """Train R = len(seeds) runs of ``cfg`` in lockstep; run r equals ``train(cfg, seeds[r])``.

    One ESN with R networks (``rngs`` = each seed's :func:`run_streams` Generator) and
    one :class:`skinny_mj.plant.BatchPlant` with R ``MjData`` (each seed's sensor-noise
    seed) step together; every per-run number is the one the single run computes.
    ``metrics["wall_s"]`` is the batch's wall time divided by R (and
    ``metrics["lockstep_runs"]`` = R). With ``cfg.plant == "env"`` (dm_control, one run
    per environment) the runs are trained one after another.
    """
    seeds = [int(s) for s in seeds]
    if cfg.plant == "env":
        return [train(cfg, s, progress) for s in seeds]
    return _train_runs(cfg, seeds, progress) if seeds else []


def _train_runs(cfg: TrainConfig, seeds: list[int],
                progress: Callable[[int, int], None] | None) -> list[TrainOutcome]:
    """The one training path behind :func:`train` and :func:`train_batch`."""
    from skinny_mj.ideal import true_commands

    start = time.perf_counter()
    n_runs = len(seeds)
    trajectory, report = load_trajectory(cfg)
    training = trajectory.repeat(cfg.reps) if cfg.reps > 1 else trajectory
    # Full scale: twice the fastest speed of each DOF in ONE repetition of the movement
    # (or of another movement, so that networks trained on different movements share
    # one command scale, as in paper C).
    max_speed = full_scale_speeds(cfg, trajectory)
    streams = [run_streams(s) for s in seeds]
    plant_seeds = [p for _, p in streams]
    n_signals = trajectory.position_signals(cfg.signals).shape[1]
    esn = ESN(esn_config(cfg, n_signals), n_runs=n_runs, rngs=[g for g, _ in streams])
    desired = training.position_signals(cfg.signals)
    commands = true_commands(training.angles, max_speed, training.dt)
    runs: list[dict[str, Any]] = [{} for _ in seeds]  # per run: "train" (+ failure)
    if cfg.method == "true-target":
        tt = TrueTargetConfig(method="original" if cfg.beta >= 1 else "new", beta=cfg.beta,
                              cycles=cfg.tt_cycles, noise=cfg.noise_level > 0)
        result = train_true_target(esn, desired, commands, tt,
                                   one_step=one_step_positions(training, cfg.signals, max_speed))
        for r in range(n_runs):
            runs[r]["train"] = {"motor_nrmse": float(result.motor_nrmse[r]),
                                "position_nrmse": float(result.position_nrmse[r])}
        _report(progress, 1, 1)
    else:
        fcfg = fel.FELConfig(method=cfg.method, beta=cfg.beta,
                             learning_cycles=cfg.learning_cycles, epochs=cfg.epochs)
        per_epoch = fcfg.learning_cycles + 2
        total = cfg.epochs * per_epoch
        plant = make_plant(cfg.dof, cfg.signals, training, plant_seeds, cfg.sensor_noise,
                           max_speed, cfg.plant)

        def tick(epoch: int, cycle: int) -> None:
            _report(progress, epoch * per_epoch + cycle + 1, total)

        result = fel.train(esn, plant, desired, fcfg, true_commands=commands, progress=tick)
        curve = result.to_dict()
        for r in range(n_runs):
            runs[r]["train"] = {"gains": curve["gains"],
                                "position_nrmse": curve["position_nrmse"][r],
                                "motor_nrmse": curve["motor_nrmse"][r]}
            if result.failed[r]:
                runs[r].update(failed=True, fail_reason=result.fail_reason[r],
                               fail_epoch=result.fail_epoch[r])
    tests = test_networks(esn, trajectory, cfg.signals, plant_seeds, cfg.sensor_noise,
                          max_speed, cfg.plant)
    wall_share = (time.perf_counter() - start) / n_runs
    outcomes = []
    for r, (seed, metrics, test) in enumerate(zip(seeds, runs, tests, strict=True)):
        if not metrics.get("failed") and test.failed:
            metrics.update(failed=True, fail_reason=f"test: {test.fail_reason}")
        metrics.setdefault("failed", False)
        if metrics["failed"]:  # a diverged network has no test result, only its reason
            metrics["test"] = {"position_nrmse": None, "motor_nrmse": None}
        else:
            metrics["test"] = {"position_nrmse": test.position_nrmse,
                               "motor_nrmse": test.motor_nrmse}
        metrics.update(
            config={**asdict(cfg), "learning_cycles": cfg.learning_cycles,
                    "noise_level": cfg.noise_level},
            seed=seed, steps_per_cycle=len(desired),
            max_speed_rad_s=[float(v) for v in max_speed],
            clipped_samples=int(report.clipped_samples), wall_s=wall_share,
            lockstep_runs=n_runs,
        )
        outcomes.append(TrainOutcome(cfg, seed, metrics, esn_run(esn, r), test, max_speed))
    return outcomes


def record_test(path, outcome: TrainOutcome, title: str, metadata: dict | None = None):
    """Write the closed-loop test of a trained run as one rerun ``.rrd``: desired vs
    actual angles and signals, commands, the arms in 3D, and the training curve."""
    from skinny_mj import body
    from skinny_mj.recording import write_recording

    test, cfg, ro = outcome.test, outcome.config, outcome.test.rollout
    curve = outcome.metrics["train"].get("position_nrmse")
    curves = None
    if isinstance(curve, list) and curve:
        curves = {"train_position_nrmse": np.array([np.nan if v is None else v for v in curve],
                                                   dtype=float)}
    meta = {"seed": outcome.seed, "test": outcome.metrics["test"], "movement": cfg.trajectory,
            **(metadata or {})}
    return write_recording(
        path, dt=test.trajectory.dt, dof=cfg.dof, dof_names=list(body.dof_names(cfg.dof)),
        signal_names=list(body.signal_names(cfg.dof, cfg.signals)),
        desired_angles=test.trajectory.angles, actual_angles=ro.angles[0],
        commands=ro.commands[0], desired_signals=test.desired,
        actual_signals=ro.true_signals[0], sensed_signals=ro.sensed[0], title=title,
        metadata=meta, curves=curves,
    )


def esn_run(esn: ESN, r: int) -> ESN:
    """Run ``r`` of a lockstep ESN as a one-run ESN (weights, state, noise stream)."""
    if esn.n_runs == 1:
        return esn
    one = ESN.__new__(ESN)
    one.cfg, one.n_runs, one.dtype, one.rngs = esn.cfg, 1, esn.dtype, [esn.rngs[r]]
    one._set_weights(esn.W[r:r + 1], esn.W_in[r:r + 1], esn.W_back[r:r + 1],
                     esn.W_out[r:r + 1])
    one.x, one.y = esn.x[r:r + 1].copy(), esn.y[r:r + 1].copy()
    one.extended = esn.extended[r:r + 1].copy()
    one._noise_pos = esn._noise_pos
    if hasattr(esn, "_noise_buf"):
        one._noise_buf = esn._noise_buf[:, r:r + 1].copy()
    return one


def rollout_run(ro: fel.Rollout, r: int) -> fel.Rollout:
    """Run ``r`` of a lockstep :class:`controllers.fel.Rollout` (arrays keep R = 1)."""
    if ro.commands.shape[0] == 1:
        return ro
    return fel.Rollout(**{
        f.name: None if getattr(ro, f.name) is None else getattr(ro, f.name)[r:r + 1]
        for f in fields(ro)
    })


def full_scale_speeds(cfg: TrainConfig, trajectory) -> np.ndarray:
    """(n_dof,) rad/s: 2 x the fastest speed per DOF of ``trajectory`` (one repetition)
    or of the movement named by ``cfg.max_speed_from``."""
    from skinny_mj.ideal import max_speeds
    from skinny_mj.trajectories import load_movement

    if cfg.max_speed_from is not None:
        trajectory, _ = load_movement(cfg.max_speed_from, cfg.dof, asf=cfg.asf)
    return max_speeds(trajectory.angles, trajectory.dt)


def one_step_positions(trajectory, signals: str, max_speed_rad_s: np.ndarray):
    """The true-target architecture's training position error: each teacher-forced
    command applied for one step from the desired pose q_d(t), through Skinny's
    kinematics (the servo follows a command to < 1 %; joints clip at their ranges)."""
    from skinny_mj import body

    dof, dt = trajectory.dof, trajectory.dt
    lo, hi = body.joint_ranges(dof).T
    q_from = trajectory.angles[:-1]

    def one_step(_positions: np.ndarray, commands: np.ndarray) -> np.ndarray:
        q_next = np.clip(q_from + np.clip(commands, -1, 1) * max_speed_rad_s * dt, lo, hi)
        return body.position_signals(q_next, dof, signals)

    return one_step


def _report(progress: Callable[[int, int], None] | None, done: int, total: int) -> None:
    if progress is not None:
        progress(done, total)


def with_overrides(cfg: TrainConfig, **changes: Any) -> TrainConfig:
    """``cfg`` with some fields replaced (validated again)."""
    return replace(cfg, **{k: v for k, v in changes.items() if v is not None})
