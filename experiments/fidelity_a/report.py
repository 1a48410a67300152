"""Tables, claims and figures of :mod:`skinny_mj.experiments.fidelity_a.study` (from the run
files)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
from skinny_mj.experiments.fidelity_a.study import THESIS

from skinny_mj.engine.stats import load_runs
from skinny_mj.io import atomic_write_text
from skinny_mj.plots import pyplot, save_figure

ARCHS = ("inverse", "parallel", "serial", "hybrid")
WHERE = {"train": "last training epoch (K = 0.65)", "test": "K = 0 test"}
COLORS = {"inverse": "tab:red", "serial": "tab:blue", "parallel": "tab:green",
          "hybrid": "tab:purple"}


def labels(params: dict) -> dict:
    """A row's architecture, forward input, delay and epochs from its run files'
    ``params``: the config keys it changes (or, in sweeps of earlier versions, the
    names themselves)."""
    if "architecture" in params:
        return params
    forward = params.get("forward", "none")
    return {"architecture": "inverse" if forward == "none" else forward,
            "forward_input": params.get("forward.input", "sensed"),
            "delay": params["plant.delay"], "epochs": params["method.epochs"]}


class Runs:
    """Values of the ok runs by (row id, metric), seeds in run order."""

    def __init__(self, *out_dirs: Path) -> None:
        self.runs = [r for d in out_dirs for r in load_runs(d) if r.get("status") == "ok"]
        self.rows: dict[str, dict] = {}
        for r in self.runs:
            self.rows.setdefault(r["row"], labels(r["params"]))

    def get(self, row: str, metric: str) -> np.ndarray:
        """(n,) finite values of ``metric`` in ``row``."""
        v = [r["metrics"].get(metric) for r in self.runs if r["row"] == row]
        return np.array([x for x in v if isinstance(x, int | float) and np.isfinite(x)])

    def count(self, row: str, metric: str) -> float:
        """Sum of a 0/1 metric (failures) over the row's runs."""
        return float(sum(r["metrics"].get(metric) or 0 for r in self.runs if r["row"] == row))

    def curves(self, row: str) -> np.ndarray:
        c = [r["metrics"].get("curve_train_nrmse") for r in self.runs if r["row"] == row]
        return np.array([[np.nan if v is None else v for v in x] for x in c if x], float)

    def find(self, arch: str, forward_input: str, delay: int) -> str | None:
        for row, p in self.rows.items():
            if (p["architecture"], p["forward_input"], p["delay"]) == (arch, forward_input,
                                                                        delay):
                return row
        return None


def _cell(v: np.ndarray, scale: float = 1.0, digits: int = 2) -> str:
    if not len(v):
        return "—"
    v = v * scale
    return f"{v.mean():.{digits}f} ({v.min():.{digits}f}–{v.max():.{digits}f})"


def _epochs(runs: Runs, row: str) -> list[int]:
    last = int(runs.rows[row]["epochs"])
    return [e for e in (10, 50, 150) if e <= last] or [last]


def _pe(runs: Runs, row: str) -> int:
    """The epochs the prediction comparisons use: 10 (paper A's schedule), or fewer."""
    return min(10, int(runs.rows[row]["epochs"]))


def _row_order(runs: Runs) -> list[str]:
    key = {a: i for i, a in enumerate(ARCHS)}
    return sorted(runs.rows, key=lambda r: (runs.rows[r]["forward_input"] != "sensed",
                                            key[runs.rows[r]["architecture"]],
                                            runs.rows[r]["delay"]))


def error_table(runs: Runs) -> str:
    lines = ["| row | epochs | n | train NRMSE % | train mean diff % of range | train mean diff "
             "% of half-range | feedback share % | test NRMSE % | test mean diff % of range "
             "| test fails |", "|" + "---|" * 10]
    for row in _row_order(runs):
        for e in _epochs(runs, row):
            n = len(runs.get(row, f"train_nrmse_e{e}"))
            lines.append(
                f"| {row} | {e} | {n} | {_cell(runs.get(row, f'train_nrmse_e{e}'), 100)} | "
                f"{_cell(runs.get(row, f'train_mad_e{e}'), 100)} | "
                f"{_cell(runs.get(row, f'train_mad_e{e}'), 200)} | "
                f"{_cell(runs.get(row, f'train_share_e{e}'), 100, 0)} | "
                f"{_cell(runs.get(row, f'test_nrmse_e{e}'), 100, 1)} | "
                f"{_cell(runs.get(row, f'test_mad_e{e}'), 100, 1)} | "
                f"{runs.count(row, f'test_failed_e{e}'):.0f} |")
    return "\n".join(lines)


def prediction_table(runs: Runs) -> str:
    lines = ["| forward input | delay | epochs | serial | parallel | hybrid | pre-training "
             "(serial, hybrid) |", "|" + "---|" * 7]
    for fi in ("sensed", "chained"):
        for d in sorted({p["delay"] for p in runs.rows.values()}):
            rows = {a: runs.find(a, fi, d) for a in ("serial", "parallel", "hybrid")}
            if not all(rows.values()):
                continue
            vals = {a: runs.get(rows[a], f"train_pred_nrmse_e{_pe(runs, rows[a])}") * 100
                    for a in rows}
            cells = [f"{v.mean():.2f} ± {v.std(ddof=1):.2f}" if len(v) > 1 else _cell(v)
                     for v in vals.values()]
            pre = np.concatenate([runs.get(rows[a], "pretrain_prediction_nrmse")
                                  for a in ("serial", "hybrid")])
            e = _pe(runs, rows["serial"])
            lines.append(f"| {fi} | {d} | {e} | {' | '.join(cells)} | {_cell(pre, 100)} |")
    return "\n".join(lines)


def thesis_table(runs: Runs) -> str:
    """The thesis's stated numbers (paper A §4, text) beside ours."""
    lines = ["| quantity | thesis (paper A text) | ours |", "|---|---|---|"]
    lo, hi = THESIS["inverse_error_by_delay_4"]
    for d in (4, 10):
        row = runs.find("inverse", "sensed", d)
        if row:
            cells = "; ".join(
                f"e{e}: train NRMSE {runs.get(row, f'train_nrmse_e{e}').mean() * 100:.1f}, "
                f"mean diff {runs.get(row, f'train_mad_e{e}').mean() * 100:.1f} "
                f"(×2: {runs.get(row, f'train_mad_e{e}').mean() * 200:.1f}), "
                f"test NRMSE {runs.get(row, f'test_nrmse_e{e}').mean() * 100:.1f}"
                for e in _epochs(runs, row))
            lines.append(f"| inverse only, error at delay {d} (%) | {lo:.0%}–{hi:.0%} | {cells} |")
    row = runs.find("inverse", "sensed", 4)
    if row:
        lines.append(f"| inverse only, feedback share at delay 4 | ≈ "
                     f"{THESIS['inverse_feedback_share_delay_4']:.0%} | "
                     f"{runs.get(row, 'train_share_e10').mean():.0%} (e10) |")
    for d in (0, 10):
        v = [runs.get(r, "pretrain_prediction_nrmse") for r in
             (runs.find("serial", "sensed", d), runs.find("hybrid", "sensed", d)) if r]
        v = np.concatenate(v) if v else np.array([])
        lines.append(f"| pre-training prediction error, delay {d} | ≈ "
                     f"{THESIS[f'pretrain_prediction_delay_{d}']:.0%} | "
                     f"{_cell(v, 100)} % NRMSE (n = {len(v)}) |")
    return "\n".join(lines)


def _welch(a: np.ndarray, b: np.ndarray) -> float:
    from scipy.stats import ttest_ind

    if len(a) < 2 or len(b) < 2:
        return float("nan")
    return float(ttest_ind(a, b, equal_var=False).pvalue)


def claims(runs: Runs) -> list[str]:
    """The thesis's claims, each measured every way the study records."""
    out = []
    inv = [runs.find("inverse", "sensed", d) for d in (4, 6, 10)]
    inv = [r for r in inv if r]
    hits, total = [], 0
    for row in inv:
        for e in _epochs(runs, row):
            for where in ("train", "test"):
                for metric, scale, label in (("nrmse", 1, "NRMSE"), ("mad", 1, "mean diff/range"),
                                             ("mad", 2, "mean diff/half-range")):
                    v = runs.get(row, f"{where}_{metric}_e{e}") * scale
                    if len(v):
                        total += 1
                        if 0.10 <= v.mean() <= 0.20:
                            hits.append(f"{row} e{e} {where} {label} {v.mean():.3f}")
    out.append(f"- inverse only, error 10–20 % at delay >= 4: {len(hits)} of {total} "
               f"(row, epochs, where, metric) readings fall in 0.10–0.20"
               f"{': ' + '; '.join(hits) if hits else ''}")
    for fi in ("sensed", "chained"):
        for d in sorted({p["delay"] for p in runs.rows.values()}):
            rows = {a: runs.find(a, fi, d) for a in ("serial", "parallel", "hybrid")}
            if not all(rows.values()):
                continue
            p = {a: runs.get(rows[a], f"train_pred_nrmse_e{_pe(runs, rows[a])}") for a in rows}
            perf = {a: runs.get(rows[a], f"train_nrmse_e{_pe(runs, rows[a])}") for a in rows}
            if not all(len(v) for v in p.values()):
                continue
            highest = max(p, key=lambda a: p[a].mean())
            p_sp = min(_welch(p["serial"], p["parallel"]), _welch(p["serial"], p["hybrid"]))
            ok = highest == "serial" and p_sp < 0.05
            out.append(f"- [{'holds' if ok else 'does NOT hold'}] {fi} d{d}: serial has the "
                       f"highest prediction error (significantly): highest {highest}; means "
                       + ", ".join(f"{a} {p[a].mean():.4f}" for a in p)
                       + f"; Welch p (serial vs other, larger) {p_sp:.3g}")
            p_ph, q_ph = _welch(p["parallel"], p["hybrid"]), _welch(perf["parallel"],
                                                                    perf["hybrid"])
            ok = p_ph >= 0.05 and q_ph >= 0.05
            out.append(f"- [{'holds' if ok else 'does NOT hold'}] {fi} d{d}: parallel ≈ hybrid "
                       f"(no significant difference): prediction p = {p_ph:.3g}, performance "
                       f"p = {q_ph:.3g} (performance means {perf['parallel'].mean():.4f} vs "
                       f"{perf['hybrid'].mean():.4f})")
    for d in (4, 6, 10):
        s, i = runs.find("serial", "sensed", d), runs.find("inverse", "sensed", d)
        if not (s and i):
            continue
        for where in ("train", "test"):
            e = min(_pe(runs, s), _pe(runs, i))
            sv, iv = runs.get(s, f"{where}_nrmse_e{e}"), runs.get(i, f"{where}_nrmse_e{e}")
            if len(sv) and len(iv):
                ok = sv.max() < iv.min()
                out.append(f"- [{'holds' if ok else 'does NOT hold'}] d{d} e{e} {where}: worst "
                           f"serial {sv.max():.4f} < best inverse {iv.min():.4f} (Fig. 5)")
    return out


def _band(ax, x, m: np.ndarray, color: str, label: str) -> None:
    """Mean line and min–max band over seeds of m (R, len(x)); NaN columns skipped."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        mean, lo, hi = np.nanmean(m, 0), np.nanmin(m, 0), np.nanmax(m, 0)
    ax.plot(x, mean, "o-", color=color, label=label)
    ax.fill_between(x, lo, hi, color=color, alpha=0.2)


def _matrix(runs: Runs, arch: str, delays: list[int], metric: str, scale: float) -> np.ndarray:
    cols = []
    for d in delays:
        row = runs.find(arch, "sensed", d)
        cols.append(runs.get(row, metric) * scale if row else np.array([]))
    n = max([len(c) for c in cols] + [1])
    m = np.full((n, len(delays)), np.nan)
    for j, c in enumerate(cols):
        m[:len(c), j] = c
    return m


def fig5(runs: Runs, path: Path, epochs: int = 10) -> None:
    """Thesis Fig. 5 redrawn: inverse only vs serial, mean and min–max band over seeds."""
    plt = pyplot()
    epochs = min([epochs] + [_pe(runs, r) for r in runs.rows])
    delays = sorted({p["delay"] for r, p in runs.rows.items()
                     if p["architecture"] in ("inverse", "serial")
                     and p["forward_input"] == "sensed"})
    panels = (("train_nrmse", 100, "NRMSE %", "last training epoch (K = 0.65)"),
              ("train_mad", 100, "mean difference, % of range", "last training epoch"),
              ("test_nrmse", 100, "NRMSE %", "K = 0 test"))
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.4))
    for ax, (metric, scale, label, where) in zip(axes, panels, strict=True):
        for arch in ("inverse", "serial"):
            m = _matrix(runs, arch, delays, f"{metric}_e{epochs}", scale)
            if np.isfinite(m).any():
                _band(ax, delays, m, COLORS[arch], f"ours: {arch}" + (" only" if arch ==
                                                                        "inverse" else ""))
        ax.fill_between([4, max(delays + [4])], 10, 20, color="0.5", alpha=0.15,
                        label="thesis text: inverse only 10–20 % (delay >= 4)")
        if metric == "train_mad":  # the other reading: a fraction of the half-range 1
            for arch in ("inverse", "serial"):
                m = _matrix(runs, arch, delays, f"{metric}_e{epochs}", 2 * scale)
                if np.isfinite(m).any():
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore", RuntimeWarning)
                        ax.plot(delays, np.nanmean(m, 0), ":", color=COLORS[arch],
                                label=f"ours: {arch}, × 2 (% of half-range)")
        if metric == "train_nrmse":
            tw = ax.twinx()
            for arch in ("inverse", "serial"):
                m = _matrix(runs, arch, delays, f"train_share_e{epochs}", 100)
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", RuntimeWarning)
                    tw.plot(delays, np.nanmean(m, 0), "--", color=COLORS[arch],
                            label=f"ours: feedback share, {arch}")
            tw.plot([4], [50], "kD", label="thesis: share ≈ 50 % at d4 (inverse)")
            tw.set_ylabel("feedback share % (dashed)")
            tw.set_ylim(0, 100)
            tw.legend(loc="lower right", fontsize=7)
        if metric == "test_nrmse":
            ax.set_yscale("log")
        ax.set(xlabel="delay (steps of 20 ms)", ylabel=f"{label}, {where}",
               title=f"{where}, {epochs} epochs")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper left", fontsize=7)
    fig.suptitle(f"Paper A Fig. 5 redrawn (ours, {epochs} epochs): band = min–max over seeds")
    save_figure(fig, path)


def fig_epochs(runs: Runs, path: Path) -> bool:
    """Error against epochs for the rows run longer than 10 epochs: the training curve
    (every epoch) and the K = 0 test at the checkpoints, mean and min–max over seeds."""
    long = [r for r in _row_order(runs) if int(runs.rows[r]["epochs"]) > 10]
    if not long:
        return False
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.4))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, row in enumerate(long):
        c = runs.curves(row) * 100
        if c.size:
            _band(axes[0], np.arange(1, c.shape[1] + 1), c, colors[k % 10], f"ours: {row}")
        checks = sorted({int(m.rsplit("_e", 1)[1]) for r in runs.runs if r["row"] == row
                         for m in r["metrics"] if m.startswith("test_nrmse_e")})
        m = np.array([[r["metrics"].get(f"test_nrmse_e{e}") or np.nan for e in checks]
                      for r in runs.runs if r["row"] == row], float) * 100
        _band(axes[1], checks, m, colors[k % 10], f"ours: {row}")
    for ax, title in zip(axes, ("last training epoch (K = 0.65)", "K = 0 test"), strict=True):
        ax.axhspan(10, 20, color="0.5", alpha=0.15, label="thesis text: inverse only 10–20 %")
        ax.set(xscale="log", xlabel="epochs trained", ylabel="position NRMSE %", title=title)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    axes[1].set_yscale("log")
    save_figure(fig, path)
    return True


def fig6(runs: Runs, path: Path) -> bool:
    """Thesis Fig. 6 redrawn: prediction error per training mode, mean ± sd, by delay."""
    groups = [(fi, d) for fi in ("sensed", "chained")
              for d in sorted({p["delay"] for p in runs.rows.values()})
              if all(runs.find(a, fi, d) for a in ("serial", "parallel", "hybrid"))]
    if not groups:
        return False
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8, 4.2))
    for k, arch in enumerate(("parallel", "serial", "hybrid")):
        vals = [runs.get(row, f"train_pred_nrmse_e{_pe(runs, row)}") * 100
                for row in (runs.find(arch, fi, d) for fi, d in groups)]
        ax.bar(np.arange(len(groups)) + (k - 1) * 0.27, [v.mean() for v in vals], 0.27,
               yerr=[v.std(ddof=1) if len(v) > 1 else 0 for v in vals], capsize=3,
               color=COLORS[arch], label=f"ours: {arch}")
    ax.set_xticks(np.arange(len(groups)), [f"{fi}\nd{d}" for fi, d in groups])
    ax.set(ylabel="prediction NRMSE %, last training epoch (10 epochs)",
           title="Paper A Fig. 6 redrawn: thesis says serial highest, parallel ≈ hybrid")
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=8)
    save_figure(fig, path)
    return True


def report(results, plan, out_dir: Path) -> str:
    """The study's report: tables.md (error and prediction-error tables, the claims) and
    the figures."""
    return write_report(Path(out_dir))


def write_report(out_dir: Path, extra_dirs: tuple[Path, ...] = ()) -> str:
    """tables.md and the figures in ``out_dir``, from its runs and those of ``extra_dirs``
    (sweeps of other rows of the same config, e.g. run apart); returns the claims."""
    runs = Runs(out_dir, *extra_dirs)
    lines = claims(runs)
    fig5(runs, out_dir / "fig5_band.png")
    figs = ["fig5_band.png"]
    if fig_epochs(runs, out_dir / "fig_epochs.png"):
        figs.append("fig_epochs.png")
    if fig6(runs, out_dir / "fig6_prediction.png"):
        figs.append("fig6_prediction.png")
    text = ("# fidelity-a\n\nMean (min–max) over seeds; % = value × 100. Mean difference = "
            "mean |desired − actual| / 2 (fraction of the range 2); × 2 for the half-range "
            "reading.\n\n## The thesis's numbers beside ours\n\n" + thesis_table(runs)
            + "\n\n## Performance error\n\n" + error_table(runs)
            + "\n\n## Prediction error (NRMSE %, mean ± sd, last training epoch)\n\n"
            + prediction_table(runs) + "\n\n## Claims\n\n" + "\n".join(lines)
            + "\n\nFigures: " + ", ".join(figs) + "\n")
    atomic_write_text(out_dir / "tables.md", text)
    return "\n".join(lines)


if __name__ == "__main__":  # python -m skinny_mj.experiments.fidelity_a.report OUT [MORE_SWEEPS...]
    import json
    import sys

    dirs = [Path(a) for a in sys.argv[1:]]
    config = json.loads((dirs[0] / "config.json").read_text())["config"]
    for d in dirs[1:]:
        if json.loads((d / "config.json").read_text())["config"] != config:
            raise SystemExit(f"{d} was run with another config than {dirs[0]}")
    print(write_report(dirs[0], tuple(dirs[1:])))
