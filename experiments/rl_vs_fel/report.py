"""Figures and tables of :mod:`skinny_mj.experiments.rl_vs_fel.study`, made from its
curves' data files (:mod:`skinny_mj.experiments.rl_vs_fel.data`), never by training.

- ``rl-vs-fel_steps.png`` / ``rl-vs-fel_cpu.png``: one column per score (``ymca``,
  ``clips@0.18``, ``clips@1``), the test position NRMSE (above) and RMS joint error in
  degrees (below), log, against env steps / training CPU seconds (log), one thin line
  per curve and seed, a thick line per learner (the mean over its seeds at their shared
  test points), the thresholds dotted.
- the reach table: per learner and score, the curves' final NRMSE and RMS joint error,
  and per threshold how many seeds reached it, the mean env steps and CPU seconds of the
  first test at or below it (or "not reached by N");
- the ratio table: per score and threshold, ESN + FEL against the best RL learner
  (the fewest mean env steps among those whose every seed reached it).

After a sweep, :func:`report` exports its curves into ``<out>/data`` and writes these
there. The results page's figures and tables (between :data:`BEGIN` and :data:`END`)
regenerate from the committed data files::

    python -m skinny_mj.experiments.rl_vs_fel.report docs/results/rl-vs-fel-data \\
        --out docs/results --page docs/results/rl-vs-fel.md
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from skinny_mj.experiments.rl_vs_fel import data as data_mod
from skinny_mj.experiments.rl_vs_fel.runs import mean_error

from skinny_mj.errors import SkinnyInputError
from skinny_mj.io import atomic_write_text, read_page_with_section, write_page_section
from skinny_mj.plots import pyplot, save_figure

LEARNERS = {"fel": ("ESN + FEL", "tab:blue", "-"), "fel-k1": ("ESN + FEL, K = 1", "tab:blue",
                                                               "--"),
            "ppo": ("PPO", "tab:orange", "-"), "ppo-res": ("residual PPO", "tab:orange", "--"),
            "sac": ("SAC", "tab:green", "-"), "sac-res": ("residual SAC", "tab:green", "--")}
THRESHOLDS = (0.05, 0.02, 0.01)
#: The markers around the tables in the results page (``--page``).
BEGIN, END = "<!-- rl-vs-fel tables: begin -->", "<!-- rl-vs-fel tables: end -->"


def series(records: list[dict]) -> dict[tuple[str, str], list[list[dict]]]:
    """(learner, score) -> each seed's curve as [{"steps", "cpu_s", "nrmse", "deg"}];
    ESN + FEL's test with the teacher on is the learner ``fel-k1``. Search rows are
    left out."""
    out: dict[tuple[str, str], list[list[dict]]] = {}
    for rec in records:
        if rec["curve"].startswith("search-"):
            continue
        kinds = [(rec["learner"], "tests")]
        if rec["learner"] == "fel":
            kinds.append(("fel-k1", "tests_k1"))
        for learner, tests in kinds:
            for score, cols in rec["scores"].items():
                out.setdefault((learner, score), []).append([
                    {"steps": p["steps"], "cpu_s": p["cpu_s"],
                     "nrmse": mean_error(p, cols, tests=tests),
                     "deg": mean_error(p, cols, "rms_error_deg", tests)}
                    for p in rec["points"] if tests in p])
    return out


def _mean_curve(curves: list[list[dict]], x: str, y: str) -> tuple[np.ndarray, np.ndarray]:
    """Mean x and y over seeds at their shared test points (the shortest curve's)."""
    n = min(len(c) for c in curves)
    xs = np.mean([[p[x] for p in c[:n]] for c in curves], axis=0)
    ys = np.array([[np.nan if p[y] is None else p[y] for p in c[:n]] for c in curves])
    return xs, np.nanmean(ys, axis=0) if np.isfinite(ys).any() else ys[0]


#: The figures' rows: the curve's key, the axis label, the thresholds drawn
ROWS = (("nrmse", "test position NRMSE", THRESHOLDS), ("deg", "RMS joint error (°)", ()))


#: The CPU axis's left end, s (ESN + FEL's first epoch on YMCA takes about 0.3 s).
CPU_AXIS_FROM = 0.1


def curves_png(path: Path, found: dict, x: str) -> Path | None:
    """The figure of every score's curves (NRMSE above, RMS joint error in degrees below)
    against ``x`` ("steps" or "cpu_s")."""
    scores = list(dict.fromkeys(s for _, s in found))
    if not scores:
        return None
    plt = pyplot()
    fig, axes = plt.subplots(len(ROWS), len(scores), figsize=(5.0 * len(scores), 7.2),
                             squeeze=False, sharey="row", sharex="col")
    for (y, ylabel, lines), ax_row in zip(ROWS, axes, strict=True):
        for ax, score in zip(ax_row, scores, strict=True):
            for learner, (label, colour, style) in LEARNERS.items():
                curves = found.get((learner, score))
                if not curves:
                    continue
                for c in curves:
                    pts = [p for p in c if p[x] > 0]  # a log axis: the test before training
                    ax.plot([p[x] for p in pts], [np.nan if p[y] is None else p[y]
                                                  for p in pts], color=colour, ls=style,
                            lw=0.5, alpha=0.4)
                xs, ys = _mean_curve(curves, x, y)
                keep = xs > 0
                ax.plot(xs[keep], ys[keep], color=colour, ls=style, lw=2, marker="o", ms=2.5,
                        label=f"{label} ({len(curves)} seed{'s' * (len(curves) > 1)})")
            for th in lines:
                ax.axhline(th, color="grey", ls=":", lw=0.8)
            ax.set(xscale="log", yscale="log", title=score if y == "nrmse" else "")
            if x == "cpu_s":  # tests before any learning cost microseconds: off the axis
                ax.set_xlim(left=CPU_AXIS_FROM)
            ax.grid(alpha=0.3, which="both")
        ax_row[0].set_ylabel(ylabel)
    for ax in axes[-1]:
        ax.set_xlabel("env steps" if x == "steps" else "training CPU time (s)")
    legend = {}  # one legend below the panels, off every curve: label -> line
    for ax in axes[0]:
        for line, label in zip(*ax.get_legend_handles_labels(), strict=True):
            legend.setdefault(label, line)
    fig.legend(legend.values(), legend.keys(), loc="lower center", ncol=len(legend),
               fontsize=8, frameon=False)
    return save_figure(fig, path, rect=(0, 0.05, 1, 1))


def _first(curve: list[dict], th: float) -> dict | None:
    return next((p for p in curve if p["nrmse"] is not None and p["nrmse"] <= th), None)


def reach(curves: list[list[dict]], th: float) -> tuple[int, float | None, float | None]:
    """(seeds that reached ``th``, their mean env steps and CPU s to the first test
    at or below it)."""
    hits = [h for h in (_first(c, th) for c in curves) if h is not None]
    if not hits:
        return 0, None, None
    return len(hits), float(np.mean([h["steps"] for h in hits])), \
        float(np.mean([h["cpu_s"] for h in hits]))


def _cell(values: Sequence[float | None], fmt: str = ".4f") -> str:
    v = np.array([x for x in values if x is not None], float)
    if not v.size:
        return "—"
    return f"{v.mean():{fmt}} ± {v.std(ddof=1):{fmt}}" if v.size > 1 else f"{v[0]:{fmt}}"


def reach_table(found: dict) -> str:
    head = ["score", "learner", "seeds", "env steps", "final NRMSE", "final RMS error (°)"]
    head += [f"to {th:g}: seeds, env steps, CPU s" for th in THRESHOLDS]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for (learner, score), curves in sorted(found.items(), key=lambda kv: (
            kv[0][1], list(LEARNERS).index(kv[0][0]))):
        budget = max(c[-1]["steps"] for c in curves)
        cells = [score, LEARNERS[learner][0], str(len(curves)), f"{budget:,}",
                 _cell([c[-1]["nrmse"] for c in curves]),
                 _cell([c[-1]["deg"] for c in curves], ".2f")]
        for th in THRESHOLDS:
            n, steps, cpu = reach(curves, th)
            cells.append(f"not reached by {budget:,}" if n == 0 else
                         f"{n}/{len(curves)}, {steps:,.0f}, {cpu:,.1f}")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def ratio_table(found: dict) -> str:
    """ESN + FEL (K = 0) against the best RL learner per score and threshold: the one
    with the fewest env steps to it in every seed, and the one with the least CPU."""
    lines = ["| score | threshold | ESN + FEL: env steps, CPU s | best RL: learner, env "
             "steps, CPU s | RL / FEL: env steps, CPU |", "|---|---|---|---|---|"]
    for score in dict.fromkeys(s for _, s in found):
        fel = found.get(("fel", score))
        rl = {lr: c for (lr, s), c in found.items() if s == score and not lr.startswith("fel")}
        for th in THRESHOLDS:
            f = reach(fel, th) if fel else (0, None, None)
            reached = {lr: reach(c, th) for lr, c in rl.items()}  # lr -> (seeds, steps, cpu)
            every = [(lr, *r) for lr, r in reached.items() if r[0] == len(rl[lr])]
            best = min(every, key=lambda t: t[2], default=None)  # the fewest env steps
            quick = min(every, key=lambda t: t[3], default=None)  # the least CPU
            fel_cell = "—" if not fel else (
                f"{f[1]:,.0f}, {f[2]:,.1f}" if f[0] == len(fel) else
                f"{f[0]}/{len(fel)} seeds")
            some = [f"{LEARNERS[lr][0]} {r[0]}/{len(rl[lr])}" for lr, r in reached.items()
                    if 0 < r[0] < len(rl[lr])]
            if best is not None:
                rl_cell = f"{LEARNERS[best[0]][0]}, {best[2]:,.0f}, {best[3]:,.1f}"
                if quick[0] != best[0]:
                    rl_cell += (f"; least CPU: {LEARNERS[quick[0]][0]}, {quick[2]:,.0f}, "
                                f"{quick[3]:,.1f}")
            else:
                rl_cell = f"not in every seed ({', '.join(some)} seeds)" if some else \
                    "none reached"
            fel_all = bool(fel) and f[0] == len(fel)
            if best is not None and fel_all:
                ratio = f"{best[2] / f[1]:,.1f}, {quick[3] / f[2]:,.1f}"
            elif fel_all and rl:  # a bound: no RL curve got there within its budget
                most = max(max(c[-1]["steps"] for c in curves) for curves in rl.values())
                ratio = f"> {most / f[1]:,.1f} (no RL by {most:,})"
            elif best is not None and fel:  # a bound: FEL did not get there in its budget
                budget = max(c[-1]["steps"] for c in fel)
                ratio = f"< {best[2] / budget:,.2f} (no FEL by {budget:,})"
            else:
                ratio = "—"
            lines.append(f"| {score} | {th:g} | {fel_cell} | {rl_cell} | {ratio} |")
    return "\n".join(lines)


def tables(found: dict) -> str:
    """The reach and ratio tables of ``found`` (:func:`series`), one blank line apart."""
    return "\n\n".join([reach_table(found), ratio_table(found)])


def page_tables(text: str) -> str:
    """The results page's section: the tables ``text`` (:func:`tables`) between
    :data:`BEGIN` and :data:`END`."""
    return f"{BEGIN}\n\n{text}\n\n{END}\n"


def write(records: list[dict], out: Path, prefix: str = "rl-vs-fel", *,
          page: Path | None = None) -> str:
    """The figures (``<prefix>_steps.png``, ``<prefix>_cpu.png``) of ``records`` in
    ``out``, and their tables in ``<prefix>_tables.md`` there or, given ``page``, in that
    page's section (:func:`page_tables`); returns the tables' text."""
    if page is not None:  # refused before the figures are drawn, not after
        read_page_with_section(page, BEGIN, END)
    out.mkdir(parents=True, exist_ok=True)
    found = series(records)
    if not found:
        return "no curves yet"
    lines = []
    for x, name in (("steps", "steps"), ("cpu_s", "cpu")):
        png = curves_png(out / f"{prefix}_{name}.png", found, x)
        if png is not None:
            lines.append(f"figure: {png.name}")
    text = tables(found)
    if page is None:
        atomic_write_text(out / f"{prefix}_tables.md", text + "\n")
    else:
        write_page_section(page, BEGIN, END, page_tables(text))
        lines.append(f"tables: {page}")
    return "\n".join([*lines, "", text])


def report(results, plan, out_dir: Path) -> str:
    """After a sweep: its curves exported to ``<out_dir>/data``, the figures and tables
    beside them."""
    out_dir = Path(out_dir)
    data_mod.export([out_dir], out_dir / "data")
    return write(data_mod.load(out_dir / "data"), out_dir)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        prog="python -m skinny_mj.experiments.rl_vs_fel.report",
        description="The rl-vs-fel figures and tables from its curves' data files.")
    parser.add_argument("data", type=Path, nargs="?", default=data_mod.DEFAULT_DATA)
    parser.add_argument("--out", type=Path, default=Path("docs/results"),
                        help="the figures' folder (default docs/results)")
    parser.add_argument("--page", type=Path, default=None,
                        help=f"write the tables into this page, between its lines {BEGIN} "
                             f"and {END} (default: <out>/rl-vs-fel_tables.md)")
    args = parser.parse_args(argv)
    try:
        print(write(data_mod.load(args.data), args.out, page=args.page))
    except SkinnyInputError as exc:
        parser.exit(2, f"{parser.prog}: {exc}\n")


if __name__ == "__main__":
    main()
