"""Three-d's report, from a sweep's run files (the sweep is
:mod:`skinny_mj.experiments.three_d.study`):
the 2D vs 3D table, each paper's own report on each body, the papers' claims checked
on 2D and on 3D side by side, and one figure.

Each paper's report and claims run unchanged on a view of the sweep:
``papers/<paper>-<dim>/`` holds that paper's and body's run files under the paper's own
row ids (and a config.json with the paper's config), rewritten from ``runs/`` at every
report, so the paper's claim functions read them as their own sweep's.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
from skinny_mj.controllers.metrics import nrmse
from skinny_mj.experiments import paper_a, paper_b
from skinny_mj.experiments.paper_c import report as paper_c_report
from skinny_mj.experiments.paper_c.study import MOVEMENTS
from skinny_mj.experiments.three_d.study import DIMS, PAPERS, paper_experiment, row_id, subset

from skinny_mj.engine.stats import aggregate, load_runs, to_jsonable
from skinny_mj.io import atomic_write_json, atomic_write_text
from skinny_mj.plant import body
from skinny_mj.plots import pyplot, save_figure
from skinny_mj.trajectories import load_movement

#: The table's lines: paper -> (paper row or None for every row of the subset, metric,
#: label). Paper C's metrics are ``<test movement>__<metric>``.
LINES = {
    "a": [(None, "performance_nrmse", "performance NRMSE (signals)"),
          (None, "feedback_share", "feedback share")],
    "b": [(None, "relative_error_x1", "rel. shoulder error, 1x"),
          (None, "relative_error_x0.5", "rel. shoulder error, 0.5x"),
          (None, "relative_error_x1.5", "rel. shoulder error, 1.5x")],
    "c": [("ymca", "ymca__position_nrmse", "→ ymca, NRMSE (signals)"),
          ("ymca", "ymca__angle_nrmse", "→ ymca, NRMSE (joint angles)"),
          *(("ymca", f"{t}__position_nrmse", f"→ {t}, NRMSE (signals)")
            for t in ("y", "ym", "mirror-right", "mirror-left", "ymca-0.5x", "ymca-1.5x",
                      "real")),
          ("y", "ymca__position_nrmse", "→ ymca, NRMSE (signals)"),
          ("y", "ymca__angle_nrmse", "→ ymca, NRMSE (joint angles)"),
          ("y-pure", "ym__position_nrmse", "→ ym, NRMSE (signals)"),
          ("y-pure", "ym__angle_nrmse", "→ ym, NRMSE (joint angles)"),
          ("y-pure", "ym__elbow_rom_ratio", "→ ym, elbow range / desired"),
          ("mirror-left", "ymca__position_nrmse", "→ ymca, NRMSE (signals)"),
          ("mirror-left", "ymca__err_vs_avg", "→ ymca, NRMSE vs the arms' average"),
          ("mirror-right", "ymca__position_nrmse", "→ ymca, NRMSE (signals)")],
}
#: What the thesis states in numbers for a line (paper A §4.1 only; B and C give none).
THESIS = {("a", "inverse-d4", "performance_nrmse"): "0.10–0.20 (text: 10–20 %)",
          ("a", "inverse-d4", "feedback_share"):
              f"≈ {paper_a.PAPER_TEXT['inverse_feedback_share_delay_4']:g} (text: almost half)"}
_LINE = re.compile(r"^- \[([^\]]+)\] (.*)$")


def angle_nrmse(produced: np.ndarray, desired: np.ndarray, dof: int) -> float | None:
    """NRMSE of normalized joint angles (produced, desired: (T, dof) rad), None if the
    lengths differ: the same measure on both bodies, whatever the signals."""
    if produced.shape != desired.shape:
        return None
    return float(nrmse(body.body_of(dof).normalize_angles(produced),
                       body.body_of(dof).normalize_angles(desired)))


def _with_angle_errors(rec: dict, dof: int) -> dict:
    """Paper C's run metrics (on the body with ``dof`` DOFs) plus ``<col>__angle_nrmse``
    for the kept joint angles."""
    metrics = dict(rec["metrics"])
    for key, value in rec["metrics"].items():
        if key.startswith("angles__") and value is not None:
            col = key.removeprefix("angles__")
            desired = load_movement(MOVEMENTS[col], dof)[0].angles
            e = angle_nrmse(np.asarray(value, float), desired, dof)
            if e is not None:
                metrics[f"{col}__angle_nrmse"] = e
    return metrics


def write_views(out_dir: Path, runs: list[dict], quick: bool, dof: int,
                signals: str) -> dict[str, Path]:
    """``papers/<paper>-<dim>/``: each paper's run files on each body under the paper's
    own row ids and seeds (:mod:`skinny_mj.engine.stats` format), and its config."""
    views = {}
    for p in PAPERS:
        for dim in DIMS:
            exp = paper_experiment(p, dim, quick, dof, signals)
            index = {r.id: i for i, r in enumerate(exp.rows)}
            view = out_dir / "papers" / f"{p}-{dim}"
            shutil.rmtree(view / "runs", ignore_errors=True)
            (view / "runs").mkdir(parents=True)
            atomic_write_json(view / "config.json", {
                "experiment": exp.name, "config": to_jsonable(exp.to_dict())})
            for rec in runs:
                if rec["params"].get("paper") != p or rec["params"].get("dim") != dim:
                    continue
                own = rec["params"]["row"]
                atomic_write_json(view / "runs" / f"{own}-{rec['seed']}.json",
                                  {**rec, "experiment": exp.name, "row": own,
                                   "row_index": index[own]})
            views[f"{p}-{dim}"] = view
    return views


def paper_claims(p: str, view: Path, dof: int) -> list[str]:
    """Paper ``p``'s own claim lines on the sweep in ``view``."""
    if p == "a":
        return paper_a.claims(view)
    if p == "b":
        return paper_b.claims(view)

    ok = [r for r in load_runs(view) if r["status"] == "ok"]
    return paper_c_report.claims(ok, dof) if ok else ["- [n/a] no finished runs"]


def _split(line: str) -> tuple[str, str]:
    m = _LINE.match(line)
    return (m.group(1), m.group(2)) if m else ("", line.removeprefix("- "))


def _statement_end(text: str, n: int) -> int:
    """Where a claim's statement ends in ``text``: its last ": " outside parentheses
    before ``n`` (where the 2D and 3D lines part), else ``n``'s last space."""
    depth, end = 0, -1
    for i, ch in enumerate(text[:n]):
        depth += (ch == "(") - (ch == ")")
        if depth == 0 and text.startswith(": ", i) and i + 1 < n:
            end = i
    return end if end > 0 else max(text.rfind(" ", 0, n), 0)


def claims_side_by_side(lines_2d: list[str], lines_3d: list[str]) -> tuple[str, list]:
    """A markdown table (claim | 2D | 3D), paired line by line, and the verdict pairs.
    The claim is the text both lines share; each cell is its verdict and its rest."""
    out = ["| claim | 2D | 3D |", "|---|---|---|"]
    pairs = []
    for a, b in zip(lines_2d, lines_3d, strict=False):
        (va, ta), (vb, tb) = _split(a), _split(b)
        n = 0
        while n < min(len(ta), len(tb)) and ta[n] == tb[n]:
            n += 1
        cut = len(ta) if ta == tb else _statement_end(ta, n)
        head = ta[:cut].strip()
        rest = (ta[cut:].lstrip(": ").strip(), tb[cut:].lstrip(": ").strip())
        out.append(f"| {head.replace('|', '/')} | **{va}** {rest[0].replace('|', '/')} | "
                   f"**{vb}** {rest[1].replace('|', '/')} |")
        pairs.append((head, va, vb))
    if len(lines_2d) != len(lines_3d):
        out.append(f"| (unpaired: {len(lines_2d)} lines in 2D, {len(lines_3d)} in 3D) | | |")
    return "\n".join(out), pairs


def summary_line(pairs: list[tuple[str, str, str]]) -> str:
    """How many claims hold of those checked per body, and every verdict that changed."""
    def count(k: int) -> str:
        checked = [v[k] for v in pairs if v[k] in ("holds", "does NOT hold")]
        return f"{checked.count('holds')} of {len(checked)} checked hold"

    changed = [f"{h[:90]}{'…' if len(h) > 90 else ''} ({a} → {b})" for h, a, b in pairs
               if a != b]
    return (f"2D {count(1)}, 3D {count(2)} ({len(pairs)} claims); changed from 2D to 3D: "
            f"{'; '.join(changed) or 'none'}")


def table_lines(results: dict, values: dict, quick: bool) -> list[dict]:
    """One dict per table line: paper, row, label, metric, per dim (mean, sd, n) or None,
    and per dim (failed, n)."""
    rows = {r["row"]: r for r in results.get("rows", [])}
    out = []
    for p, specs in LINES.items():
        ids = subset(quick)[p]
        for only, metric, label in specs:
            for rid in ids if only is None else [only] if only in ids else []:
                line = {"paper": p, "row": rid, "metric": metric, "label": label,
                        "thesis": THESIS.get((p, rid, metric), "—")}
                for dim in DIMS:
                    v = values.get((row_id(p, dim, rid), metric), [])
                    line[dim] = (float(np.mean(v)), float(np.std(v, ddof=1)) if len(v) > 1
                                 else float("nan"), len(v)) if v else None
                    agg = rows.get(row_id(p, dim, rid), {})
                    line[f"{dim}_failed"] = (agg.get("n_failed", 0), agg.get("n", 0))
                if line["2d"] or line["3d"]:
                    out.append(line)
    return out


def _cell(stat) -> str:
    if stat is None:
        return "—"
    m, sd, n = stat
    return f"{m:.3g} ± {sd:.2g}" if np.isfinite(sd) else f"{m:.3g} (n = {n})"


def table_markdown(lines: list[dict]) -> str:
    out = ["| paper | row | measure | 2D mean ± sd | 3D mean ± sd | failed / n (2D, 3D) "
           "| thesis (2D) |", "|---|---|---|---|---|---|---|"]
    for ln in lines:
        f2, f3 = ln["2d_failed"], ln["3d_failed"]
        out.append(f"| {ln['paper'].upper()} | {ln['row']} | {ln['label']} | "
                   f"{_cell(ln['2d'])} | {_cell(ln['3d'])} | {f2[0]}/{f2[1]}, {f3[0]}/{f3[1]} | "
                   f"{ln['thesis']} |")
    return "\n".join(out)


def figure_png(path: Path, lines: list[dict], bodies: dict[str, str]) -> Path | None:
    """Per paper, each line's 2D and 3D mean ± sd (markers on one row per line, log x)."""
    from matplotlib.ticker import NullFormatter

    by_paper = {p: [ln for ln in lines if ln["paper"] == p and ln["2d"] and ln["3d"]]
                for p in PAPERS}
    by_paper = {p: v for p, v in by_paper.items() if v}
    if not by_paper:
        return None
    plt = pyplot()
    heights = [0.3 * len(v) + 0.9 for v in by_paper.values()]
    fig, axes = plt.subplots(len(by_paper), 1, figsize=(8.5, sum(heights) + 0.6),
                             squeeze=False, gridspec_kw={"height_ratios": heights})
    for ax, (p, v) in zip(axes[:, 0], by_paper.items(), strict=True):
        y = np.arange(len(v))
        for k, (dim, style) in enumerate((("2d", "o"), ("3d", "s"))):
            m = np.array([ln[dim][0] for ln in v])
            sd = np.nan_to_num(np.array([ln[dim][1] for ln in v]))
            ax.errorbar(m, y + (0.15 if k else -0.15), xerr=np.vstack(
                [np.minimum(sd, 0.9 * m), sd]), fmt=style, ms=4, capsize=2,
                color="tab:orange" if k else "tab:blue", label=bodies[dim])
        ax.set_yticks(y, [f"{ln['row']} {ln['label']}" for ln in v], fontsize=7)
        ax.set_ylim(len(v) - 0.5, -0.5)
        ax.set_xscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.grid(alpha=0.3, which="both")
        ax.set_title(f"Paper {p.upper()}: mean ± sd over the ok runs", fontsize=9)
    axes[0, 0].legend(fontsize=7, loc="lower center", bbox_to_anchor=(0.5, 1.12), ncol=2)
    return save_figure(fig, path)


def report(results, plan, out_dir: Path) -> str:
    """The study's report: the 2D vs 3D table, each paper's figures and claims per body,
    the claims side by side and the figure, for the sweep's ``plan`` (its quick, its 3D
    body)."""
    return write_report(results, Path(out_dir), plan.params["quick"], plan.base.plant.dof,
                        plan.base.plant.signals)


def write_report(results: dict, out_dir: Path, quick: bool, dof: int, signals: str,
                 figures: bool = True) -> str:
    """Views, each paper's report per body (its figures; not with ``figures=False``), the
    table, the figure and the claims; ``quick``: the sweep's, ``dof`` and ``signals``: its
    3D body."""
    runs = load_runs(out_dir)
    values: dict = {}
    for rec in runs:
        if rec["status"] != "ok":
            continue
        p, dim = rec["params"]["paper"], rec["params"]["dim"]
        metrics = rec["metrics"] if p != "c" else _with_angle_errors(
            rec, 4 if dim == "2d" else dof)
        for k, v in metrics.items():
            if isinstance(v, int | float) and not isinstance(v, bool) and np.isfinite(v):
                values.setdefault((rec["row"], k), []).append(float(v))
    lines = table_lines(results, values, quick)
    table = table_markdown(lines)
    if figures:
        figure_png(out_dir / "three_d.png", lines, {
            "2d": "2D (4 DOF, joint angles)", "3d": f"3D ({dof} DOF, {signals})"})
    text = ["## 2D vs 3D", "", table, "",
            "Means and sd over the ok runs (failed runs diverged and are left out). "
            "'signals' = the run's position signals: joint angles in 2D, Cartesian elbow "
            "and wrist positions in 3D.", ""]
    summary = []
    views = write_views(out_dir, runs, quick, dof, signals)
    for p in PAPERS:
        per_dim = {}
        for dim in DIMS:
            view = views[f"{p}-{dim}"]
            if not any((view / "runs").iterdir()):
                per_dim[dim] = []
                continue
            if figures:  # the paper's own report: its figures and claims.md
                exp = paper_experiment(p, dim, quick, dof, signals)
                own = exp.report(aggregate(view), view)
                atomic_write_text(view / "claims.md", f"## Claims\n{own}\n")
            per_dim[dim] = paper_claims(p, view, 4 if dim == "2d" else dof)
        if not per_dim["2d"] and not per_dim["3d"]:
            text += [f"## Paper {p.upper()}: claims on 2D and on 3D", "",
                     "(no run of this paper in the sweep yet)", ""]
            summary.append(f"- paper {p.upper()}: not run yet")
            continue
        side, pairs = claims_side_by_side(per_dim["2d"], per_dim["3d"])
        text += [f"## Paper {p.upper()}: claims on 2D and on 3D", "", side, ""]
        summary.append(f"- paper {p.upper()}: " + summary_line(pairs))
    text += ["## Summary", "", *summary]
    atomic_write_text(out_dir / "three_d.md", "\n".join(text) + "\n")
    return "\n".join(text)
