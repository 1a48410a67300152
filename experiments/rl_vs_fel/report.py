"""Figures and the comparison table of :mod:`skinny_mj.experiments.rl_vs_fel.study`, from its run
files.

``curves_steps.png`` / ``curves_cpu.png``: one panel per body x movement, the test
position NRMSE (log) against env steps / training CPU time (log; without the test before
training), one line per run
(thin) and the mean over runs per learner (thick; a learner's runs share their test
points), the thresholds dashed. ``comparison.md``: per row the budget, the final error
(mean ± sd over runs), and per threshold how many runs reached it and, over those, the
mean env steps, CPU and wall time of the first test at or below it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from skinny_mj.engine.stats import load_runs
from skinny_mj.io import atomic_write_text
from skinny_mj.plots import pyplot, save_figure

COLOURS = {"fel": "tab:blue", "ppo": "tab:orange", "sac": "tab:green"}
LABELS = {"fel": "ESN + FEL", "ppo": "PPO", "sac": "SAC"}


def _curves(runs: list[dict]) -> dict[str, list[list[dict]]]:
    out: dict[str, list[list[dict]]] = {}
    for r in runs:
        if r["status"] == "ok" and r["metrics"].get("curve"):
            out.setdefault(r["row"], []).append(r["metrics"]["curve"])
    return out


def _xy(curve: list[dict], x: str) -> tuple[np.ndarray, np.ndarray]:
    if x == "cpu_s":  # log axis: the test before training (0 s) is left out
        curve = curve[1:]
    xs = np.array([p[x] for p in curve], float)
    ys = np.array([np.nan if p["position_nrmse"] is None else p["position_nrmse"]
                   for p in curve], float)
    return xs, ys


def curves_png(path: Path, thresholds, rows, curves: dict, x: str) -> Path:
    plt = pyplot()
    bodies = sorted({r.params["actuation"] for r in rows}, reverse=True)
    moves = list(dict.fromkeys(r.params["movement"] for r in rows))
    fig, axes = plt.subplots(len(bodies), len(moves), figsize=(5.2 * len(moves),
                             3.6 * len(bodies)), squeeze=False, sharey=True)
    for i, body in enumerate(bodies):
        for j, mv in enumerate(moves):
            ax = axes[i][j]
            for row in rows:
                p = row.params
                if (p["actuation"], p["movement"]) != (body, mv) or row.row_id not in curves:
                    continue
                colour, runs = COLOURS[p["learner"]], curves[row.row_id]
                for c in runs:
                    ax.plot(*_xy(c, x), color=colour, lw=0.6, alpha=0.45)
                n = min(len(c) for c in runs)
                xs = np.mean([_xy(c[:n], x)[0] for c in runs], axis=0)
                ys = np.nanmean([_xy(c[:n], x)[1] for c in runs], axis=0)
                ax.plot(xs, ys, color=colour, lw=2, marker="o", ms=3,
                        label=f"{LABELS[p['learner']]} ({len(runs)} run{'s' * (len(runs) > 1)})")
            for th in thresholds:
                ax.axhline(th, color="grey", ls="--", lw=0.8)
            ax.set(xscale="linear" if x == "steps" else "log", yscale="log",
                   title=f"{body} body, {mv}",
                   xlabel="env steps" if x == "steps" else "training CPU time (s)")
            if j == 0:
                ax.set_ylabel("test position NRMSE (K = 0)")
            ax.grid(alpha=0.3, which="both")
            if ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=8, loc="lower left")
    return save_figure(fig, path)


def overlay_png(path: Path, thresholds, rows, sources: list[tuple[Path, str]],
                x: str = "steps") -> Path:
    """:func:`curves_png` of ``rows`` with each row's runs taken from its own sweep
    folder, ``sources`` = [(folder, row id)] (e.g. a longer PPO budget run apart)."""
    curves = {row_id: _curves(load_runs(d)).get(row_id, []) for d, row_id in sources}
    shown = [r for r in rows if curves.get(r.row_id)]
    return curves_png(path, thresholds, shown, {k: v for k, v in curves.items() if v}, x)


def _cell(values: list[float]) -> str:
    if not values:
        return "—"
    a = np.asarray(values, float)
    return f"{a.mean():.4f} ± {a.std(ddof=1):.4f}" if a.size > 1 else f"{a[0]:.4f}"


def _reach(ms: list[dict], th: float) -> str:
    hit = [m for m in ms if m.get(f"steps_to_{th:g}") is not None]
    if not hit:
        return f"0/{len(ms)}"
    steps = np.mean([m[f"steps_to_{th:g}"] for m in hit])
    cpu = np.mean([m[f"cpu_to_{th:g}"] for m in hit])
    wall = np.mean([m[f"wall_to_{th:g}"] for m in hit])
    return f"{len(hit)}/{len(ms)}: {steps:,.0f} steps, {cpu:.1f} CPU s, {wall:.1f} s"


def comparison_table(thresholds, rows, runs: list[dict]) -> str:
    head = ["learner", "body", "movement", "env steps (budget)", "final test NRMSE",
            "best test NRMSE"]
    head += [f"reach {th:g}: runs, mean steps, CPU, wall" for th in thresholds]
    head += ["train CPU (s) per run", "train wall (s) per run", "failed / n"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for row in rows:
        recs = [r for r in runs if r["row"] == row.row_id]
        if not recs:
            continue
        ms = [r["metrics"] for r in recs if r["status"] == "ok"]
        final = [m["position_nrmse"] for m in ms if m["position_nrmse"] is not None]
        best = [m["best_nrmse"] for m in ms if m["best_nrmse"] is not None]
        p = row.params
        steps = ms[0]["env_steps"] if ms else "—"
        n_failed = sum(r["status"] == "failed" for r in recs)
        cells = [LABELS[p["learner"]], p["actuation"], p["movement"],
                 f"{steps:,}" if ms else "—", _cell(final), _cell(best)]
        cells += [_reach(ms, th) for th in thresholds]
        cells += [_cell([m["train_cpu_s"] for m in ms]), _cell([m["train_wall_s"] for m in ms]),
                  f"{n_failed} / {sum(r['status'] != 'error' for r in recs)}"]
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "Final: the test after the last env step of the budget; reach: the first "
              "test at or below the threshold (mean over the runs that reached it). CPU "
              "(the run's process) and wall times exclude the tests."]
    return "\n".join(lines)


def report(results, plan, out_dir: Path) -> str:
    """The study's report: learning curves (test NRMSE against env steps and against
    CPU time) and the comparison table (``comparison.md``)."""
    return write_report(Path(out_dir), plan.params["thresholds"], plan.experiment().rows)


def write_report(out_dir: Path, thresholds, rows) -> str:
    """The figures and ``comparison.md`` of the sweep in ``out_dir``: ``rows`` (row_id,
    params with ``learner``, ``actuation``, ``movement``), ``thresholds`` (NRMSE)."""
    runs = load_runs(out_dir)
    curves = _curves(runs)
    lines = []
    if curves:
        for x, name in (("steps", "curves_steps.png"), ("cpu_s", "curves_cpu.png")):
            png = curves_png(out_dir / name, thresholds, rows, curves, x)
            lines.append(f"figure: {png.name}")
    table = comparison_table(thresholds, rows, runs)
    atomic_write_text(out_dir / "comparison.md", table + "\n")
    return "\n".join([*lines, "", table])
