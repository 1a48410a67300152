"""The mismatch study's report: the mismatch x controller table (position NRMSE and RMS
joint error in degrees, mean ± sd over ok runs) and the goals, from the run files
(:mod:`skinny_mj.experiments.mismatch.study`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from skinny_mj.experiments.mismatch.study import (
    BODIES,
    CLIP_BODIES,
    CONTROLLERS,
    EPOCHS,
    GOAL_K0,
    GOAL_RATIO,
    GOAL_VS_CT,
    LONG,
    LONG_FACTOR,
    MISMATCHES,
    MODEL_ERROR,
    MOVEMENTS,
    row_id,
)
from skinny_mj.experiments.mismatch.switch import LEARNERS, POST, PRE

from skinny_mj.engine.stats import load_runs

#: table columns: header, row's controller, metric suffix
COLUMNS = (("PD + g", "pd-g", ""), ("teacher alone", "teacher", ""),
           ("nominal CT", "ct-nominal", ""), ("adaptive CT", "ct-adaptive", ""),
           ("oracle CT", "ct-oracle", ""), ("ESN K = 0", "esn", ""),
           ("ESN K = 1", "esn", "_k1"), ("ESN trained nominal, K = 0", "esn", "_on"))


def values(records: list[dict], row: str, metric: str) -> list[float]:
    """The finite values of ``metric`` over the ok runs of ``row``."""
    out = []
    for rec in records:
        v = rec["metrics"].get(metric) if rec["row"] == row and rec.get("status") == "ok" \
            else None
        if isinstance(v, int | float) and np.isfinite(v):
            out.append(float(v))
    return out


def _cell(vals: list[float], degrees: list[float]) -> str:
    if not vals:
        return "—"
    text = f"{np.mean(vals):.4f} ± {np.std(vals):.4f}"
    return f"{text} ({np.mean(degrees):.2f}°)" if degrees else text


def _lookup(records, bd: str, m: str, ctl: str, suffix: str, metric: str,
            mv: str = "ymca", variant: str = "") -> list[float]:
    if suffix == "_on":
        if m == "none":
            return values(records, row_id(bd, "none", "esn", mv) + variant, metric)
        return values(records, row_id(bd, "none", "esn", mv) + variant, f"{metric}_on_{m}")
    return values(records, row_id(bd, m, ctl, mv) + variant, metric + suffix)


def mean(records, bd, m, ctl, suffix="", metric="position_nrmse", mv="ymca",
         variant="") -> float:
    vals = _lookup(records, bd, m, ctl, suffix, metric, mv, variant)
    return float(np.mean(vals)) if vals else float("nan")


def best(records, bd, m, ctl, mv="ymca") -> float:
    """``ctl``'s mean position NRMSE under the better of the two velocity estimates."""
    return float(np.nanmin([mean(records, bd, m, ctl, mv=mv),
                            mean(records, bd, m, ctl, mv=mv, variant="-fd2")]))


def table(records: list[dict], bd: str, mv: str = "ymca", variant: str = "") -> list[str]:
    """Markdown: one line per mismatch, position NRMSE mean ± sd (RMS joint error, °);
    ``variant``: the rows' id suffix (``-fd2``: the second-order difference)."""
    lines = ["| mismatch | " + " | ".join(h for h, _, _ in COLUMNS) + " |",
             "|---|" + "---|" * len(COLUMNS)]
    for m in MISMATCHES:
        cells = [_cell(_lookup(records, bd, m, c, s, "position_nrmse", mv, variant),
                       _lookup(records, bd, m, c, s, "rms_error_deg", mv, variant))
                 for _, c, s in COLUMNS]
        lines.append(f"| {m} | " + " | ".join(cells) + " |")
    n = sorted({len(values(records, row_id(bd, m, c, mv) + variant, "position_nrmse"))
                for m in MISMATCHES for c in CONTROLLERS} - {0})
    lines.append("")
    lines.append(f"Position NRMSE, mean ± sd over {'/'.join(map(str, n))} ok runs per row "
                 "(RMS joint error in degrees).")
    return lines


def goals(records: list[dict], bd: str, mv: str = "ymca") -> list[str]:
    """The goals against what was measured."""
    base = mean(records, bd, "none", "esn", mv=mv)
    out = [f"- ESN + FEL, nominal teacher, realistic sensing, K = 0, no mismatch: "
           f"{base:.4f} (goal <= {GOAL_K0[bd]})"]
    fd2 = values(records, row_id(bd, "none", "esn", mv) + "-fd2", "position_nrmse")
    if fd2:
        out.append(f"- the same with velocities by the second-order difference instead of "
                   f"the observer: {np.mean(fd2):.4f} ± {np.std(fd2):.4f}")
    for m in MISMATCHES:
        if m == "none":
            continue
        v = mean(records, bd, m, "esn", mv=mv)
        if np.isnan(v):  # that row was not swept
            continue
        out.append(f"- {m}: ESN K = 0 {v:.4f} = {v / base:.2f}x its no-mismatch error "
                   f"(goal <= {GOAL_RATIO}x)")
    for m in MODEL_ERROR:
        k1, ct = mean(records, bd, m, "esn", "_k1", mv=mv), mean(records, bd, m, "ct-nominal",
                                                                  mv=mv)
        ad = mean(records, bd, m, "ct-adaptive", mv=mv)
        if np.isnan(k1) or np.isnan(ct):  # those rows were not swept
            continue
        out.append(f"- {m}: ESN K = 1 {k1:.4f}, nominal CT {ct:.4f} ({ct / k1:.2f}x; goal >= "
                   f"{GOAL_VS_CT}x), adaptive CT {ad:.4f} ({ad / k1:.2f}x)")
        bct, bad = best(records, bd, m, "ct-nominal", mv), best(records, bd, m, "ct-adaptive", mv)
        k0 = min(mean(records, bd, m, "esn", mv=mv), k1)
        out.append(f"  each under its better velocity estimate: the ESN's better of K = 0 / 1 "
                   f"{k0:.4f}, nominal CT {bct:.4f} ({bct / k0:.2f}x), adaptive CT {bad:.4f} "
                   f"({bad / k0:.2f}x)")
    return out


def switch_table(records: list[dict]) -> list[str]:
    """Markdown: the payload switch per learner, mean position NRMSE per cycle."""
    lines = ["| controller | before | switch cycle | +1 | +2 | +3 | last | recover (cycles) |",
             "|---|---|---|---|---|---|---|---|"]
    for learner in (*LEARNERS, *(f"{x}-fd2" for x in LEARNERS)):
        row = f"2d-ymca-switch-{learner}"
        curves = [r["metrics"]["curve"] for r in records
                  if r["row"] == row and r.get("status") == "ok"]
        if not curves:
            continue
        c = np.mean(curves, axis=0)
        rec = values(records, row, "recover_cycles")
        cells = [np.mean(values(records, row, "pre_switch")), *c[PRE:PRE + 4], c[-1]]
        never = sum(x > POST for x in rec)
        recover = "never" if never == len(rec) else f"{np.median(rec):.0f} (median; never in " \
            f"{never} of {len(rec)} runs)" if never else f"{np.median(rec):.0f} (median)"
        lines.append(f"| {learner} | " + " | ".join(f"{v:.4f}" for v in cells)
                     + f" | {recover} |")
    return lines


def long_table(records: list[dict], bd: str) -> list[str]:
    """Markdown: the ESN alone (K = 0) on YMCA trained 15 and 4 x 15 epochs (group
    ``long``, the same seeds), each against the nominal arm's error at its length."""
    rows = [m for m in LONG.get(bd, ((), 0))[0]
            if values(records, row_id(bd, m, "esn") + f"-x{LONG_FACTOR}", "position_nrmse")]
    if not rows:
        return []
    base = {v: mean(records, bd, "none", "esn", variant=v) for v in ("", f"-x{LONG_FACTOR}")}
    lines = [f"| mismatch | {EPOCHS} epochs | × its nominal | {EPOCHS * LONG_FACTOR} epochs "
             "| × its nominal |", "|---|---|---|---|---|"]
    for m in rows:
        cells = []
        for v in base:
            vals = _lookup(records, bd, m, "esn", "", "position_nrmse", variant=v)
            deg = _lookup(records, bd, m, "esn", "", "rms_error_deg", variant=v)
            cells += [_cell(vals, deg), f"{np.mean(vals) / base[v]:.2f}" if vals else "—"]
        lines.append(f"| {m} | " + " | ".join(cells) + " |")
    return lines


def report(results: dict, plan, out_dir: Path) -> str:
    """The table and the goals of each body with runs, and the payload switch."""
    records = load_runs(Path(out_dir))
    lines: list[str] = []
    for mv, movement in MOVEMENTS.items():
        for bd in BODIES if mv == "ymca" else CLIP_BODIES:
            if not any(r["row"].startswith(f"{bd}-{mv}-") and "-switch-" not in r["row"]
                       for r in records):
                continue
            lines += [f"## {bd}, {movement}", "", *table(records, bd, mv), "",
                      *goals(records, bd, mv), ""]
            if any(r["row"].startswith(f"{bd}-{mv}-") and r["row"].endswith("-fd2")
                   and "-switch-" not in r["row"] for r in records):
                lines += [f"### {bd}, {movement}, velocities by the second-order difference",
                          "", *table(records, bd, mv, "-fd2"), ""]
    for bd in BODIES:
        if long := long_table(records, bd):
            lines += [f"## {bd}, YMCA, the ESN trained {LONG_FACTOR}x as long", "", *long, ""]
    if any("-switch-" in r["row"] for r in records):
        lines += ["## Payload switched on mid-movement", "", *switch_table(records), ""]
    return "\n".join(lines) if lines else "no runs"
