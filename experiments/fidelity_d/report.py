"""The stage tables and figures of :mod:`skinny_mj.experiments.fidelity_d.study`."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from skinny_mj.experiments.claims import values
from skinny_mj.experiments.fidelity_d.study import (
    STAGE_2_CELLS,
    THESIS_TRAIN_RANGE,
    cell_id,
    cells,
    grid_of,
    in_thesis_range,
)
from skinny_mj.experiments.paper_d import PAPER_TABLE_1

from skinny_mj.engine.stats import load_runs
from skinny_mj.io import atomic_write_text
from skinny_mj.plots import pyplot

#: Paper D Table 1, TT position test means: the ordering the thesis reports.
ORDER = ("1", "2", "3a", "3b", "4")
#: "3a ≈ 3b ≈ 4": largest / smallest median within this factor (paper_d's "about").
ABOUT = 1.5
#: Train figure's lower edge: medians below it (interpolating fits) drawn on it as ▼.
TRAIN_FLOOR = 1e-4


def _row(results: dict, row_id: str) -> dict | None:
    return next((r for r in results["rows"] if r["row"] == row_id), None)


def _stat(results: dict, row_id: str, metric: str, what: str = "mean") -> float:
    row = _row(results, row_id)
    m = None if row is None else row["metrics"].get(metric)
    return np.nan if not m or m.get(what) is None else float(m[what])


def _failed(results: dict, row_id: str) -> str:
    row = _row(results, row_id)
    return "—" if row is None else f"{row['n_failed']} / {row['n']}"


def ordering(results: dict, cell: str, runs: list[dict] | None = None) -> dict:
    """Medians of the TT position test per exp at ``cell`` and the thesis's ordering
    checks: 1 > 2, 2 > each of 3a, 3b, 4, and 3a ≈ 3b ≈ 4 (max / min <= ABOUT). With the
    run records, ``p``: one-sided Mann–Whitney p of 1 > 2 and of 2 > the worst of 3a, 3b, 4."""
    med = {e: _stat(results, f"{cell}-e{e}", "tt_position_test", "median") for e in ORDER}
    tail = [med[e] for e in ("3a", "3b", "4")]
    ok = all(np.isfinite(v) for v in med.values())
    checks = {"1 > 2": ok and med["1"] > med["2"],
              "2 > 3a, 3b, 4": ok and med["2"] > max(tail),
              "3a ≈ 3b ≈ 4": ok and max(tail) / min(tail) <= ABOUT}
    p: dict[str, float] = {}
    if runs is not None and ok:
        from scipy.stats import mannwhitneyu

        v = {e: values(Path(), f"{cell}-e{e}", "tt_position_test", runs) for e in ORDER}
        worst = max(("3a", "3b", "4"), key=lambda e: med[e])
        p = {"1 > 2": float(mannwhitneyu(v["1"], v["2"], alternative="greater").pvalue),
             "2 > 3a, 3b, 4": float(mannwhitneyu(v["2"], v[worst],
                                                 alternative="greater").pvalue)}
    return {"median": med, "checks": checks, "complete": ok, "p": p}


def stage_1_table(results: dict, cfg) -> str:
    lines = ["| movement | N | input noise | exp 1 pos train | exp 2 pos train | in range | "
             "exp 1 pos test | exp 2 pos test | exp 1 motor test | exp 2 motor test | "
             "failed / n (1; 2) |", "|" + "---|" * 11]
    for m in cfg.movements:
        for n in cfg.reservoirs:
            for s in cfg.input_noises:
                c = cell_id(m, n, s)
                r1, r2 = f"{c}-e1", f"{c}-e2"

                def ms(row_id, metric):
                    mu, sd = _stat(results, row_id, metric), _stat(results, row_id, metric, "sd")
                    return "—" if np.isnan(mu) else f"{mu:.3g} ± {sd:.2g}"
                lines.append(f"| {m} | {n} | {s:g} | {ms(r1, 'tt_position_train')} | "
                             f"{ms(r2, 'tt_position_train')} | "
                             f"{'**yes**' if in_thesis_range(results, c) else 'no'} | "
                             f"{ms(r1, 'tt_position_test')} | {ms(r2, 'tt_position_test')} | "
                             f"{ms(r1, 'tt_motor_test')} | {ms(r2, 'tt_motor_test')} | "
                             f"{_failed(results, r1)}; {_failed(results, r2)} |")
    lo, hi = THESIS_TRAIN_RANGE
    lines.append(f"\nmean ± sd over the ok runs. In range: exp 1's and exp 2's mean TT "
                 f"position train NRMSE both in [{lo}, {hi}]. Thesis (paper D Table 1): "
                 "pos train 0.0033 / 0.0092, pos test 0.300 / 0.186, motor test 0.323 / "
                 "0.099 (exp 1 / exp 2).")
    return "\n".join(lines)


def stage_2_table(results: dict, cells: list[str], runs: list[dict] | None = None) -> str:
    thesis = {e: PAPER_TABLE_1[e] for e in ORDER}
    head = ["cell"] + [f"exp {e}" for e in ORDER] + ["1 > 2", "2 > 3a,3b,4", "3a≈3b≈4"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head),
             "| thesis (mean pos test; motor test) | " + " | ".join(
                 f"{thesis[e][2][0]:.3f}; {thesis[e][3][0]:.3f}" for e in ORDER)
             + " | yes | yes | yes |"]
    for c in cells:
        o = ordering(results, c, runs)
        vals = []
        for e in ORDER:
            rid = f"{c}-e{e}"
            vals.append(f"{o['median'][e]:.3f} ({_stat(results, rid, 'tt_position_test'):.3f}); "
                        f"{_stat(results, rid, 'tt_motor_test', 'median'):.3f} "
                        f"[{_failed(results, rid)}]")
        marks = [("yes" if v else "**no**") + (f" (p {o['p'][k]:.2g})" if k in o["p"] else "")
                 for k, v in o["checks"].items()]
        lines.append(f"| {c} | " + " | ".join(vals) + " | " + " | ".join(marks) + " |")
    lines.append(f"\nours: median TT position test (mean); median motor test [failed / n]. "
                 f"Ordering on the medians of the position test; ≈ = within ×{ABOUT}; p: "
                 "one-sided Mann–Whitney (2 > ...: against the worst of 3a, 3b, 4).")
    return "\n".join(lines)


def write_report(results: dict, out_dir: Path, cfg) -> str:
    """Write stages.md and the two figures of the grid ``cfg`` (a fidelity_d.Grid)."""
    out_dir = Path(out_dir)
    picked = [c for c in cells(cfg) if in_thesis_range(results, c)]
    text = ["## Stage 1 (exps 1, 2)", "", stage_1_table(results, cfg), "",
            f"Cells in range (stage 2's criterion): {', '.join(picked) or 'none'}."]
    if list(STAGE_2_CELLS) and sorted(STAGE_2_CELLS) != sorted(picked):
        text.append(f"NOTE: STAGE_2_CELLS ({', '.join(STAGE_2_CELLS)}) differs from the cells "
                    "this folder's stage 1 puts in range.")
    ran = [c for c in cells(cfg)
           if all(_row(results, f"{c}-e{e}") and _row(results, f"{c}-e{e}")["n"]
                  for e in ORDER)]
    if ran:
        text += ["", "## Stage 2 (all TT exps)", "",
                 stage_2_table(results, ran, load_runs(out_dir))]
    body = "\n".join(text) + "\n"
    atomic_write_text(out_dir / "stages.md", body)
    for metric, name in (("tt_position_train", "fig_train_error.png"),
                         ("tt_position_test", "fig_test_error.png")):
        _figure(results, cfg, metric, out_dir / name)
    return body


def _figure(results: dict, cfg, metric: str, path: Path) -> None:
    plt = pyplot()
    train = metric.endswith("train")
    fig, axes = plt.subplots(len(cfg.movements), len(cfg.reservoirs), squeeze=False,
                             figsize=(3.6 * len(cfg.reservoirs), 3.0 * len(cfg.movements)),
                             sharex=True, sharey=True)
    k = 0 if train else 2
    lo, hi = THESIS_TRAIN_RANGE if train else \
        (min(PAPER_TABLE_1[e][k][0] for e in ORDER), max(PAPER_TABLE_1[e][k][0] for e in ORDER))
    for ax_row, m in zip(axes, cfg.movements, strict=True):
        for ax, n in zip(ax_row, cfg.reservoirs, strict=True):
            ax.axhspan(lo, hi, color="grey", alpha=0.25, lw=0, label="thesis's range")
            for i, e in enumerate(ORDER):
                rids = [f"{cell_id(m, n, s)}-e{e}" for s in cfg.input_noises]
                med = np.array([_stat(results, r, metric, "median") for r in rids])
                if np.all(np.isnan(med)):
                    continue
                lo_q = np.array([_stat(results, r, metric, "min") for r in rids])
                hi_q = np.array([_stat(results, r, metric, "max") for r in rids])
                x = np.asarray(cfg.input_noises) + 0.0015 * (i - 2)
                if train:  # an interpolating fit (~1e-12) would squash the scale: mark it
                    low = med < TRAIN_FLOOR
                    med, lo_q, hi_q = (np.maximum(v, TRAIN_FLOOR) for v in (med, lo_q, hi_q))
                    ax.plot(x[low], med[low], "v", ms=7, color=f"C{i}")
                ax.errorbar(x, med, yerr=[med - lo_q, hi_q - med], fmt="o-", ms=3, lw=1,
                            capsize=2, color=f"C{i}", label=f"exp {e}")
                if not train:
                    ax.axhline(PAPER_TABLE_1[e][k][0], color=f"C{i}", lw=0.8, ls=":")
            ax.set_title(f"{m}, N = {n}", fontsize=9)
            ax.grid(alpha=0.3)
            if train:
                ax.set_yscale("log")
                ax.set_ylim(TRAIN_FLOOR / 1.3, 2e-2)
    for ax in axes[-1]:
        ax.set_xlabel("TT input noise SD")
    what = "TT position train" if train else "TT closed-loop position test"
    for ax in axes[:, 0]:
        ax.set_ylabel(f"{what} NRMSE")
    axes[0, -1].legend(fontsize=7)
    note = "▼: median below 1e-4 (drawn at 1e-4)" if train else \
        "dotted: the thesis's mean per exp"
    fig.suptitle(f"Paper D, {what} NRMSE: median, min–max over seeds; grey: the thesis's "
                 f"range; {note}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def report(results: dict, plan, out_dir: Path) -> str:
    """stage1.md / stage2.md tables and fig_train_error.png / fig_test_error.png."""
    return write_report(results, Path(out_dir), grid_of(plan))
