"""The ratio table and figure of :mod:`skinny_mj.experiments.fidelity_e.study`."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from skinny_mj.experiments.fidelity_e.study import THESIS_RATIO

from skinny_mj.io import atomic_write_text


def _stat(results: dict, row_id: str, metric: str) -> tuple[float, float, int, int]:
    """(mean, sd, n ok, n failed) of ``metric`` in row ``row_id`` (nan if absent)."""
    for row in results["rows"]:
        if row["row"] == row_id:
            m = row["metrics"].get(metric)
            if m:
                return m["mean"], m["sd"], m["n"], row["n_failed"]
            return np.nan, np.nan, 0, row["n_failed"]
    return np.nan, np.nan, 0, 0


def _grid(plan) -> tuple[list[str], list[float]]:
    """The movements (in the study's order) and u_error gains the sweep planned."""
    movements = list(dict.fromkeys(r.group for r in plan.rows))
    return movements, sorted({c.method.u_error_gain for c in plan.configs.values()})


def ratios(results: dict, plan) -> list[dict]:
    """One dict per (movement, gain, test noise, metric): exp means and the ratios."""
    out = []
    movements, gains = _grid(plan)
    for m in movements:
        for g in gains:
            for noisy in (False, True):
                for metric in ("position_nrmse", "motor_nrmse"):
                    key = ("noisy_" if noisy else "") + metric
                    e = {x: _stat(results, f"{m}-g{g:g}-e{x}", key) for x in ("1", "2", "5")}
                    if not any(n_ok + n_failed for _, _, n_ok, n_failed in e.values()):
                        continue  # a cell not run (``--rows``): no line of NaNs
                    out.append({"movement": m, "gain": g, "test_noise": noisy,
                                "metric": metric, "exp": e,
                                "ratio_2_5": e["2"][0] / e["5"][0],
                                "ratio_1_5": e["1"][0] / e["5"][0]})
    return out


def write_report(results: dict, out_dir: Path, plan) -> str:
    rows = ratios(results, plan)
    lines = ["| movement | u_error gain | test noise | metric | exp 1 | exp 2 | exp 5 | "
             "exp 2 / exp 5 | thesis |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        cells = [f"{r['exp'][x][0]:.4f} ± {r['exp'][x][1]:.4f} "
                 f"({r['exp'][x][3]} / {r['exp'][x][2] + r['exp'][x][3]} failed)"
                 for x in ("1", "2", "5")]
        lines.append(f"| {r['movement']} | {r['gain']:g} | {'on' if r['test_noise'] else 'off'}"
                     f" | {r['metric'].split('_')[0]} | {' | '.join(cells)} | "
                     f"×{r['ratio_2_5']:.2f} | ×{THESIS_RATIO[r['metric']]:.1f} |")
    text = "\n".join(lines) + "\n\nmean ± sd over the ok runs (failed / n in brackets).\n"
    atomic_write_text(Path(out_dir) / "ratios.md", text)
    _figure(rows, _grid(plan)[0], Path(out_dir) / "fig_ratio.png", THESIS_RATIO)
    return text


def _figure(rows: list[dict], movements: list[str], path: Path, thesis: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax, metric in zip(axes, ("position_nrmse", "motor_nrmse"), strict=True):
        gains = []
        for i, m in enumerate(movements):
            for noisy, style in ((False, "o-"), (True, "s--")):
                cell = [r for r in rows if r["movement"] == m and
                        r["metric"] == metric and r["test_noise"] == noisy
                        and r["ratio_2_5"] is not None and np.isfinite(r["ratio_2_5"])]
                if not cell:
                    continue
                gains += [r["gain"] for r in cell]
                ax.plot([r["gain"] for r in cell], [r["ratio_2_5"] for r in cell], style,
                        color=f"C{i}",
                        label=f"{m}, test noise {'on' if noisy else 'off'}")
        ax.axhline(thesis[metric], color="k", lw=1, ls=":", label="thesis")
        ax.axhline(1.0, color="grey", lw=0.5)
        if gains:  # (a sweep with no exp 2 / exp 5 pair yet has nothing to put on the axis)
            ax.set_xscale("log", base=2)
        ax.set_xlabel("u_error gain")
        ax.set_title(f"exp 2 / exp 5, test {metric.split('_')[0]} NRMSE")
    axes[0].set_ylabel("ratio of means")
    axes[1].legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def report(results: dict, plan, out_dir: Path) -> str:
    """ratios.md (exp 2 / exp 5 and exp 1 / exp 5 per movement, gain, test noise) and
    fig_ratio.png."""
    return write_report(results, Path(out_dir), plan)
