"""Paper A glue: FEL on the MuJoCo plant with delayed sensory input and a forward model.

Architectures (paper A §3.3–3.4, Fig. 3):

- ``inverse``: inverse ESN only; input [d(t+1); s(t - delay)].
- ``parallel``: + forward ESN trained alongside the inverse model on every learning
  cycle from a zero readout; the inverse model's input is [d(t+1); s(t - delay); p(t)].
- ``serial``: forward ESN pre-trained on the desired movement, then frozen.
- ``hybrid``: pre-trained, then trained on like ``parallel``.

The feedback controller always sees the undelayed s(t) (paper A §3.3); its gain is
fixed at K = 0.65 "throughout the experiments" (thesis §3.3.1). The forward model
predicts s(t+1) from [s(t - delay); command(t)] (paper A §3.3, "based on the motor
command and the sensed, delayed state"). Pre-training (paper A §3.4): "the forward
model was trained to predict the next state in the sequence of desired states given
the correct motor command and the delayed and noisy sensory signal", i.e. inputs
[d(t - delay) + noise; c*(t)] with c* the analytic commands, target d(t+1).

Metrics, all from the evaluation cycle of the LAST training epoch (feedback ON,
K = 0.65, reservoir noise off): the thesis measures the performance error as "the
difference between the desired and actual state averaged over all time steps in the
last epoch" (thesis §3.3.1; paper A §4: "after the last epoch of training", Fig. 5
"the performance error in the last epoch"), the online correction ratio over the same
cycle, and the prediction error "done by the forward model during the last epoch".
A closed-loop test with K = 0 is recorded as an extra, not as the paper's metric.

Seeds: run ``seed`` spawns three streams ``SeedSequence(seed).spawn(3)``: the inverse
ESN (as :func:`skinny_mj.training.run_streams`), the plant's sensor noise, and the
forward ESN + its pre-training noise.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from controllers import fel
from controllers.esn import ESN, ESNConfig
from controllers.forward_model import ForwardModel, rollout_prediction_error
from controllers.metrics import nrmse

ARCHITECTURES = ("inverse", "parallel", "serial", "hybrid")


@dataclass(frozen=True)
class DelayConfig:
    """One paper-A run's fixed parameters (paper A §3.3–3.5; thesis §3.3.1).

    Unstated in the paper and chosen here: the training schedule follows paper C
    (same year, same inverse network): epochs of 7 cycles (1 washout, 5 learning,
    1 evaluation), target u(t) + u_error(t+1) (the original method, β = 1);
    ``epochs`` (paper A: "all experiments were run the same number of epochs").
    """

    dof: int = 4
    signals: str = "joint"
    trajectory: str = "ymca"
    asf: str | None = None
    inverse_reservoir: int = 1000
    forward_reservoir: int = 100
    spectral_radius: float = 0.1
    noise: float = 0.2
    gain: float = 0.65
    sensor_noise: float = 0.01
    epochs: int = 10
    learning_cycles: int = 5
    method: str = "original"
    beta: float = 1.0
    readout: str = "pinv"
    ridge: float = 1e-6
    forward_readout: str = "pinv"
    forward_ridge: float = 1e-6

    def fel_config(self, delay: int) -> fel.FELConfig:
        return fel.FELConfig(method=self.method, beta=self.beta,
                             learning_cycles=self.learning_cycles, epochs=self.epochs,
                             gain_schedule="fixed", gain_value=self.gain, delay_steps=delay)


def delay_streams(seed: int) -> tuple[np.random.Generator, int, np.random.Generator]:
    """Inverse ESN Generator, plant sensor-noise seed, forward ESN Generator."""
    inv_ss, plant_ss, fm_ss = np.random.SeedSequence(seed).spawn(3)
    return (np.random.default_rng(inv_ss), int(plant_ss.generate_state(1, np.uint64)[0]),
            np.random.default_rng(fm_ss))


def pretrain_forward(fm: ForwardModel, desired: np.ndarray, true_commands: np.ndarray,
                     delay: int, sensor_noise: float, rng: np.random.Generator) -> np.ndarray:
    """Pre-train ``fm`` on the desired movement (paper A §3.4).

    Parameters
    ----------
    desired : (T, n_sig) desired positions, normalized.
    true_commands : (T-1, n_dof) analytic commands in [-1, 1].
    delay : steps by which the sensed input lags.
    sensor_noise : std of the Gaussian noise on the sensed input (normalized units).

    Returns
    -------
    (R,) prediction NRMSE of the fitted readout on the fitting pass against d(t+1)
    ("the prediction error in the last run of pre-training").
    """
    n_runs = fm.esn.n_runs
    noisy = desired[None] + sensor_noise * rng.standard_normal((n_runs, *desired.shape))
    inputs = np.stack([fm.sequence_inputs(noisy[r], true_commands, delay)
                       for r in range(n_runs)])
    fm.esn.reset()
    fm.esn.run(inputs, noise=True)  # washout pass
    _, states = fm.esn.run(inputs, noise=True)
    targets = np.broadcast_to(desired[1:], (n_runs, *desired[1:].shape))
    fm.esn.fit(states, targets)
    return nrmse(fm.esn.readout(states), desired[1:])


def mean_abs_error(true_signals: np.ndarray, desired: np.ndarray) -> np.ndarray:
    """Mean |desired - actual| as a fraction of the signal range 2, (R,)."""
    return np.abs(true_signals - desired).mean(axis=(-2, -1)) / 2.0


def feedback_share(ro: fel.Rollout) -> np.ndarray:
    """The feedback controller's share of the command, in [0, 1], (R,):
    mean |u_feedback| / (mean |u_feedback| + mean |y_ESN|), with u_feedback = command -
    y_ESN (the clipped K u_error). Unlike ``Rollout.correction_ratio`` (|u_feedback| /
    |u|, which exceeds 1 when the inverse model and the feedback controller push against
    each other) it reads directly as "the feedback controller's contribution in percent"."""
    fb = np.abs(ro.commands - ro.y_esn).mean(axis=(1, 2))
    ff = np.abs(ro.y_esn).mean(axis=(1, 2))
    return fb / np.maximum(fb + ff, 1e-12)


def run_delay(cfg: DelayConfig, architecture: str, delay: int, seed: int) -> dict[str, Any]:
    """Train and measure one (architecture, delay, seed) run on the MuJoCo plant.

    Returns a JSON-ready dict: ``performance_nrmse`` / ``performance_mae`` (last
    epoch's evaluation cycle, K on), ``correction_ratio``, ``prediction_nrmse`` (forward
    architectures), ``pretrain_prediction_nrmse`` (serial/hybrid), ``test_*`` (K = 0),
    ``curve_*`` per epoch, ``failed``/``fail_reason``.
    """
    from skinny_mj.ideal import max_speeds, true_commands
    from skinny_mj.training import make_plant
    from skinny_mj.trajectories import load_movement

    if architecture not in ARCHITECTURES:
        raise ValueError(f"architecture must be one of {ARCHITECTURES}, got {architecture!r}")
    start = time.perf_counter()
    trajectory, _ = load_movement(cfg.trajectory, cfg.dof, asf=cfg.asf)
    max_speed = max_speeds(trajectory.angles, trajectory.dt)  # 2x the fastest, per DOF
    desired = trajectory.position_signals(cfg.signals)
    commands = true_commands(trajectory.angles, max_speed, trajectory.dt)
    n_sig = desired.shape[1]
    inv_rng, plant_seed, fm_rng = delay_streams(seed)
    forward = None
    out: dict[str, Any] = {}
    if architecture != "inverse":
        fm_cfg = ESNConfig(n_inputs=n_sig + cfg.dof, n_outputs=n_sig,
                           n_reservoir=cfg.forward_reservoir,
                           spectral_radius=cfg.spectral_radius, noise_level=cfg.noise,
                           readout=cfg.forward_readout, ridge_lambda=cfg.forward_ridge)
        mode = "parallel" if architecture == "parallel" else architecture
        forward = ForwardModel(ESN(fm_cfg, rngs=[fm_rng]), mode)
        if architecture in ("serial", "hybrid"):
            err = pretrain_forward(forward, desired, commands, delay, cfg.sensor_noise, fm_rng)
            out["pretrain_prediction_nrmse"] = float(err[0])
    n_in = (2 if forward is None else 3) * n_sig
    inv_cfg = ESNConfig(n_inputs=n_in, n_outputs=cfg.dof, n_reservoir=cfg.inverse_reservoir,
                        spectral_radius=cfg.spectral_radius, noise_level=cfg.noise,
                        readout=cfg.readout, ridge_lambda=cfg.ridge)
    esn = ESN(inv_cfg, rngs=[inv_rng])
    plant = make_plant(cfg.dof, cfg.signals, trajectory, plant_seed, cfg.sensor_noise,
                       max_speed)
    result = fel.train(esn, plant, desired, cfg.fel_config(delay), true_commands=commands,
                       forward=forward)
    ro = result.last_rollout
    failed = bool(result.failed[0])
    out.update(failed=failed, fail_reason=result.fail_reason[0],
               curve_performance_nrmse=_clean(result.position_nrmse[0]))
    if not failed:
        out.update(
            performance_nrmse=float(result.position_nrmse[0, -1]),
            performance_mae=float(mean_abs_error(ro.true_signals, desired)[0]),
            correction_ratio=float(ro.correction_ratio[0]),
            feedback_share=float(feedback_share(ro)[0]),
            motor_nrmse=float(result.motor_nrmse[0, -1]),
        )
        if forward is not None:
            out["prediction_nrmse"] = float(rollout_prediction_error(ro)[0])
        ev = fel.evaluate(esn, plant, desired, commands, delay_steps=delay, forward=forward)
        out.update(test_position_nrmse=_num(ev.position_nrmse[0]),
                   test_motor_nrmse=_num(ev.motor_nrmse[0]))
    out.update(architecture=architecture, delay=delay, seed=seed, config=asdict(cfg),
               wall_s=time.perf_counter() - start)
    return out


def _num(v: float) -> float | None:
    return float(v) if np.isfinite(v) else None


def _clean(a: np.ndarray) -> list[float | None]:
    return [_num(v) for v in a]
