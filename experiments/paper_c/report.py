"""Paper C's report: the train x test matrices, the shoulder-vs-elbow figures, the
learning curves and the paper's claims, checked, from a sweep's run files (the sweep
itself is :mod:`skinny_mj.experiments.paper_c.study`)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from skinny_mj.controllers.metrics import nrmse
from skinny_mj.experiments.paper_c.study import (
    AS_GOOD_ABS,
    AS_GOOD_FACTOR,
    LARGE_ERROR_FACTOR,
    MOVEMENTS,
    REAL_ID,
    STILL_ELBOW_RATIO,
    SYMMETRIC_FACTOR,
    elbow_range,
    lag_steps,
    load,
)

from skinny_mj.engine.stats import load_runs
from skinny_mj.io import atomic_write_text
from skinny_mj.plant import body
from skinny_mj.plots import heatmap_png, learning_curve_png, pyplot, save_figure
from skinny_mj.trajectories import get

if TYPE_CHECKING:
    from skinny_mj.engine.plan import Experiment, Results


def _runs(out_dir: Path) -> list[dict]:
    return [r for r in load_runs(out_dir) if r.get("status") == "ok"]


def _mean(runs: list[dict], row: str, metric: str) -> float:
    v = [r["metrics"].get(metric) for r in runs if r["row"] == row]
    v = [x for x in v if isinstance(x, int | float) and np.isfinite(x)]
    return float(np.mean(v)) if v else float("nan")


def matrix(runs: list[dict], metric: str = "position_nrmse"
           ) -> tuple[list[str], list[str], np.ndarray]:
    """(train ids, test ids, (n_train, n_test) mean ``metric`` over ok runs; NaN = none)."""
    train = [r for r in MOVEMENTS if any(x["row"] == r for x in runs)]
    tests = [c for c in (*MOVEMENTS, REAL_ID)
             if any(f"{c}__{metric}" in x["metrics"] for x in runs)]
    m = np.array([[_mean(runs, r, f"{c}__{metric}") for c in tests] for r in train])
    return train, tests, m.reshape(len(train), len(tests))


def matrix_markdown(train: list[str], tests: list[str], m: np.ndarray, title: str) -> str:
    lines = [f"### {title}", "", "| train \\ test | " + " | ".join(tests) + " |",
             "|---|" + "---|" * len(tests)]
    for i, r in enumerate(train):
        cells = ["—" if not np.isfinite(v) else f"{v:.4f}" for v in m[i]]
        lines.append(f"| {r} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def arm_figure_png(path: Path, cases: list[tuple[str, np.ndarray, np.ndarray | None]],
                   dof: int = 4) -> Path:
    """Shoulder abduction θ vs elbow extension φ per arm, like paper C's Figs. 3–6.

    cases : (title, desired (T, n_dof) rad, produced (T, n_dof) rad or None).
    """
    plt = pyplot()
    names = body.body_of(dof).dof_names
    fig, axes = plt.subplots(len(cases), 2, figsize=(7.5, 3.0 * len(cases)), squeeze=False)
    for i, (title, desired, produced) in enumerate(cases):
        for j, side in enumerate(("right", "left")):
            th, ph = names.index(f"{side}_shoulder_abduction"), names.index(f"{side}_elbow_flexion")
            ax = axes[i, j]
            ax.plot(np.degrees(desired[:, th]), np.degrees(desired[:, ph]), "k--", lw=1,
                    label="desired")
            if produced is not None:
                ax.plot(np.degrees(produced[:, th]), np.degrees(produced[:, ph]), lw=1.2,
                        label="produced")
            ax.set(xlim=(-5, 185), ylim=(-5, 185), xlabel="shoulder θ (deg)",
                   ylabel="elbow φ (deg)", title=f"{title}: {side} arm")
            ax.grid(alpha=0.3)
            ax.legend(fontsize=7)
    return save_figure(fig, path)


def _first_angles(runs: list[dict], row: str, col: str) -> np.ndarray | None:
    for r in runs:
        if r["row"] == row and f"angles__{col}" in r["metrics"]:
            return np.asarray(r["metrics"][f"angles__{col}"], float)
    return None


def _mean_angles(runs: list[dict], row: str, col: str) -> np.ndarray | None:
    a = [np.asarray(r["metrics"][f"angles__{col}"], float) for r in runs
         if r["row"] == row and f"angles__{col}" in r["metrics"]]
    return np.mean(a, axis=0) if a else None


def _line(holds: bool | None, text: str, numbers: str) -> str:
    mark = "n/a" if holds is None else ("holds" if holds else "does NOT hold")
    return f"- [{mark}] {text}: {numbers}"


def claims(runs: list[dict], dof: int = 4) -> list[str]:
    """Paper C's claims (SPEC §4), each with the numbers behind it."""
    out = []
    self_err = _mean(runs, "ymca", "ymca__position_nrmse")
    for col in ("y", "ym", "mirror-right", "mirror-left", "ymca-0.5x", "ymca-1.5x"):
        e = _mean(runs, "ymca", f"{col}__position_nrmse")
        ok = None if not np.isfinite(e + self_err) else bool(
            e <= AS_GOOD_FACTOR * self_err or e - self_err <= AS_GOOD_ABS)
        out.append(_line(ok, f"trained on YMCA, tested on {col}: about as good as on YMCA "
                         f"(<= {AS_GOOD_FACTOR}x or +{AS_GOOD_ABS})",
                         f"position NRMSE {e:.4f} vs YMCA itself {self_err:.4f}"))
    ratio = _mean(runs, "y-pure", "ym__elbow_rom_ratio")
    ref = _mean(runs, "ymca", "ym__elbow_rom_ratio")
    out.append(_line(None if not np.isfinite(ratio) else bool(ratio < STILL_ELBOW_RATIO),
                     f"Y pure -> YM: the elbows do not move (produced/desired elbow range "
                     f"< {STILL_ELBOW_RATIO})",
                     f"ratio {ratio:.3f} (YMCA-trained on YM: {ref:.3f})"))
    produced = _mean(runs, "y", "ymca__elbow_range_rad")
    trained = _mean(runs, "y", "train_elbow_range_rad")
    wanted = elbow_range(load("ymca", dof).angles, dof)
    out.append(_line(None if not np.isfinite(produced) else bool(produced > trained),
                     "Y -> YMCA: more elbow motion than trained on",
                     f"produced elbow range {np.degrees(produced):.1f}° vs "
                     f"{np.degrees(trained):.1f}° in Y (YMCA wants {np.degrees(wanted):.1f}°)"))
    err = _mean(runs, "y", "ymca__position_nrmse")
    out.append(_line(None if not np.isfinite(err + self_err) else
                     bool(err >= LARGE_ERROR_FACTOR * self_err),
                     f"Y -> YMCA: large errors (>= {LARGE_ERROR_FACTOR}x YMCA -> YMCA)",
                     f"position NRMSE {err:.4f} vs {self_err:.4f}"))
    for row in ("mirror-left", "mirror-right"):
        own, avg = (_mean(runs, row, f"ymca__err_vs_{k}") for k in ("own", "avg"))
        c_own, c_avg = (_mean(runs, row, f"ymca__corr_vs_{k}") for k in ("own", "avg"))
        asym, asym_d = (_mean(runs, row, f"ymca__asym_{k}") for k in ("produced", "desired"))
        ok = None if not np.isfinite(own + avg + asym) else bool(
            avg < own and asym < SYMMETRIC_FACTOR * asym_d)
        out.append(_line(ok, f"{row} -> YMCA: symmetric output, the average of the two "
                         "arms' targets (error vs average < vs own target, arm-to-arm "
                         f"difference < {SYMMETRIC_FACTOR}x the target's)",
                         f"NRMSE vs average {avg:.4f} / vs own {own:.4f}; corr {c_avg:.3f} / "
                         f"{c_own:.3f}; arm-to-arm {asym:.4f} vs target's {asym_d:.4f}"))
    left, right = _mean_angles(runs, "mirror-left", "ymca"), _mean_angles(runs, "mirror-right",
                                                                           "ymca")
    if left is not None and right is not None:
        n = min(len(left), len(right))
        gap = float(nrmse(body.body_of(dof).normalize_angles(left[:n]),
                          body.body_of(dof).normalize_angles(right[:n])))
        asym_d = _mean(runs, "mirror-left", "ymca__asym_desired")
        out.append(_line(bool(gap < SYMMETRIC_FACTOR * asym_d),
                         "left- and right-mirror networks produce practically the same YMCA",
                         f"NRMSE between their mean outputs {gap:.4f} vs arm-to-arm "
                         f"difference of the target {asym_d:.4f}"))
    y_err, pure_err = (_mean(runs, r, "ymca__position_nrmse") for r in ("y", "y-pure"))
    y_rom, pure_rom = (_mean(runs, r, "ymca__elbow_rom_ratio") for r in ("y", "y-pure"))
    out.append(_line(None if not np.isfinite(y_err + pure_err) else bool(
        not (y_err <= AS_GOOD_FACTOR * pure_err or y_err - pure_err <= AS_GOOD_ABS)
        or y_err < pure_err / AS_GOOD_FACTOR),
        "the inference from Y -> YMCA: the small elbow motion trained in Y is what lets it "
        "generalize, so Y generalizes clearly better than Y pure (beyond "
        f"{AS_GOOD_FACTOR}x and +{AS_GOOD_ABS})",
        f"YMCA position NRMSE {y_err:.4f} (Y) vs {pure_err:.4f} (Y pure); elbow range "
        f"ratio {y_rom:.3f} vs {pure_rom:.3f}"))
    lags = timing_lags(runs, dof)
    if lags:
        worst = max(lags, key=lambda k: abs(lags[k]))
        out.append(_line(bool(abs(lags[worst]) <= TIMING_LAG_STEPS),
                         "timing is not a problem in any experiment (every kept test's "
                         f"output within {TIMING_LAG_STEPS} steps of its target's timing, "
                         "cross-correlation lag, mean over runs)",
                         f"largest |lag| {abs(lags[worst]):.1f} steps ({worst}); "
                         f"{len(lags)} train -> test pairs"))
    real = _mean(runs, "ymca", f"{REAL_ID}__position_nrmse")
    if np.isfinite(real):
        sat = _mean(runs, "ymca", f"{REAL_ID}__true_command_saturated")
        out.append(f"- [extra] YMCA-trained on the real movement: position NRMSE {real:.4f} "
                   f"vs {self_err:.4f} on YMCA; {100 * sat:.1f} % of its true commands "
                   "exceed full scale (the plant cannot follow those steps)")
    return out


#: "Timing is not a problem": the output's best-aligned lag within this many control steps.
TIMING_LAG_STEPS = 2
def timing_lags(runs: list[dict], dof: int) -> dict[str, float]:
    """Mean lag over runs of every kept train -> test pair (``angles__<col>``)."""
    out: dict[str, list[float]] = {}
    targets = {}
    for r in runs:
        for key, value in r["metrics"].items():
            if not key.startswith("angles__"):
                continue
            col = key.removeprefix("angles__")
            if col not in targets:
                targets[col] = load(MOVEMENTS[col], dof).angles
            out.setdefault(f"{r['row']} -> {col}", []).append(
                lag_steps(np.asarray(value, float), targets[col]))
    return {k: float(np.mean(v)) for k, v in out.items()}


def report(results: Results, plan: Experiment, out_dir: Path) -> str:
    """The train x test heat maps, shoulder-vs-elbow figures, learning curves, claims of
    the sweep in ``out_dir`` (``plan``: what it ran; its body's DOFs)."""
    out_dir = Path(out_dir)
    runs = _runs(out_dir)
    dof = plan.base.plant.dof
    if not runs:
        return "- [n/a] no finished runs"
    text = []
    for metric in ("position_nrmse", "motor_nrmse"):
        train, tests, m = matrix(runs, metric)
        if train and tests:
            heatmap_png(out_dir / f"matrix_{metric}.png", m, train, tests,
                        title=f"Paper C: train x test {metric} (mean of ok runs)")
            text.append(matrix_markdown(train, tests, m, f"train x test {metric} (ours)"))
    atomic_write_text(out_dir / "matrix.md", "\n\n".join(text) + "\n")
    curves = {r: np.array([x["metrics"]["train_curve_position_nrmse"] for x in runs
                           if x["row"] == r], float) for r in MOVEMENTS}
    curves = {k: v for k, v in curves.items() if v.size}
    learning_curve_png(out_dir / "train_curves.png", curves, "train position NRMSE",
                       title="Paper C: evaluation cycle per epoch", log_y=True)
    figs = [("fig3_ymca", "ymca", "ymca", "trained YMCA, tested YMCA"),
            ("fig4_ypure_ym", "y-pure", "ym", "trained Y pure, tested YM"),
            ("fig5_y_ymca", "y", "ymca", "trained Y, tested YMCA"),
            ("fig6_mirror_left_ymca", "mirror-left", "ymca", "trained left mirror, tested YMCA"),
            ("fig6_mirror_right_ymca", "mirror-right", "ymca",
             "trained right mirror, tested YMCA")]
    for name, row, col, title in figs:
        produced = _first_angles(runs, row, col)
        if produced is not None:
            cases = [(title, get(col, dof), produced)]
            if row == "y":
                cases.insert(0, ("Y (training movement)", get("y", dof), None))
            arm_figure_png(out_dir / f"{name}.png",
                           [(t, d.angles, p) for t, d, p in cases], dof)
    rss = [x["metrics"].get("peak_rss_mb") for x in runs if x["metrics"].get("peak_rss_mb")]
    lines = claims(runs, dof)
    if rss:
        lines.append(f"- [info] peak RSS per worker process: max {max(rss):.0f} MB")
    return "\n".join(text) + "\n\n" + "\n".join(lines)
