"""Figures and comparisons of :mod:`skinny_mj.experiments.bimanual_delay.study` from its run files.

- ``delay_sweep.png``: per pattern (rows of panels) the lagging arm's position NRMSE
  at 1x, its worst relative error and its worst |timing error| over the three leader
  speeds, against the delay, one line per architecture (median over ok runs, band =
  inter-quartile range);
- ``traces_d<max delay>.png``: the lagging shoulder (desired and actual) and the leader
  at the largest delay, leader at 1x and 1.5x, first ok run of each architecture and
  pattern;
- the text: a compact table (mean ± sd, failed / n) and, for every delay >= 2, whether
  each forward-model architecture has a lower mean than the inverse-only network.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from skinny_mj.experiments.bimanual_delay.study import ARCHITECTURES, row_id

from skinny_mj.engine.stats import load_runs
from skinny_mj.plant.body import CONTROL_DT_S
from skinny_mj.plots import pyplot, save_figure

#: metric, panel label
PANELS = (("position_nrmse_x1", "lagging-arm position NRMSE (1x)"),
          ("worst_relative_error", "worst relative error (0.5x, 1x, 1.5x)"),
          ("worst_abs_phase_lag_deg", "worst |timing error| (deg of period)"))
SUMMARY = (("position_nrmse_x1", "pos. NRMSE 1x", 4), ("relative_error_x1", "rel. err 1x", 3),
           ("worst_relative_error", "worst rel. err", 3),
           ("abs_phase_lag_deg_x1", "\\|lag\\| 1x (°)", 1),
           ("abs_phase_lag_deg_x0.5", "\\|lag\\| 0.5x (°)", 1),
           ("abs_phase_lag_deg_x1.5", "\\|lag\\| 1.5x (°)", 1))


def _records(out_dir: Path) -> list[dict]:
    return sorted(load_runs(out_dir), key=lambda r: (r["row"], r["run_index"]))


def index_runs(records: list[dict]) -> tuple[list[str], list[int], dict]:
    """Patterns and delays present, and (pattern, arch, delay) -> run records."""
    by: dict = {}
    for rec in records:
        p = rec["params"]
        by.setdefault((p["pattern"], p["architecture"], int(p["delay"])), []).append(rec)
    patterns = sorted({k[0] for k in by}, key=lambda s: (len(s), s))
    delays = sorted({k[2] for k in by})
    return patterns, delays, by


def _ok_values(recs: list[dict], metric: str) -> list[float]:
    return [float(r["metrics"][metric]) for r in recs if r.get("status") == "ok"
            and isinstance(r["metrics"].get(metric), int | float)
            and np.isfinite(r["metrics"][metric])]


def _sweep_png(path: Path, patterns: list[str], delays: list[int], by: dict) -> None:
    plt = pyplot()
    fig, axes = plt.subplots(len(patterns), len(PANELS), squeeze=False,
                             figsize=(4.2 * len(PANELS), 3.2 * len(patterns)))
    for i, pattern in enumerate(patterns):
        for j, (metric, label) in enumerate(PANELS):
            ax = axes[i, j]
            for arch in ARCHITECTURES:
                stats = [np.percentile(v, (25, 50, 75)) if v else (np.nan,) * 3 for v in
                         (_ok_values(by.get((pattern, arch, d), []), metric) for d in delays)]
                lo, med, hi = np.array(stats).T
                (line,) = ax.plot(delays, med, "o-", label=arch)
                ax.fill_between(delays, lo, hi, color=line.get_color(), alpha=0.15)
            ax.set(xlabel="sensory delay (steps of 20 ms)", ylabel=label, title=pattern)
            ax.set_xticks(delays)
            ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    fig.suptitle("Bimanual coordination under delay (median over ok runs, IQR band)")
    fig.tight_layout()
    save_figure(fig, path)


def _traces_png(path: Path, patterns: list[str], delay: int, by: dict,
                tags: tuple[str, ...] = ("x1", "x1.5")) -> None:
    plt = pyplot()
    cols = [(p, tag) for p in patterns for tag in tags]
    fig, axes = plt.subplots(len(ARCHITECTURES), len(cols), squeeze=False, sharex="col",
                             figsize=(4.6 * len(cols), 1.9 * len(ARCHITECTURES)))
    legend = None
    for j, (pattern, tag) in enumerate(cols):
        for i, arch in enumerate(ARCHITECTURES):
            ax = axes[i, j]
            ok = [r for r in by.get((pattern, arch, delay), []) if r.get("status") == "ok"]
            ax.set_title(f"{row_id(pattern, arch, delay)}, leader at {tag[1:]}x", fontsize=8)
            ax.grid(alpha=0.3)
            if not ok or tag not in ok[0]["metrics"].get("traces", {}):
                ax.text(0.5, 0.5, "no ok run", ha="center", transform=ax.transAxes)
                continue
            tr = ok[0]["metrics"]["traces"][tag]
            t = np.arange(len(tr["leader"])) * CONTROL_DT_S
            ax.plot(t, tr["leader"], color="0.6", label="leading arm")
            ax.plot(t, tr["desired"], "--", color="tab:blue", label="lagging, desired")
            ax.plot(t, tr["actual"], color="tab:red", label="lagging, actual")
            legend = legend or ax
            if j == 0:
                ax.set_ylabel("shoulder (°)")
    for ax in axes[-1]:
        ax.set_xlabel("time (s)")
    if legend is not None:
        legend.legend(fontsize=7, loc="upper right")
    fig.suptitle(f"Lagging shoulder at delay {delay} (first ok run of each row)")
    fig.tight_layout()
    save_figure(fig, path)


def _cell(v: list[float], digits: int) -> str:
    return "—" if not v else f"{np.mean(v):.{digits}f} ± {np.std(v):.{digits}f}"


def summary_table(patterns: list[str], delays: list[int], by: dict) -> list[str]:
    """Markdown: one line per (pattern, architecture, delay), mean ± sd over ok runs."""
    head = "| pattern | architecture | delay | failed / n | " + " | ".join(
        label for _, label, _ in SUMMARY) + " |"
    lines = [head, "|" + "---|" * (4 + len(SUMMARY))]
    for pattern in patterns:
        for arch in ARCHITECTURES:
            for d in delays:
                recs = [r for r in by.get((pattern, arch, d), []) if r.get("status")
                        in ("ok", "failed")]
                if not recs:
                    continue
                failed = sum(r["status"] == "failed" for r in recs)
                cells = [_cell(_ok_values(recs, m), k) for m, _, k in SUMMARY]
                lines.append(f"| {pattern} | {arch} | {d} | {failed} / {len(recs)} | "
                             + " | ".join(cells) + " |")
    return lines


def comparisons(patterns: list[str], delays: list[int], by: dict) -> list[str]:
    """For each forward-model architecture, the delays >= 2 at which its mean position
    NRMSE / worst |timing error| is below the inverse-only network's."""
    lines = []
    for metric, label in (("position_nrmse_x1", "position NRMSE 1x"),
                          ("worst_abs_phase_lag_deg", "worst |timing error|"),
                          ("worst_relative_error", "worst relative error")):
        for pattern in patterns:
            for arch in list(ARCHITECTURES)[1:]:
                pairs = []
                for d in (d for d in delays if d >= 2):
                    a = _ok_values(by.get((pattern, arch, d), []), metric)
                    b = _ok_values(by.get((pattern, "inverse", d), []), metric)
                    if a and b:
                        pairs.append((d, float(np.mean(a)), float(np.mean(b))))
                lower = sum(a < b for _, a, b in pairs)
                detail = "; ".join(f"d{d} {a:.3g} {'<' if a < b else '>='} {b:.3g}"
                                   for d, a, b in pairs)
                lines.append(f"- {pattern}, {arch} vs inverse, mean {label}: lower at "
                             f"{lower} of {len(pairs)} delays >= 2 ({detail or 'no data'})")
    return lines


def report(results: dict, plan, out_dir: Path) -> str:
    """Figures (metrics against delay per architecture; traces at the largest delay) and
    the comparisons with the inverse-only network."""
    out_dir = Path(out_dir)
    patterns, delays, by = index_runs(_records(out_dir))
    if not by:
        return "no runs"
    _sweep_png(out_dir / "delay_sweep.png", patterns, delays, by)
    _traces_png(out_dir / f"traces_d{max(delays)}.png", patterns, max(delays), by)
    return "\n".join(summary_table(patterns, delays, by) + [""] + comparisons(
        patterns, delays, by))
