"""How much memory a run's buffers need, against what the machine has free.

A command asks before any work (:func:`skinny_mj.preflight.check`): a run too big for the
machine is refused with one line (exit 2) naming the parameter that makes it big, the
estimate and the memory available, instead of allocating gigabytes for minutes and ending in a
``MemoryError``. The estimate counts the arrays that grow with a run's size, from the
shapes the training code allocates: the reservoir weights (N x N per network, and the
copies made while drawing and stacking them), the per-step buffers of a cycle (signals,
commands, extended states; x steps x lockstep runs), the readout fit's workspace and
targets, the test cycle and its recording. The process's fixed baseline (Python, MuJoCo,
rerun: about 0.25 GB) is not counted: it is already in use when the available memory is
read.
"""

from __future__ import annotations

from typing import Any

from skinny_mj.preflight import Estimate
from skinny_mj.training.config import TrueTarget

__all__ = ["train_estimate", "test_estimate", "track_estimate", "generation_estimate",
           "steps_cause"]

_F8 = 8  # bytes per float64
#: Bytes per step a rerun recording holds while it is written. With it the estimates
#: were checked against peak RSS (``/usr/bin/time -v``, less the same command's on one
#: repetition of YMCA with N = 200): ``skinny test --reps 100`` 3.9 kB/step measured,
#: 4.0 estimated; ``skinny track --reps 100`` 2.9 and 3.5; ``skinny train --epochs 1
#: --cycles 1`` with ``--reps 300`` +257 MB and 378 MB, ``--reservoir 2000`` +102 and
#: 97 MB, ``--reservoir 3000 --reps 12`` +212 and 253 MB.
RECORDING_BYTES_PER_STEP = 2048
#: Bytes per epoch and run of a learning curve once it is Python lists and JSON text
#: (three curves of floats: ~32 bytes per float object and list slot, ~25 per number).
CURVE_BYTES_PER_EPOCH = 200
#: Bytes per step of ``skinny track``'s Python lists (one small array object per
#: signal and step: a NumPy array's header is ~112 bytes).
TRACK_BYTES_PER_STEP = 1024


# -- sizes of the arrays a run allocates ---------------------------------------------------
def _weights(n: int, n_in: int, n_out: int, runs: int) -> tuple[int, int]:
    """One ESN's weights, (kept, while drawing): kept, the (R, N, N) reservoir and the
    small input, feedback and readout matrices; while drawing, per run a uniform N x N,
    its mask and the masked copy beside the runs drawn so far, then the drawn, the
    stacked and the dtype-cast (R, N, N) at once."""
    per_run = n * n * _F8
    small = runs * n * (n_in + 2 * n_out + 1) * _F8
    drawing = max(per_run * 3 + n * n + per_run * (runs - 1), per_run * 3 * runs)
    return per_run * runs + small, drawing + 3 * small


def _layout(cfg: Any) -> dict[str, int]:
    """The signal counts of ``cfg`` (a TrainConfig): n_sig, n_out, n_in, D, D_fm."""
    from skinny_mj.training.parts import network_sizes

    n_sig, n_out, n_in = network_sizes(cfg)
    d_fm = _forward_size(cfg) + n_sig + n_out + 1 if _forward_size(cfg) else 0
    return {"n_sig": n_sig, "n_out": n_out, "n_in": n_in, "D": cfg.esn.n_reservoir + n_in + 1,
            "D_fm": d_fm}


def _forward_size(cfg: Any) -> int:
    """The forward model's reservoir size (0: no forward model)."""
    return getattr(cfg.forward, "reservoir", 0)


def _per_step(cfg: Any, lay: dict[str, int]) -> int:
    """Floats one run's cycle keeps per step: sensed, true signals, angles, u_error,
    commands, ESN outputs, extended states (+ the forward model's, + feed-forward)."""
    floats = 2 * lay["n_sig"] + cfg.plant.dof + 3 * lay["n_out"] + lay["D"]
    if _forward_size(cfg):
        floats += lay["D_fm"] + lay["n_sig"]
    if cfg.torque is not None:
        floats += lay["n_out"]
    return floats


def train_estimate(cfg: Any, steps: int, test_steps: int, runs: int = 1,
                   steps_cause: str = "") -> Estimate:
    """Bytes one ``train_batch(cfg, seeds)`` of ``runs`` seeds needs: ``steps`` control
    steps per training cycle (the movement x its reps), ``test_steps`` in the test."""
    lay = _layout(cfg)
    step = _per_step(cfg, lay) * _F8
    n_res, epochs = cfg.esn.n_reservoir, getattr(cfg.method, "epochs", 0)
    fit = (lay["D"] + lay["n_out"]) * _F8 + 8 * lay["n_out"] * runs * _F8
    if runs > 1:  # pinv of the live runs only copies their states
        fit += lay["D"] * runs * _F8
    if cfg.esn.readout == "ridge":  # (a ridge-select fit needs the ridge readout)
        fit += lay["D"] * _F8
    if _forward_size(cfg):
        fit += (lay["D_fm"] + lay["n_sig"]) * _F8
    if isinstance(cfg.method, TrueTarget):  # teacher-forced states of every run, then the fit
        fit += lay["D"] * runs * _F8
    kept, drawing = _weights(n_res, lay["n_in"], lay["n_out"], runs)
    if _forward_size(cfg):
        fm_kept, fm_drawing = _weights(_forward_size(cfg), lay["n_sig"] + lay["n_out"],
                                       lay["n_sig"], runs)
        kept, drawing = kept + fm_kept, max(drawing, kept + fm_drawing)
    movement = (lay["n_sig"] + 4 * cfg.plant.dof) * _F8
    cause = steps_cause or f"{steps} steps per cycle"
    lockstep = f" x {runs} lockstep runs" if runs > 1 else ""
    parts = {"per-step buffers": step * runs * steps + movement * steps,
             "readout fit": fit * steps,
             "test": (step * runs + RECORDING_BYTES_PER_STEP) * test_steps,
             # per epoch and run: the curves' arrays, then their JSON lists and text
             "learning curve": epochs * (3 * runs * _F8 + runs * CURVE_BYTES_PER_EPOCH)}
    # the weights are drawn before any buffer exists: the peak is the larger of the two
    parts["reservoir weights"] = max(kept, drawing - sum(parts.values()))
    return Estimate(
        parts,
        {"per-step buffers": cause + lockstep, "readout fit": cause + lockstep,
         "reservoir weights": f"--reservoir {n_res}{lockstep}",
         "test": f"{test_steps} test steps{lockstep}",
         "learning curve": f"--epochs {epochs}{lockstep}"})


def test_estimate(n_reservoir: int, n_inputs: int, n_outputs: int, n_dof: int, n_sig: int,
                  steps: int, steps_cause: str) -> Estimate:
    """Bytes ``skinny test`` needs: the saved network (loaded, then cast) and one test
    cycle of ``steps`` steps with its recording."""
    d = n_reservoir + n_inputs + 1
    step = (2 * n_sig + n_dof + 3 * n_outputs + d) * _F8 + RECORDING_BYTES_PER_STEP
    return Estimate({"reservoir weights": 3 * n_reservoir * (n_reservoir + d) * _F8,
                     "per-step buffers": step * steps},
                    {"reservoir weights": f"the model's reservoir of {n_reservoir} units",
                     "per-step buffers": steps_cause})


def track_estimate(n_dof: int, n_sig: int, steps: int, steps_cause: str) -> Estimate:
    """Bytes ``skinny track`` needs: its per-step lists, their arrays and the recording."""
    step = TRACK_BYTES_PER_STEP + 2 * (3 * n_sig + 2 * n_dof) * _F8 + RECORDING_BYTES_PER_STEP
    return Estimate({"per-step buffers": step * steps}, {"per-step buffers": steps_cause})


def generation_estimate(n_res: int, n_in: int, n_out: int, steps: int, free_steps: int,
                        runs: int = 1, rls: bool = False, cycles: int = 1) -> Estimate:
    """Bytes one lockstep batch of ``runs`` ESNs with output feedback and no plant needs
    (:mod:`skinny_mj.controllers.generation`): the weights, the series and inputs of ``steps``
    teacher steps + ``free_steps`` free ones, a teacher-forced pass's outputs and extended
    states (two at once when ``cycles`` > 1: a pass's are made before the last one's are
    freed), the readout's float64 copy and one run's QR of them; ``rls``: FORCE's
    inverse correlation matrix per run and its update's temporaries instead of the fit."""
    d = n_res + n_in + n_out + 1
    kept, drawing = _weights(n_res, n_in, n_out, runs)
    passes = 2 if cycles > 1 else 1
    series = runs * ((steps + free_steps) * n_out + steps * n_in) * _F8
    parts = {"per-step buffers": series + passes * runs * steps * (d + 2 * n_out) * _F8,
             "readout fit": 0 if rls else (runs + 1) * steps * d * _F8,
             "noise": 256 * runs * n_res * _F8,
             "rls": 3 * runs * d * d * _F8 if rls else 0}
    parts["reservoir weights"] = max(kept, drawing - sum(parts.values()))
    lockstep = f" x {runs} lockstep runs" if runs > 1 else ""
    cause = f"{steps} teacher steps{lockstep}"
    return Estimate(parts, {"per-step buffers": cause, "readout fit": cause,
                            "noise": f"reservoir {n_res}{lockstep}",
                            "rls": f"reservoir {n_res}{lockstep} (RLS)",
                            "reservoir weights": f"reservoir {n_res}{lockstep}"})


def steps_cause(movement: str, one_rep: int, reps: int, flag: str = "--reps ") -> str:
    """``--reps 400 x 313 steps of ymca`` (or the movement's steps alone)."""
    if reps > 1:
        return f"{flag}{reps} x {one_rep} steps of {movement}" if flag \
            else f"{reps} repetitions x {one_rep} steps of {movement}"
    return f"{one_rep} steps of {movement}"
