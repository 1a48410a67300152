"""The parts every run is built from: seed streams, the movement and its full scale, the
plant, the ESN's shape, the true commands. :func:`skinny_mj.training.loop.build_run` assembles
them (and re-exports these names: the training API stays in one place).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from skinny_mj.controllers.arm_forward import ArmForwardModels
from skinny_mj.controllers.esn import ESN
from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.plant.adapters import BatchPlant, EnvPlant
from skinny_mj.plant.bimanual import BimanualPlant, arm_dofs, arm_signals
from skinny_mj.plant.ideal import max_speeds
from skinny_mj.plant.task import load
from skinny_mj.training.actuation import actuation_of
from skinny_mj.training.config import TrainConfig
from skinny_mj.training.feasible import load_movement  # NAME@feasible too, else trajectories'


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
    """The movement of one repetition (at cfg.movement.speed) and its retarget report."""
    mv = cfg.movement
    kw = {} if mv.retarget == "angles" else {"retarget": mv.retarget}  # today's call
    return load_movement(mv.trajectory, cfg.plant.body, asf=mv.asf, speed=mv.speed, **kw)


def full_scale_speeds(cfg: TrainConfig, trajectory) -> np.ndarray:
    """(n_dof,) rad/s: ``movement.full_scale_factor`` (default 2) x the fastest speed per
    DOF of ``trajectory`` (one repetition) or of the movement named by
    ``movement.max_speed_from``,
    so that networks trained on different movements share one command scale (paper C);
    ``movement.full_scale="shared"``: the fastest DOF's for every DOF."""
    mv = cfg.movement
    if mv.max_speed_from is not None:
        trajectory, _ = load_movement(mv.max_speed_from, cfg.plant.body, asf=mv.asf)
    speeds = max_speeds(trajectory.angles, trajectory.dt, speed_factor=mv.full_scale_factor)
    return np.full_like(speeds, speeds.max()) if mv.full_scale == "shared" else speeds


def make_plant(cfg: TrainConfig, trajectory, plant_seeds: Sequence[int],
               max_speed_rad_s: np.ndarray):
    """The plant of ``cfg`` imitating ``trajectory``, one run per plant seed; a body
    driven otherwise than ``cfg.actuation`` says is a :class:`SkinnyInputError`."""
    seeds, plant = [int(s) for s in plant_seeds], cfg.plant
    skinny = body.body_of(plant.body)
    if skinny.actuation != cfg.actuation.kind:
        raise SkinnyInputError(f"plant.body={skinny.name} is driven by {skinny.actuation}, not "
                               f"actuation={cfg.actuation.kind}: set one of them (the other "
                               "follows)")
    common = dict(n_runs=len(seeds), seeds=seeds, sensor_noise=plant.sensor_noise,
                  max_speed_rad_s=max_speed_rad_s)
    if plant.leading_arm is not None:
        return BimanualPlant(skinny, plant.signals, trajectory, plant.leading_arm, **common)
    if plant.backend == "env":
        if len(seeds) != 1:
            raise ValueError("the dm_control path steps one run per environment")
        env = load(skinny, plant.signals, trajectory, sensor_noise=plant.sensor_noise,
                   seed=seeds[0], max_speed_rad_s=max_speed_rad_s)
        return EnvPlant(env)
    return BatchPlant(skinny, plant.signals, trajectory, **common)



def controlled_dofs(cfg: TrainConfig) -> np.ndarray | None:
    """Body DOFs the ESN drives: None for all, paper B's lagging arm's otherwise."""
    if cfg.plant.leading_arm is None:
        return None

    return arm_dofs(cfg.plant.body, lagging_arm(cfg))


def network_sizes(cfg: TrainConfig) -> tuple[int, int, int]:
    """(n_sig, n_out, n_in): the position signals, the inverse ESN's outputs (the DOFs
    it drives) and its inputs (desired and sensed signals, the forward model's
    prediction, the torque loop's velocity inputs)."""
    n_sig = body.body_of(cfg.plant.body).n_signals(cfg.plant.signals)
    dofs = controlled_dofs(cfg)
    n_out = cfg.plant.dof if dofs is None else len(dofs)
    n_in = (n_sig if cfg.inputs == "desired+sensed" else 0) + n_sig \
        + (0 if cfg.forward.kind == "none" else n_sig) + actuation_of(cfg).n_extra_inputs
    return n_sig, n_out, n_in


def lagging_arm(cfg: TrainConfig) -> str:
    """Paper B's arm the ESN drives: the one that is not ``plant.leading_arm``."""
    return "left" if cfg.plant.leading_arm == "right" else "right"


def true_commands_of(cfg: TrainConfig, trajectory, max_speed_rad_s: np.ndarray) -> np.ndarray:
    """(T-1, n_controlled) the analytic commands of ``trajectory`` for the ESN's DOFs
    (torque body: the normalized inverse-dynamics torques)."""
    commands = actuation_of(cfg).true_commands(trajectory, max_speed_rad_s)
    dofs = controlled_dofs(cfg)
    return commands if dofs is None else commands[:, dofs]


def arm_forward_models(cfg: TrainConfig, rngs: Sequence[np.random.Generator]):
    """Paper B's per-arm forward models
    (:class:`skinny_mj.controllers.arm_forward.ArmForwardModels`,
    ``forward.sharing``): the lagging arm's network from each run's forward stream,
    the leading arm's (shared predictions only) from a child of that stream."""
    plant, sharing = cfg.plant, cfg.forward.sharing
    lag_sig, lead_sig = (arm_signals(plant.body, plant.signals, s)
                         for s in (lagging_arm(cfg), plant.leading_arm))
    n_arm = len(controlled_dofs(cfg))

    def nets(n_sig: int, streams):
        fm_cfg = cfg.esn_config(n_sig + n_arm, n_sig, cfg.forward.reservoir)
        return ESN(fm_cfg, n_runs=len(streams), rngs=streams)

    lag = nets(len(lag_sig), list(rngs))
    lead = nets(len(lead_sig), [g.spawn(1)[0] for g in rngs]) \
        if sharing == "predictions" else None
    return ArmForwardModels(lag, lead, lag_sig, lead_sig, sharing)
