"""How much memory a sweep needs: its largest row's estimate (a study's own, else its
trainings' :func:`skinny_mj.training.memory.train_estimate`) times the workers that run
at once."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from skinny_mj.preflight import Estimate
from skinny_mj.training.config import TrainConfig
from skinny_mj.training.memory import steps_cause, train_estimate

__all__ = ["row_configs", "row_estimate", "sweep_estimate"]


def row_configs(module: Any, experiment: Any, row: Any) -> list[Any]:
    """The TrainConfigs one run of ``row`` trains, as the study says
    (:meth:`skinny_mj.engine.study.Study.train_configs`)."""
    fn = getattr(module, "train_configs", None)  # none: a test's stand-in, no estimate
    out = {} if fn is None else fn(experiment, row)
    return [c for c in out.values() if isinstance(c, TrainConfig)]


def _steps(cfg: Any, cache: dict) -> tuple[int, str]:
    """One repetition's control steps of ``cfg``'s movement (cached per movement)."""
    mv = cfg.movement
    key = (mv.trajectory, mv.asf, cfg.plant.body, mv.speed, mv.retarget)
    if key not in cache:
        from skinny_mj.training.parts import load_trajectory

        cache[key] = len(load_trajectory(cfg)[0])
    return cache[key], steps_cause(str(mv.trajectory), cache[key], mv.reps, flag="")


def row_estimate(module: Any, experiment: Any, row: Any, runs: int = 1,
                 cache: dict | None = None) -> Estimate | None:
    """Bytes one batch of ``runs`` lockstep runs of ``row`` needs: the module's own
    ``estimate_bytes(experiment, row, runs)`` (an :class:`Estimate`; None: not this row),
    else the largest of its TrainConfigs' (see :func:`row_configs`); None when the
    module says nothing of the row."""
    cache = {} if cache is None else cache
    own = getattr(module, "estimate_bytes", None)
    found = None if own is None else own(experiment, row, runs)
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
    lockstep = max(1, min(batch, runs))
    for row in rows:
        est = row_estimate(module, experiment, row, lockstep, cache)
        if est is not None and (best is None or est.total > best[0].total):
            best = (est, row.id)
    if best is None:
        return None
    jobs = max(1, min(workers, len(rows) * runs))
    est = best[0] if jobs == 1 else best[0].scaled(jobs, f"x {jobs} workers")
    return est, best[1]
