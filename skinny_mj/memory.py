"""How much memory a run's buffers need, against what the machine has free.

A command asks before any work (:func:`check`): a run too big for the machine is refused
with one line (exit 2) naming the parameter that makes it big, the estimate and the
memory available, instead of allocating gigabytes for minutes and ending in a
``MemoryError``. The estimate counts the arrays that grow with a run's size, from the
shapes the training code allocates: the reservoir weights (N x N per network, and the
copies made while drawing and stacking them), the per-step buffers of a cycle (signals,
commands, extended states; x steps x lockstep runs), the readout fit's workspace and
targets, the test cycle and its recording. The process's fixed baseline (Python, MuJoCo,
rerun: about 0.25 GB) is not counted: it is already in use when the available memory is
read.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from skinny_mj.errors import SkinnyInputError
from skinny_mj.training.config import TrueTarget

__all__ = ["Estimate", "available_bytes", "check", "train_estimate", "test_estimate",
           "track_estimate", "generation_estimate", "row_configs", "row_estimate",
           "sweep_estimate", "fmt_bytes"]

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


def fmt_bytes(n: float) -> str:
    """``n`` bytes in the largest binary unit that keeps it >= 1 (``1.5 GiB``)."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(n) < 1024 or unit == "PiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.3g} {unit}" if n >= 1e4 \
                else f"{n:.1f} {unit}"
        n /= 1024
    raise AssertionError("unreachable")


@dataclass(frozen=True)
class Estimate:
    """Bytes a run (or a sweep) needs: ``parts`` (label -> bytes) and, per part, the
    parameter that makes it grow (``causes``: label -> e.g. ``"--reservoir 20000"``)."""

    parts: dict[str, int]
    causes: dict[str, str] = field(default_factory=dict)

    @property
    def total(self) -> int:
        return int(sum(self.parts.values()))

    @property
    def culprit(self) -> str:
        """The parameter behind the largest part."""
        label = max(self.parts, key=lambda k: self.parts[k])
        return self.causes.get(label, label)

    def scaled(self, factor: int, cause: str) -> Estimate:
        """``factor`` copies at once (e.g. parallel workers), ``cause`` added to each."""
        return Estimate({k: v * factor for k, v in self.parts.items()},
                        {k: f"{self.causes.get(k, k)}, {cause}" for k in self.parts})


def available_bytes() -> int | None:
    """Memory this process may still use: ``MemAvailable`` of ``/proc/meminfo`` (or
    psutil's ``available`` off Linux), lowered to a cgroup's headroom (``memory.max``
    less ``memory.current``, cgroup v2) where one is set; None if nothing says."""
    free: int | None = None
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                free = int(line.split()[1]) * 1024
                break
    except (OSError, ValueError, IndexError):
        free = None
    if free is None:
        try:
            import psutil

            free = int(psutil.virtual_memory().available)
        except Exception:  # no psutil, or it cannot read this system
            return None
    try:
        limit = Path("/sys/fs/cgroup/memory.max").read_text().strip()
        used = int(Path("/sys/fs/cgroup/memory.current").read_text().strip())
        if limit != "max":
            free = min(free, max(0, int(limit) - used))
    except (OSError, ValueError):
        pass
    return free


def check(estimate: Estimate, what: str, *, available: int | None = None,
          hint: str = "") -> None:
    """Refuse (:class:`SkinnyInputError`) when ``estimate`` exceeds the memory available.

    ``what`` names the run ("the training"); ``available`` defaults to
    :func:`available_bytes` (unknown: no check)."""
    free = available_bytes() if available is None else available
    if free is None or estimate.total <= free:
        return
    raise SkinnyInputError(
        f"{what} needs about {fmt_bytes(estimate.total)} of memory ({estimate.culprit}), "
        f"more than the {fmt_bytes(free)} available{'; ' + hint if hint else ''}")


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
    n_res, epochs = cfg.esn.n_reservoir, getattr(cfg.rule, "epochs", 0)
    fit = (lay["D"] + lay["n_out"]) * _F8 + 8 * lay["n_out"] * runs * _F8
    if runs > 1:  # pinv of the live runs only copies their states
        fit += lay["D"] * runs * _F8
    if cfg.esn.readout == "ridge":  # (a ridge-select fit needs the ridge readout)
        fit += lay["D"] * _F8
    if _forward_size(cfg):
        fit += (lay["D_fm"] + lay["n_sig"]) * _F8
    if isinstance(cfg.rule, TrueTarget):  # teacher-forced states of every run, then the fit
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


def test_estimate(n_reservoir: int, n_inputs: int, n_outputs: int, dof: int, n_sig: int,
                  steps: int, steps_cause: str) -> Estimate:
    """Bytes ``skinny test`` needs: the saved network (loaded, then cast) and one test
    cycle of ``steps`` steps with its recording."""
    d = n_reservoir + n_inputs + 1
    step = (2 * n_sig + dof + 3 * n_outputs + d) * _F8 + RECORDING_BYTES_PER_STEP
    return Estimate({"reservoir weights": 3 * n_reservoir * (n_reservoir + d) * _F8,
                     "per-step buffers": step * steps},
                    {"reservoir weights": f"the model's reservoir of {n_reservoir} units",
                     "per-step buffers": steps_cause})


def track_estimate(dof: int, n_sig: int, steps: int, steps_cause: str) -> Estimate:
    """Bytes ``skinny track`` needs: its per-step lists, their arrays and the recording."""
    step = TRACK_BYTES_PER_STEP + 2 * (3 * n_sig + 2 * dof) * _F8 + RECORDING_BYTES_PER_STEP
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


# -- sweeps ------------------------------------------------------------------------------
def row_configs(module: Any, experiment: Any, row: Any) -> list[Any]:
    """The TrainConfigs one run of ``row`` trains, as the study says
    (:meth:`skinny_mj.engine.study.Study.train_configs`)."""
    from skinny_mj.training.config import TrainConfig

    fn = getattr(module, "train_configs", None)  # none: a test's stand-in, no estimate
    out = {} if fn is None else fn(experiment.config, row)
    return [c for c in out.values() if isinstance(c, TrainConfig)]


def _steps(cfg: Any, cache: dict) -> tuple[int, str]:
    """One repetition's control steps of ``cfg``'s movement (cached per movement)."""
    mv = cfg.movement
    key = (mv.trajectory, mv.asf, cfg.plant.dof, mv.speed, mv.retarget)
    if key not in cache:
        from skinny_mj.training.parts import load_trajectory

        cache[key] = len(load_trajectory(cfg)[0])
    return cache[key], steps_cause(str(mv.trajectory), cache[key], mv.reps, flag="")


def row_estimate(module: Any, experiment: Any, row: Any, runs: int = 1,
                 cache: dict | None = None) -> Estimate | None:
    """Bytes one batch of ``runs`` lockstep runs of ``row`` needs: the module's own
    ``estimate_bytes(config, row, runs)`` (an :class:`Estimate`; None: not this row),
    else the largest of its TrainConfigs' (see :func:`row_configs`); None when the
    module says nothing of the row."""
    cache = {} if cache is None else cache
    own = getattr(module, "estimate_bytes", None)
    found = None if own is None else own(experiment.config, row, runs)
    if found is not None:
        return found
    ests = [train_estimate(cfg, one * cfg.movement.reps, one, runs, cause)
            for cfg in row_configs(module, experiment, row)
            for one, cause in [_steps(cfg, cache)]]
    return max(ests, key=lambda e: e.total, default=None)


def sweep_estimate(module: Any, experiment: Any, rows: Sequence[Any], runs: int,
                   workers: int, batch: int) -> tuple[Estimate, str] | None:
    """The largest row's estimate (:func:`row_estimate`) x the workers that run at once,
    and that row's id; None when the module says nothing of its rows."""
    cache: dict = {}
    best: tuple[Estimate, str] | None = None
    lockstep = max(1, min(batch, runs)) if experiment.run_batch is not None else 1
    for row in rows:
        est = row_estimate(module, experiment, row, lockstep, cache)
        if est is not None and (best is None or est.total > best[0].total):
            best = (est, row.row_id)
    if best is None:
        return None
    jobs = max(1, min(workers, len(rows) * runs))
    est = best[0] if jobs == 1 else best[0].scaled(jobs, f"x {jobs} workers")
    return est, best[1]


# -- the checks the commands make ------------------------------------------------------------
def check_train(cfg: Any, what: str = "the training") -> None:
    """Refuse a training of ``cfg`` the machine cannot hold (loads one repetition of its
    movement to count the steps)."""
    from skinny_mj.training.parts import load_trajectory

    traj, _ = load_trajectory(cfg)
    one, reps = len(traj), cfg.movement.reps
    check(train_estimate(cfg, one * reps, one, 1, steps_cause(traj.name, one, reps)), what)


def check_test(esn_cfg: Any, dof: int, n_sig: int) -> Any:
    """``check(steps, cause)`` for ``skinny test`` of a network with ``esn_cfg``."""
    def run(steps: int, cause: str) -> None:
        check(test_estimate(esn_cfg.n_reservoir, esn_cfg.n_inputs, esn_cfg.n_outputs, dof,
                            n_sig, steps, cause), "the test",
              hint="use a shorter movement or fewer --reps")
    return run


def check_track(dof: int, n_sig: int) -> Any:
    """``check(steps, cause)`` for ``skinny track``."""
    def run(steps: int, cause: str) -> None:
        check(track_estimate(dof, n_sig, steps, cause), "tracking",
              hint="use a shorter movement or fewer --reps")
    return run


def check_sweep(module: Any, experiment: Any, rows: Any, runs: int | None,
                workers: int | None, scheduler: str | None) -> None:
    """Refuse a sweep whose largest row, times the workers running at once, does not
    fit; on a remote Dask cluster the memory is the cluster's (no check here)."""
    from skinny_mj.engine.experiment import default_batch_size, default_workers, select_rows

    if scheduler is not None and scheduler != "local":
        return
    selected = select_rows(experiment, rows)
    runs = experiment.runs if runs is None else int(runs)
    workers = default_workers(workers)
    found = sweep_estimate(module, experiment, selected, runs, workers,
                           default_batch_size(len(selected), runs, workers))
    if found is not None:
        est, row = found
        check(est, f"the sweep's largest row, {row},",
              hint="use fewer --workers or --runs, or leave that row out with --rows")


def check_export(dof: int, out: Any) -> Any:
    """Check ``skinny trajectory export``'s ``out`` (a writable .npz or .csv), and return
    ``check(steps, cause)`` for its memory: the repeated angles, the resampled and clipped
    copies and the file's text."""
    from skinny_mj.preflight import check_writable_file

    if Path(out).suffix.lower() not in (".npz", ".csv"):
        raise SkinnyInputError("export writes .npz or .csv", path=out)
    check_writable_file(out)

    def run(steps: int, cause: str) -> None:
        check(Estimate({"movement": steps * dof * _F8 * 4 + steps * dof * 25},
                       {"movement": cause}), "the export", hint="use fewer --reps")
    return run


def check_bench(workers: int | None, quick: bool) -> None:
    """``skinny bench``: its fixed workloads are small but for the whole paper-E table
    (not with ``--quick``), a sweep on ``workers`` processes: checked as a sweep is."""
    if quick:
        return
    from skinny_mj.engine import registry

    module = registry.get("paper-e")
    rows = list(getattr(module, "TABLE_1", ())) or None
    check_sweep(module, module.build(), rows, None, workers, None)
