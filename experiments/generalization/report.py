"""The generalization matrix's report: per representation the train x test matrices
(position NRMSE, DTW NRMSE, within 5°), a heat map with the seen cells marked, and a
summary per training set (coverage, speeds, mean over unseen tests, the real clips, the
command-scale cost), from a sweep's run files
(:mod:`skinny_mj.experiments.generalization.study`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from skinny_mj.experiments.generalization.study import (
    CARTESIAN_BASE,
    CARTESIAN_ROWS,
    GENERAL_OF,
    GENERAL_ROWS,
    REPRESENTATIONS,
    SEEN,
    TESTS,
    TRAIN_SETS_EXTRA,
    TRAIN_SETS_GENERAL,
)
from skinny_mj.experiments.generalization.study import TRAIN_SETS as _MAIN_SETS

from skinny_mj.engine.stats import load_runs
from skinny_mj.io import atomic_write_text
from skinny_mj.plots import pyplot, save_figure

# the report shows the extra and general rows too ("general" marked as no movement row)
TRAIN_SETS = {**_MAIN_SETS, **TRAIN_SETS_EXTRA, **TRAIN_SETS_GENERAL,
              "general": ("the preset's", {"preset": "general"})}
#: Per representation, the best row on unseen real dance before the general presets
#: (the matrix's; j3 had no matrix: today's ``--preset general --dof 8``).
BEFORE = {"j2": "j2-babble15-scale4", "j3": "j3-babble15-scale4",
          "c2": "c2-babble15+ymca", "c3": "c3-babble15+ymca"}
CLIPS = ("md_02", "md_03")

REAL = ("md_02", "md_03", "md_02-tail", "md_03-tail")


def _runs(out_dir: Path) -> list[dict]:
    return [r for r in load_runs(out_dir) if r.get("status") == "ok"]


def _values(runs: list[dict], row: str, metric: str) -> np.ndarray:
    v = [r["metrics"].get(metric) for r in runs if r["row"] == row]
    return np.array([x for x in v if isinstance(x, int | float) and np.isfinite(x)], float)


def stat(runs: list[dict], row: str, metric: str) -> tuple[float, float, int]:
    """(mean, sd, n) of ``metric`` over the ok runs of ``row`` (NaN, NaN, 0 if none)."""
    v = _values(runs, row, metric)
    if not v.size:
        return float("nan"), float("nan"), 0
    return float(v.mean()), float(v.std(ddof=1)) if v.size > 1 else 0.0, int(v.size)


def unseen(train: str, col: str) -> bool:
    return col not in SEEN.get(train, set())


def matrix(runs: list[dict], rep: str, metric: str):
    """(train ids, test ids, (n_train, n_test) means over ok runs; NaN = none)."""
    train = [t for t in TRAIN_SETS if any(x["row"] == f"{rep}-{t}" for x in runs)]
    tests = [c for c in TESTS if any(f"{c}__{metric}" in x["metrics"] for x in runs
                                     if x["row"].startswith(f"{rep}-"))]
    m = np.array([[stat(runs, f"{rep}-{t}", f"{c}__{metric}")[0] for c in tests]
                  for t in train], float).reshape(len(train), len(tests))
    return train, tests, m


def heatmap(path: Path, m: np.ndarray, train: list[str], tests: list[str], title: str,
            fmt: str = "{:.3f}") -> Path:
    """A heat map; cells whose test movement the row trained on are marked '*'."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(1.2 + 0.8 * len(tests), 1.0 + 0.45 * len(train)))
    image = ax.imshow(m, cmap="viridis_r", aspect="auto")
    fig.colorbar(image, ax=ax)
    ax.set_xticks(range(len(tests)), tests, rotation=35, ha="right", fontsize=8)
    ax.set_yticks(range(len(train)), train, fontsize=8)
    mid = np.nanmean(m) if np.isfinite(m).any() else 0.0
    for (i, j), v in np.ndenumerate(m):
        mark = "" if unseen(train[i], tests[j]) else "*"
        ax.text(j, i, fmt.format(v) + mark, ha="center", va="center", fontsize=6.5,
                color="black" if v < mid else "white")
    ax.set_title(title + "  (* = seen in training)", fontsize=9)
    return save_figure(fig, path)


def markdown(m: np.ndarray, train: list[str], tests: list[str], title: str) -> str:
    lines = [f"#### {title}", "", "| train \\ test | " + " | ".join(tests) + " |",
             "|---|" + "---|" * len(tests)]
    for i, t in enumerate(train):
        cells = ["—" if not np.isfinite(v) else f"{v:.3f}" + ("" if unseen(t, c) else "*")
                 for v, c in zip(m[i], tests, strict=True)]
        lines.append(f"| {t} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def summary(runs: list[dict], rep: str) -> str:
    """Per training set: what the movement is like and how it does on unseen tests."""
    head = ("| train set | n | steps | coverage | p99 speed rad/s | train s/run | unseen mean "
            "pos | unseen real pos (mean ± sd) | unseen real DTW | unseen real within 5° | "
            "md_02 |c|>1 | md_02 clipped-ideal pos |")
    lines = [head, "|---|" + "---|" * 11]
    for t in TRAIN_SETS:
        row = f"{rep}-{t}"
        n = stat(runs, row, "train_position_nrmse")[2]
        if not n:
            continue
        present = {k.split("__")[0] for x in runs if x["row"] == row for k in x["metrics"]
                   if k.endswith("__position_nrmse")}
        cols = [c for c in TESTS if unseen(t, c) and c in present]
        per_run = _per_run_mean(runs, row, [f"{c}__position_nrmse" for c in cols])
        real = [c for c in REAL if unseen(t, c) and c in present]
        rp = _per_run_mean(runs, row, [f"{c}__position_nrmse" for c in real])
        rd = _per_run_mean(runs, row, [f"{c}__dtw_nrmse" for c in real])
        rw = _per_run_mean(runs, row, [f"{c}__within5" for c in real])
        f = stat
        lines.append(
            f"| {t} | {n} | {f(runs, row, 'train_steps')[0]:.0f} | "
            f"{f(runs, row, 'train_coverage')[0]:.3f} | "
            f"{f(runs, row, 'train_speed_p99_rad_s')[0]:.1f} | "
            f"{f(runs, row, 'train_wall_s')[0]:.1f} | {_ms(per_run)} | {_ms(rp)} | {_ms(rd)} | "
            f"{_ms(rw)} | {100 * f(runs, row, 'md_02__saturated')[0]:.1f} % | "
            f"{f(runs, row, 'md_02__clipped_ideal_nrmse')[0]:.3f} |")
    return "\n".join(lines)


def rq3(runs: list[dict], rep: str) -> str:
    """Spearman rank correlation, over the movement rows of ``rep`` (not the N / scale
    variants), of each training movement's property with its mean unseen-test error."""
    from scipy.stats import spearmanr

    props = {"coverage": "train_coverage", "p99 speed": "train_speed_p99_rad_s",
             "duration": "train_steps"}
    err, vals = [], {k: [] for k in props}
    for t, (_, changes) in TRAIN_SETS.items():
        row = f"{rep}-{t}"
        if changes or not stat(runs, row, "train_steps")[2]:
            continue
        present = {k.split("__")[0] for x in runs if x["row"] == row for k in x["metrics"]
                   if k.endswith("__position_nrmse")}
        per_run = _per_run_mean(runs, row, [f"{c}__position_nrmse" for c in TESTS
                                            if unseen(t, c) and c in present])
        if not per_run.size:
            continue
        err.append(per_run.mean())
        for k, metric in props.items():
            vals[k].append(stat(runs, row, metric)[0])
    if len(err) < 3:
        return f"{rep}: fewer than 3 training movements, no correlation"
    parts = []
    for k, v in vals.items():
        rho, pval = spearmanr(v, err)
        parts.append(f"{k} ρ = {rho:+.2f} (p = {pval:.2f})")
    return (f"{rep}: Spearman correlation with the mean unseen-test position NRMSE over "
            f"{len(err)} training movements: " + "; ".join(parts))


def _per_run_mean(runs: list[dict], row: str, metrics: list[str]) -> np.ndarray:
    out = []
    for r in runs:
        if r["row"] != row:
            continue
        v = [r["metrics"].get(k) for k in metrics]
        v = [x for x in v if isinstance(x, int | float) and np.isfinite(x)]
        if v and len(v) == len(metrics):
            out.append(np.mean(v))
    return np.array(out, float)


def _ms(v: np.ndarray) -> str:
    if not v.size:
        return "—"
    return f"{v.mean():.3f} ± {v.std(ddof=1) if v.size > 1 else 0.0:.3f}"


def report(results: dict, plan, out_dir: Path) -> str:
    """Matrices, figures and findings."""
    out_dir = Path(out_dir)

    runs = _runs(out_dir)
    if not runs:
        return "- [n/a] no finished runs"
    text = []
    for rep, (dof, signals) in REPRESENTATIONS.items():
        if not any(x["row"].startswith(f"{rep}-") for x in runs):
            continue
        text.append(f"### {rep}: {dof} DOF, {signals} signals")
        for metric, label in (("position_nrmse", "position NRMSE"),
                              ("dtw_nrmse", "DTW NRMSE"), ("within5", "fraction within 5°")):
            train, tests, m = matrix(runs, rep, metric)
            if train and tests:
                if metric == "position_nrmse":
                    heatmap(out_dir / f"matrix_{rep}.png", m, train, tests,
                            f"{rep} ({dof} DOF, {signals}): test position NRMSE, mean of ok runs")
                text.append(markdown(m, train, tests, f"{rep}: {label} (mean of ok runs)"))
        text.append(f"#### {rep}: per training set\n\n" + summary(runs, rep)
                    + "\n\n" + rq3(runs, rep))
    text.append(general_section(runs, out_dir))
    text.append(cartesian_section(runs, out_dir))
    body = "\n\n".join(text) + "\n"
    atomic_write_text(out_dir / "matrix.md", body)
    return body


def general_section(runs: list[dict], out_dir: Path) -> str:
    """Before -> after per body and signal on the two clips (no row here trained on
    them): position (Cartesian rows: on the segment signals) and DTW NRMSE mean ± sd,
    and a bar figure ``general.png``."""
    lines = ["### The general model per body and signal (clips never trained on)", "",
             "| rep | row | role | n | " + " | ".join(f"{c} pos | {c} DTW" for c in CLIPS)
             + " | train s/run |", "|---|---|---|---|" + "---|---|" * len(CLIPS) + "---|"]
    bars = []
    for rep in ("j2", "j3", "c2", "c3"):
        # Cartesian rows scored on the segment signals alone (the elbow rows' own hold more)
        pos = "cartesian_position_nrmse" if rep.startswith("c") else "position_nrmse"
        rows = dict.fromkeys([BEFORE[rep], *(f"{r}-{t}" for r, t in GENERAL_ROWS if r == rep),
                              GENERAL_OF[rep]])
        for row in rows:
            n = stat(runs, row, "train_position_nrmse")[2]
            if not n:
                continue
            role = " and ".join(name for name, of in (("before", BEFORE), ("preset", GENERAL_OF))
                                if of[rep] == row) or "ingredient"
            cells = [_ms(_values(runs, row, f"{c}__{m}")) for c in CLIPS
                     for m in (pos, "dtw_nrmse")]
            lines.append(f"| {rep} | {row} | {role} | {n} | " + " | ".join(cells)
                         + f" | {stat(runs, row, 'train_wall_s')[0]:.1f} |")
            bars.append((f"{row}\n({role})", [stat(runs, row, f"{c}__{pos}")[:2]
                                               for c in CLIPS]))
    if bars:
        general_figure(out_dir / "general.png", bars)
    return "\n".join(lines)


def cartesian_section(runs: list[dict], out_dir: Path) -> str:
    """The Cartesian candidates against their base row, paired seeds: position NRMSE
    scored on the Cartesian signals (``cartesian_position_nrmse``: the elbow rows' own
    signals hold the elbow angles too), DTW NRMSE on each row's own signals and the
    fraction of steps within 5°, and a bar figure ``cartesian.png``."""
    lines = ["### Cartesian candidates (the preset row with one change, its seeds)", "",
             "| rep | row | n | " + " | ".join(f"{c} pos | {c} DTW | {c} within 5°"
                                                 for c in CLIPS)
             + " | train s/run |", "|---|---|---|" + "---|---|---|" * len(CLIPS) + "---|"]
    bars = []
    for rep, base in CARTESIAN_BASE.items():
        for row in (base, *(f"{base}+{v}" for r, v in CARTESIAN_ROWS if r == rep)):
            n = stat(runs, row, "train_position_nrmse")[2]
            if n:
                cells = [_ms(_values(runs, row, f"{c}__{m}")) for c in CLIPS
                         for m in ("cartesian_position_nrmse", "dtw_nrmse", "within5")]
                lines.append(f"| {rep} | {row} | {n} | " + " | ".join(cells)
                             + f" | {stat(runs, row, 'train_wall_s')[0]:.1f} |")
                bars.append((row, [stat(runs, row, f"{c}__cartesian_position_nrmse")[:2]
                                   for c in CLIPS]))
    if bars:
        general_figure(out_dir / "cartesian.png", bars,
                       "Cartesian signals on unseen CMU dance: the preset row and one change")
    return "\n".join(lines)


def general_figure(path: Path, bars: list,
                   title: str = "Imitating unseen CMU dance: before -> the general presets"
                   ) -> Path:
    """Grouped bars: per row (label, [(mean, sd) per clip]) the clips' mean ± sd."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(1.5 + 0.7 * len(bars), 4.2))
    x = np.arange(len(bars))
    width = 0.8 / len(CLIPS)
    for k, clip in enumerate(CLIPS):
        mean = [b[1][k][0] for b in bars]
        sd = [b[1][k][1] for b in bars]
        ax.bar(x + (k - (len(CLIPS) - 1) / 2) * width, mean, width, yerr=sd, capsize=2,
               label=f"{clip} (never trained on)")
    ax.axhline(0.03, color="black", lw=0.8, ls="--", label="goal 0.03")
    ax.set_xticks(x, [b[0] for b in bars], rotation=35, ha="right", fontsize=7)
    ax.set_yscale("log")
    ax.set_ylim(top=4 * max(b[1][k][0] + b[1][k][1] for b in bars for k in range(len(CLIPS))))
    ax.set_ylabel("test position NRMSE (mean ± sd)")
    ax.legend(fontsize=7, ncol=3, loc="upper left")
    ax.set_title(title, fontsize=9)
    return save_figure(fig, path)
