"""What ``figure-eight`` and ``mackey-glass`` share: the rows (ways to fit one ESN with
output feedback), lockstep runs of all seeds, the free-run metrics, the report.

Rows (``method`` in a row's params):

- ``ordinary``: one teacher-forced fit (:func:`skinny_mj.controllers.generation.fit_ordinary`);
- ``new``: paper E's β method, β = 0.1 over 30 cycles (Table 1's 3 per epoch x 10),
  teacher fed back, blended target (:func:`skinny_mj.controllers.generation.fit_beta`);
- ``new-conv``: the β method run to convergence instead of a fixed count: β = 0.1,
  each run stops at the first pass whose output error is not at least 1 % below the
  previous pass's (:data:`MIN_IMPROVEMENT`; cap :data:`MAX_CYCLES`); the cycles it took
  are recorded. With a perfect teacher the fixed 30 cycles leave the readout short by
  (1 − β)^30 = 4 % of the ordinary fit (a generator whose loop gain is 4 % short
  decays), so the fixed count cannot test the method; the thesis states no count for
  generation tasks;
- ``new-blend``: the same as ``new``, the fed-back value the blend of teacher and own output;
- ``force``: FORCE, online RLS with the own output fed back (figure-eight only);
- ``reservoirpy``: reservoirpy 0.4 on the same data (optional extra ``bench``).

A seed gives the series (Mackey-Glass: its own attractor trajectory) and the ESN's
weights and noise: ``np.random.SeedSequence(seed).spawn(2)``. Our rows step all seeds in
lockstep (bit for bit each seed alone); wall time = batch / R.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from skinny_mj.controllers import generation as gen
from skinny_mj.controllers.esn import ESN, ESNConfig
from skinny_mj.experiments.claims import claim_lines

from skinny_mj.engine.stats import load_runs
from skinny_mj.engine.study import Row
from skinny_mj.plots import boxplot_png
from skinny_mj.training.memory import generation_estimate

#: Row order fixes each row's seeds (the engine's per-row seeds): new rows go last.
METHODS = ("ordinary", "new", "new-blend", "force", "reservoirpy", "new-conv")
BETA, CYCLES = 0.1, 30
#: ``new-conv``: stop when a pass's output NRMSE falls by less than this fraction; cap.
MIN_IMPROVEMENT, MAX_CYCLES = 0.01, 400
COLUMNS = {"free_nrmse": "free-run NRMSE", "horizon": "horizon (steps)",
           "stable": "stable", "fit_wall_s": "fit wall (s)"}


def streams(seed: int) -> tuple[np.random.Generator, np.random.Generator]:
    """(data Generator, ESN Generator) of run ``seed``."""
    data, net = np.random.SeedSequence(int(seed)).spawn(2)
    return np.random.default_rng(data), np.random.default_rng(net)


def rows(methods: tuple[str, ...]) -> tuple[Row, ...]:
    """One row per method (its run reads ``params["method"]``)."""
    return tuple(Row(m, params={"method": m}) for m in methods)


def fit_ours(method: str, esn: ESN, inputs: np.ndarray, teacher: np.ndarray,
             washout: int, force_lambda: float) -> np.ndarray:
    """Fit ``esn`` (R runs) the row's way; afterwards the state is at the end of the
    teacher (noise-free re-drive for the batch fits), ready to run free. Returns the
    training passes each run made (R,): 1 for the ordinary fit and FORCE."""
    passes = np.ones(esn.n_runs, int)
    if method == "force":
        gen.fit_force(esn, inputs, teacher, washout, ridge_lambda=force_lambda)
        return passes
    if method == "ordinary":
        gen.fit_ordinary(esn, inputs, teacher, washout)
    elif method == "new-conv":
        curve = gen.fit_beta(esn, inputs, teacher, washout, BETA, MAX_CYCLES,
                             min_improvement=MIN_IMPROVEMENT)
        passes = np.isfinite(curve).sum(axis=1)
    else:
        gen.fit_beta(esn, inputs, teacher, washout, BETA, CYCLES,
                     feedback="blend" if method == "new-blend" else "teacher")
        passes[:] = CYCLES
    esn.reset()
    esn.run(inputs, noise=False, teacher=teacher)
    return passes


def run_ours(method: str, cfg: ESNConfig, seeds: list[int],
             data: Callable[[np.random.Generator], np.ndarray], n_fit: int, washout: int,
             force_lambda: float = 1e-4
             ) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
    """(free run (R, H, n), target (R, H, n), wall per run, training passes (R,)): all
    seeds in lockstep."""
    series = np.stack([data(streams(s)[0]) for s in seeds])  # (R, L, n)
    esn = ESN(cfg, n_runs=len(seeds), rngs=[streams(s)[1] for s in seeds])
    teacher, target = series[:, :n_fit], series[:, n_fit:]
    inputs = np.zeros((len(seeds), n_fit, cfg.n_inputs))
    start = time.perf_counter()
    passes = fit_ours(method, esn, inputs, teacher, washout, force_lambda)
    wall = (time.perf_counter() - start) / len(seeds)
    free = gen.free_run(esn, np.zeros((len(seeds), target.shape[1], cfg.n_inputs)))
    return free, target, wall, passes


def estimate(method: str, cfg: ESNConfig, n_fit: int, n_free: int, runs: int):
    """The memory one batch of ``runs`` seeds of row ``method`` needs
    (:func:`skinny_mj.training.memory.generation_estimate`; reservoirpy's rows run one seed at a
    time, counted as ours)."""
    cycles = {"new": CYCLES, "new-blend": CYCLES, "new-conv": MAX_CYCLES}.get(method, 1)
    return generation_estimate(cfg.n_reservoir, cfg.n_inputs, cfg.n_outputs, n_fit, n_free,
                               1 if method == "reservoirpy" else runs,
                               rls=method == "force", cycles=cycles)


def metrics(free: np.ndarray, target: np.ndarray, period: int, scale: float) -> list[dict]:
    """Per run: NRMSE over the first ``period`` free steps, horizon before the error
    exceeds 0.1 x ``scale`` (the teacher's std), last-period amplitude ratio, stable
    (finite, bounded and that ratio within [0.8, 1.25])."""
    hz = gen.horizon(free, target, 0.1, scale)
    out = []
    for r in range(free.shape[0]):
        f, d = free[r], target[r]
        finite = bool(np.all(np.isfinite(f)))
        err = float(np.sqrt(np.mean((f[:period] - d[:period]) ** 2)) / scale) if finite \
            else None
        amp = float(np.mean(f[-period:].std(axis=0) / d[-period:].std(axis=0))) \
            if finite else None
        out.append({"free_nrmse": err, "horizon": int(hz[r]), "amplitude_ratio": amp,
                    "stable": float(finite and amp is not None and 0.8 <= amp <= 1.25
                                    and float(np.max(np.abs(f))) < 10)})
    return out


def claims_for(kind: str) -> list:
    return [
        (f"{kind}: the new β method runs free longer than the ordinary fit", "mean", "new",
         "horizon", ">", "mean", "ordinary"),
        (f"{kind}: the new β method with blended feedback runs free longer than the ordinary "
         "fit", "mean", "new-blend", "horizon", ">", "mean", "ordinary"),
        (f"{kind}: ours (ordinary) runs free at least as long as reservoirpy", "mean",
         "ordinary", "horizon", ">=", "mean", "reservoirpy"),
        (f"{kind}: the ordinary fit's free-run error is below the new method's", "median",
         "ordinary", "free_nrmse", "<", "median", "new"),
        (f"{kind}: the new β method run to convergence runs free at least as long as the "
         "ordinary fit", "mean", "new-conv", "horizon", ">=", "mean", "ordinary"),
        (f"{kind}: the new β method run to convergence fits in less wall time than the "
         "ordinary fit (the thesis: 'may be faster')", "mean", "new-conv", "fit_wall_s", "<",
         "mean", "ordinary"),
    ]


def report(results, plan, out_dir: Path, kind: str, extra: list[str] | None = None) -> str:
    """Box plots of horizon and free-run NRMSE per row of the sweep's ``plan``, and the
    claims."""
    out_dir = Path(out_dir)
    runs = load_runs(out_dir)
    ids = [r.id for r in plan.rows]
    lines = []
    for metric, label in (("horizon", "free-run horizon (steps)"),
                          ("free_nrmse", "free-run NRMSE")):
        data = {i: [r["metrics"][metric] for r in runs if r["row"] == i
                    and r["status"] == "ok" and r["metrics"].get(metric) is not None]
                for i in ids}
        if any(data.values()):
            png = boxplot_png(out_dir / f"{metric}.png", data, label, title=f"{kind}: {label}")
            lines.append(f"figure: {png.name}")
    lines.append(claim_lines(out_dir, claims_for(kind)))
    return "\n".join(lines + (extra or []))


def unavailable_rows() -> dict[str, str]:
    """The ``reservoirpy`` row needs the optional package (the ``bench`` extra): a
    study's ``unavailable``."""
    import importlib.util

    if importlib.util.find_spec("reservoirpy") is not None:
        return {}
    return {"reservoirpy": "needs reservoirpy: pip install -e '.[bench]'"}
