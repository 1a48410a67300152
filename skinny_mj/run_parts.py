"""The parts every run is built from: seed streams, the movement and its full scale, the
plant, the ESN's shape, the true commands. :func:`skinny_mj.training.build_run` assembles
them (and re-exports these names: the training API stays in one place).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from controllers.esn import ESNConfig
from skinny_mj import torque_training as torque
from skinny_mj.config import TrainConfig
from skinny_mj.errors import SkinnyInputError


class RunStreams(NamedTuple):
    """The random streams of one run (see the module docstring)."""

    esn: np.random.Generator
    plant_seed: int
    forward: np.random.Generator


def run_streams(seed: int) -> RunStreams:
    """The inverse ESN's Generator, the plant's sensor-noise seed and the forward
    ESN's Generator for run ``seed``."""
    esn_ss, plant_ss, fm_ss = np.random.SeedSequence(int(seed)).spawn(3)
    return RunStreams(np.random.default_rng(esn_ss),
                      int(plant_ss.generate_state(1, np.uint64)[0]),
                      np.random.default_rng(fm_ss))


def load_trajectory(cfg: TrainConfig):
    """The movement of one repetition (at cfg.speed) and its retarget report."""
    from skinny_mj.trajectories import load_movement

    kw = {} if cfg.retarget == "angles" else {"retarget": cfg.retarget}  # today's call
    return load_movement(cfg.trajectory, cfg.dof, asf=cfg.asf, speed=cfg.speed, **kw)


def full_scale_speeds(cfg: TrainConfig, trajectory) -> np.ndarray:
    """(n_dof,) rad/s: ``cfg.full_scale_factor`` (default 2) x the fastest speed per DOF
    of ``trajectory`` (one repetition) or of the movement named by ``cfg.max_speed_from``,
    so that networks trained on different movements share one command scale (paper C)."""
    from skinny_mj.ideal import max_speeds
    from skinny_mj.trajectories import load_movement

    if cfg.max_speed_from is not None:
        trajectory, _ = load_movement(cfg.max_speed_from, cfg.dof, asf=cfg.asf)
    return max_speeds(trajectory.angles, trajectory.dt, speed_factor=cfg.full_scale_factor)


def make_plant(cfg: TrainConfig, trajectory, plant_seeds: Sequence[int],
               max_speed_rad_s: np.ndarray):
    """The plant of ``cfg`` imitating ``trajectory``, one run per plant seed."""
    from skinny_mj.plant import BatchPlant, EnvPlant

    seeds = [int(s) for s in plant_seeds]
    common = dict(n_runs=len(seeds), seeds=seeds, sensor_noise=cfg.sensor_noise,
                  actuation=cfg.actuation, max_speed_rad_s=max_speed_rad_s)
    if cfg.leading_arm is not None:
        from skinny_mj.bimanual import BimanualPlant

        return BimanualPlant(cfg.dof, cfg.signals, trajectory, cfg.leading_arm, **common)
    if cfg.plant == "env":
        from skinny_mj.task import load

        if len(seeds) != 1:
            raise ValueError("the dm_control path steps one run per environment")
        env = load(cfg.dof, cfg.signals, trajectory, actuation=cfg.actuation,
                   sensor_noise=cfg.sensor_noise, seed=seeds[0], max_speed_rad_s=max_speed_rad_s)
        return EnvPlant(env)
    return BatchPlant(cfg.dof, cfg.signals, trajectory, **common)


def esn_config(cfg: TrainConfig, n_inputs: int, n_outputs: int,
               n_reservoir: int | None = None) -> ESNConfig:
    try:
        return ESNConfig(
            n_inputs=n_inputs, n_outputs=n_outputs,
            n_reservoir=cfg.reservoir if n_reservoir is None else n_reservoir,
            spectral_radius=cfg.spectral_radius, noise_level=cfg.noise_level,
            readout=cfg.readout, ridge_lambda=cfg.ridge,
        )
    except ValueError as err:
        raise SkinnyInputError(str(err)) from None


def controlled_dofs(cfg: TrainConfig) -> np.ndarray | None:
    """Body DOFs the ESN drives: None for all, paper B's lagging arm's otherwise."""
    if cfg.leading_arm is None:
        return None
    from skinny_mj.bimanual import arm_dofs

    return arm_dofs(cfg.dof, "left" if cfg.leading_arm == "right" else "right")


def true_commands_of(cfg: TrainConfig, trajectory, max_speed_rad_s: np.ndarray) -> np.ndarray:
    """(T-1, n_controlled) the analytic commands of ``trajectory`` for the ESN's DOFs
    (torque body: the normalized inverse-dynamics torques)."""
    if cfg.actuation == "torque":
        return torque.true_torques(cfg.dof, trajectory)
    from skinny_mj.ideal import true_commands

    commands = true_commands(trajectory.angles, max_speed_rad_s, trajectory.dt)
    dofs = controlled_dofs(cfg)
    return commands if dofs is None else commands[:, dofs]


def arm_forward_models(cfg: TrainConfig, rngs: Sequence[np.random.Generator]):
    """Paper B's per-arm forward models (:class:`controllers.arm_forward.ArmForwardModels`,
    ``cfg.forward_sharing``): the lagging arm's network from each run's forward stream,
    the leading arm's (shared predictions only) from a child of that stream."""
    from controllers.arm_forward import ArmForwardModels
    from controllers.esn import ESN
    from skinny_mj.bimanual import arm_signals

    lead_side = cfg.leading_arm
    lag_side = "left" if lead_side == "right" else "right"
    lag_sig, lead_sig = (arm_signals(cfg.dof, cfg.signals, s) for s in (lag_side, lead_side))
    n_arm = len(controlled_dofs(cfg))

    def nets(n_sig: int, streams):
        fm_cfg = esn_config(cfg, n_sig + n_arm, n_sig, cfg.forward_reservoir)
        return ESN(fm_cfg, n_runs=len(streams), rngs=streams)

    lag = nets(len(lag_sig), list(rngs))
    lead = nets(len(lead_sig), [g.spawn(1)[0] for g in rngs]) \
        if cfg.forward_sharing == "predictions" else None
    return ArmForwardModels(lag, lead, lag_sig, lead_sig, cfg.forward_sharing)
