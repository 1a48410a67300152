"""paper-e-explain's table, claims and Figs. 7–10, from a sweep's run files only.

Figures (``out_dir/fig7_exp1.png`` …): the top row shows one network (run index 0,
the same initial network in all three rows) as the thesis's panels do; the bottom row
shows the per-epoch numbers of every run, mean ± sd over runs.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from skinny_mj.experiments.paper_e_explain.study import EXPS

from skinny_mj.engine.stats import load_runs
from skinny_mj.io import atomic_write_text
from skinny_mj.plots import pyplot, save_figure
from skinny_mj.training.parts import full_scale_speeds, load_trajectory, true_commands_of

TABLE_EPOCHS = (1, 2, 5, 10)
#: table rows: (run-file key, label)
QUANTITIES = (
    ("est_nrmse", "y_est NRMSE"), ("used_nrmse", "y_used NRMSE"),
    ("esn_nrmse", "ESN output NRMSE (eval cycle)"),
    ("est_rough", "y_est roughness"), ("used_rough", "y_used roughness"),
    ("esn_learn_rough", "ESN output roughness (learning cycle)"),
    ("esn_rough", "ESN output roughness (eval cycle)"),
    ("tf_position_nrmse", "teacher forcing: position NRMSE (learning cycle)"),
)
LABEL = {"1": "exp 1 (original, 1 rep)", "2": "exp 2 (original, 5 reps)",
         "5": "exp 5 (new, β = 0.1)"}
DOF_NAMES = ("right shoulder", "right elbow", "left shoulder", "left elbow")


def _runs(out_dir: Path) -> dict[str, list[dict]]:
    out: dict[str, list[dict]] = {e: [] for e in EXPS}
    for rec in load_runs(out_dir):
        if rec.get("status") == "ok" and rec["row"] in out:
            out[rec["row"]].append(rec)
    return out


def curves(runs: list[dict], key: str) -> np.ndarray:
    """(R, E) per-epoch values of ``key`` of the runs that have it (None -> NaN)."""
    rows = [[np.nan if v is None else v for v in r["metrics"][key]] for r in runs
            if key in r["metrics"]]
    return np.array(rows, float) if rows else np.full((0, 0), np.nan)


def _paired(by_row: dict[str, list[dict]], a: tuple[str, str, int], b: tuple[str, str, int]
            ) -> tuple[np.ndarray, np.ndarray]:
    """Values (row, key, epoch) of a and b for the run indices both have (same network)."""
    def values(row: str, key: str, epoch: int) -> dict[int, float]:
        out = {}
        for r in by_row[row]:
            series = r["metrics"].get(key, [])
            if epoch <= len(series) and series[epoch - 1] is not None:
                out[r["run_index"]] = series[epoch - 1]
        return out
    va, vb = values(*a), values(*b)
    common = sorted(set(va) & set(vb))
    return np.array([va[k] for k in common]), np.array([vb[k] for k in common])


def claims(by_row: dict[str, list[dict]], epochs: int) -> list[str]:
    """The thesis's §5.1 statements, each checked seed by seed (paired: same network)."""
    e5, last = min(5, epochs), epochs
    checks = (  # (statement "a > b", a, b): a, b = (row, key, epoch); b None: the true
        ("Fig. 7: exp 1's estimated target is noisier than the true target (epoch 1): "
         "roughness(y_est) > roughness(true commands)", ("1", "est_rough", 1), None),
        ("Fig. 7: training on it makes the ESN output even noisier (exp 1, epoch 1): "
         "roughness(ESN output after the fit) > roughness(y_est)",
         ("1", "esn_rough", 1), ("1", "est_rough", 1)),
        (f"Fig. 7: \"this only gets worse\" (exp 1): ESN output NRMSE epoch {last} > epoch 1",
         ("1", "esn_nrmse", last), ("1", "esn_nrmse", 1)),
        (f"Fig. 8: repetitions make the ESN output less noisy: roughness(ESN output) "
         f"exp 1 > exp 2 (epoch {last})", ("1", "esn_rough", last), ("2", "esn_rough", last)),
        (f"Fig. 9: y_used is less noisy than y_est (exp 5, epoch {e5}): roughness "
         "y_est > y_used", ("5", "est_rough", e5), ("5", "used_rough", e5)),
        (f"Fig. 9: y_used is closer to the true target than y_est (exp 5, epoch {e5}): "
         "NRMSE y_est > y_used", ("5", "est_nrmse", e5), ("5", "used_nrmse", e5)),
        (f"Fig. 9: the ESN output after the fit is smoother than y_est (exp 5, epoch {e5}): "
         "roughness y_est > ESN output", ("5", "est_rough", e5), ("5", "esn_rough", e5)),
        (f"extra: the new method's ESN output is smoother than exp 2's (epoch {last}): "
         "roughness exp 2 > exp 5", ("2", "esn_rough", last), ("5", "esn_rough", last)),
        (f"Fig. 10: better teacher forcing with the new method (epoch {e5}): position "
         "NRMSE exp 1 > exp 5", ("1", "tf_position_nrmse", e5), ("5", "tf_position_nrmse", e5)),
        (f"Fig. 10: better teacher forcing with the new method (epoch {e5}): position "
         "NRMSE exp 2 > exp 5", ("2", "tf_position_nrmse", e5), ("5", "tf_position_nrmse", e5)),
    )
    lines = []
    for text, a, b in checks:
        if b is None:  # compare with the true commands' roughness
            runs = [r for r in by_row[a[0]] if len(r["metrics"].get(a[1], [])) >= a[2]
                    and r["metrics"][a[1]][a[2] - 1] is not None]
            va = np.array([r["metrics"][a[1]][a[2] - 1] for r in runs])
            vb = np.array([r["metrics"]["true_rough"] for r in runs])
        else:
            va, vb = _paired(by_row, a, b)
        if va.size == 0:
            lines.append(f"- [no runs] {text}")
            continue
        n_hold = int(np.sum(va > vb))
        verdict = "holds" if n_hold == va.size else "does NOT hold" if n_hold == 0 \
            else f"holds in {n_hold} of {va.size} runs"
        lines.append(f"- [{verdict}] {text}: {np.mean(va):.4g} vs {np.mean(vb):.4g} "
                     f"(means, ratio {np.mean(va) / np.mean(vb):.3g}; {n_hold} / {va.size} "
                     "runs)")
    return lines


def table(by_row: dict[str, list[dict]], epochs: int) -> str:
    """Per quantity and exp: mean (sd) over ok runs at a few epochs."""
    shown = [e for e in TABLE_EPOCHS if e <= epochs] or [epochs]
    head = "| quantity | exp | " + " | ".join(f"epoch {e}" for e in shown) + " |"
    lines = [head, "|---|---|" + "---|" * len(shown)]
    for key, label in QUANTITIES:
        for exp in EXPS:
            c = curves(by_row[exp], key)
            if c.size == 0:
                continue
            cells = []
            for e in shown:
                v = c[:, e - 1][np.isfinite(c[:, e - 1])]
                cells.append("—" if v.size == 0 else f"{v.mean():.4f} ({v.std():.4f})")
            lines.append(f"| {label} | {exp} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def write_report(out_dir: Path, plan) -> str:
    """explain.md and Figs. 7–10 of the sweep ``plan`` in ``out_dir``."""
    by_row = _runs(out_dir)
    cfg = plan.config(EXPS[0])
    epochs = cfg.method.epochs
    true_rough = [r["metrics"]["true_rough"] for runs in by_row.values() for r in runs]
    n = {e: len(by_row[e]) for e in EXPS}
    diverged = {e: sum(r["metrics"]["diverged"] for r in by_row[e]) for e in EXPS}
    text = "\n".join([
        f"Movement `{cfg.movement.trajectory}`, {epochs} epochs, N = {cfg.esn.n_reservoir}; "
        "runs per exp "
        + ", ".join(f"{e}: {n[e]} ({diverged[e]} diverged)" for e in EXPS) + ".",
        f"Roughness of the true commands: {np.mean(true_rough):.4f}" if true_rough else "",
        "", "Mean (sd) over runs; y_est / y_used of the epoch's last learning cycle; "
        "NRMSE against the true commands (motor units), roughness = RMS of the second "
        "difference (per DOF, then averaged).", "", table(by_row, epochs), "",
        "## Claims (paired: the same network in every exp)", *claims(by_row, epochs), ""])
    atomic_write_text(out_dir / "explain.md", text)
    for fig in (fig7, fig8, fig9, fig10):
        fig(out_dir, plan, by_row)
    return text


# -- figures ------------------------------------------------------------------------------
def _example(runs: list[dict]) -> dict | None:
    """The run of the lowest run index with kept signals (the same network in every
    exp)."""
    kept = [r for r in runs if r["metrics"].get("series") is not None]
    return min(kept, key=lambda r: r["run_index"]) if kept else None


def _series(run: dict, key: str, epoch: int) -> np.ndarray | None:
    s = None if run is None else run["metrics"].get("series")
    if s is None or epoch not in s["epochs"]:
        return None
    return np.asarray(s[key][s["epochs"].index(epoch)], float)


def _commands_panel(ax, y: np.ndarray | None, title: str) -> None:
    if y is None:
        ax.set_title(title + " (diverged)", fontsize=9)
        return
    for j in range(y.shape[1]):
        ax.plot(y[:, j], lw=0.8, label=DOF_NAMES[j] if j < len(DOF_NAMES) else f"DOF {j}")
    ax.set_ylim(-1.05, 1.05)
    ax.set_title(title, fontsize=9)
    ax.set_xlabel("time step", fontsize=8)
    ax.tick_params(labelsize=7)


def _band(ax, runs: list[dict], key: str, label: str, style: str = "-") -> None:
    c = curves(runs, key)
    if c.size == 0:
        return
    x = np.arange(1, c.shape[1] + 1)
    with np.errstate(all="ignore"):
        mean, sd = np.nanmean(c, axis=0), np.nanstd(c, axis=0)
    (line,) = ax.plot(x, mean, style, marker="o", ms=3, label=label)
    ax.fill_between(x, mean - sd, mean + sd, color=line.get_color(), alpha=0.2)


def _epoch_axes(ax, ylabel: str, true_rough: float | None = None, log: bool = True) -> None:
    if true_rough is not None:
        ax.axhline(true_rough, color="k", ls="--", lw=0.8, label="true commands")
    from matplotlib.ticker import MaxNLocator

    if log:
        ax.set_yscale("log")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("epoch", fontsize=8)
    ax.set_ylabel(ylabel, fontsize=8)
    ax.tick_params(labelsize=7, which="both")
    ax.legend(fontsize=7)


def _movement(plan) -> str:
    return plan.base.movement.trajectory


def _epochs(plan) -> int:
    return plan.config(EXPS[0]).method.epochs


def _true_commands(plan, exp: str) -> np.ndarray:
    tc = plan.config(exp)
    traj, _ = load_trajectory(tc)
    return true_commands_of(tc, traj, full_scale_speeds(tc, traj))


def _true_rough(runs: list[dict]) -> float | None:
    return runs[0]["metrics"]["true_rough"] if runs else None


def _figure(n_top: int):
    plt = pyplot()
    fig = plt.figure(figsize=(3.2 * max(n_top, 2), 6.4))
    grid = fig.add_gridspec(2, 2 * n_top)
    top = [fig.add_subplot(grid[0, 2 * i:2 * i + 2]) for i in range(n_top)]
    half = n_top
    bottom = [fig.add_subplot(grid[1, :half]), fig.add_subplot(grid[1, half:])]
    return fig, top, bottom


def fig7(out_dir: Path, plan, by_row: dict[str, list[dict]]) -> Path | None:
    """Fig. 7: why exp 1 fails (true target, initial output, y_est and the output after
    training in epoch 1), and per epoch roughness / NRMSE of y_est and the ESN output."""
    runs = by_row["1"]
    ex = _example(runs)
    if ex is None:
        return None
    fig, top, (rough, err) = _figure(4)
    _commands_panel(top[0], _true_commands(plan, "1"), "(a) true target")
    _commands_panel(top[1], np.asarray(ex["metrics"]["series"]["initial_output"], float),
                    "(b) initial ESN output (W_out = 0)")
    _commands_panel(top[2], _series(ex, "y_est", 1), "(c) y_est, epoch 1")
    _commands_panel(top[3], _series(ex, "y_esn", 1), "(d) ESN output after fit, epoch 1")
    top[0].legend(fontsize=6)
    for key, label in (("est_rough", "y_est"), ("esn_rough", "ESN output (eval)")):
        _band(rough, runs, key, label)
    _epoch_axes(rough, "roughness (RMS 2nd difference)", _true_rough(runs))
    for key, label in (("est_nrmse", "y_est"), ("esn_nrmse", "ESN output (eval)")):
        _band(err, runs, key, label)
    _epoch_axes(err, "NRMSE vs true commands", log=False)
    fig.suptitle(f"Exp 1 (original, 1 rep), {_movement(plan)}: example run "
                 f"(seed {ex['metrics']['network_seed']}); bottom: mean ± sd, "
                 f"{len(runs)} runs", fontsize=9)
    return save_figure(fig, out_dir / "fig7_exp1.png")


def fig8(out_dir: Path, plan, by_row: dict[str, list[dict]]) -> Path | None:
    """Fig. 8: the ESN output after training, exp 1 vs exp 2 (repetitions)."""
    if not by_row["1"] or not by_row["2"]:
        return None
    fig, top, (rough, err) = _figure(2)
    last, exp_reps = _epochs(plan), {"1": "1 rep", "2": "5 reps"}
    for ax, exp, tag in ((top[0], "1", "(a)"), (top[1], "2", "(b)")):
        _commands_panel(ax, _series(_example(by_row[exp]), "y_esn", last),
                        f"{tag} exp {exp}, {exp_reps[exp]}: ESN output, epoch {last}")
    top[0].legend(fontsize=6)
    for exp in ("1", "2"):
        _band(rough, by_row[exp], "esn_rough", LABEL[exp])
        _band(err, by_row[exp], "esn_nrmse", LABEL[exp])
    _epoch_axes(rough, "ESN output roughness (eval)", _true_rough(by_row["1"]))
    _epoch_axes(err, "ESN output NRMSE vs true commands", log=False)
    fig.suptitle(f"Repetitions, {_movement(plan)}: same initial network; bottom: mean ± sd "
                 "over runs", fontsize=9)
    return save_figure(fig, out_dir / "fig8_reps.png")


def fig9(out_dir: Path, plan, by_row: dict[str, list[dict]]) -> Path | None:
    """Fig. 9: exp 5 in epoch 5: y_est, y_used, the ESN output after the fit; per epoch
    roughness / NRMSE of the three (and exp 1's y_est for reference)."""
    runs = by_row["5"]
    ex = _example(runs)
    if ex is None:
        return None
    e5 = min(5, _epochs(plan))
    fig, top, (rough, err) = _figure(3)
    _commands_panel(top[0], _series(ex, "y_est", e5), f"(a) y_est, epoch {e5}")
    _commands_panel(top[1], _series(ex, "y_used", e5), f"(b) y_used, epoch {e5}")
    _commands_panel(top[2], _series(ex, "y_esn", e5), f"(c) ESN output after fit, epoch {e5}")
    top[0].legend(fontsize=6)
    for key, label in (("est", "y_est"), ("used", "y_used"), ("esn", "ESN output (eval)")):
        _band(rough, runs, f"{key}_rough", label)
        _band(err, runs, f"{key}_nrmse", label)
    _band(rough, by_row["1"], "est_rough", "exp 1 y_est", ":")
    _band(err, by_row["1"], "est_nrmse", "exp 1 y_est", ":")
    _epoch_axes(rough, "roughness (RMS 2nd difference)", _true_rough(runs))
    _epoch_axes(err, "NRMSE vs true commands", log=False)
    fig.suptitle(f"Exp 5 (new, β = 0.1), {_movement(plan)}: last learning cycle of each epoch; "
                 "bottom: mean ± sd over runs", fontsize=9)
    return save_figure(fig, out_dir / "fig9_exp5.png")


def fig10(out_dir: Path, plan, by_row: dict[str, list[dict]]) -> Path | None:
    """Fig. 10: teacher forcing in epoch 5: the plant's positions (one repetition)
    beside the desired ones, and the position NRMSE of the learning cycles per epoch."""
    if not any(by_row.values()):
        return None
    e5 = min(5, _epochs(plan))
    tc = plan.config("1")
    desired = load_trajectory(tc)[0].position_signals(tc.plant.signals)
    fig, top, (curve, box) = _figure(3)
    for ax, exp, tag in zip(top, EXPS, ("(a)", "(b)", "(c)"), strict=True):
        ex = _example(by_row[exp])
        pos = None if ex is None else _series(ex, "positions", e5)
        ax.plot(desired, color="0.6", lw=0.8, ls="--")
        if pos is not None:
            ax.set_prop_cycle(None)
            ax.plot(pos, lw=0.8)
        ax.set_ylim(-1.05, 1.05)
        ax.set_title(f"{tag} {LABEL[exp]}, epoch {e5}", fontsize=9)
        ax.set_xlabel("time step (dashed: desired)", fontsize=8)
        ax.tick_params(labelsize=7)
    for exp in EXPS:
        _band(curve, by_row[exp], "tf_position_nrmse", LABEL[exp])
    _epoch_axes(curve, "position NRMSE, learning cycle", log=False)
    data = [curves(by_row[e], "tf_position_nrmse")[:, e5 - 1] if by_row[e] else np.array([])
            for e in EXPS]
    box.boxplot([d[np.isfinite(d)] for d in data])
    box.set_xticks(range(1, len(EXPS) + 1), [f"exp {e}" for e in EXPS])
    box.set_yscale("log")
    box.set_ylabel(f"position NRMSE, epoch {e5}", fontsize=8)
    box.tick_params(labelsize=7, which="both")
    fig.suptitle(f"Teacher forcing, {_movement(plan)}: 8 position signals of the plant "
                 "during the learning cycle", fontsize=9)
    return save_figure(fig, out_dir / "fig10_teacher_forcing.png")


def report(results: dict, plan, out_dir: Path) -> str:
    """explain.md (per-epoch table) and fig7_*.png … fig10_*.png."""
    return write_report(Path(out_dir), plan)
