"""``skinny bench``'s goals and the table it prints: each figure's value against its goal
(:mod:`skinny_mj.cli.bench` measures them)."""

from __future__ import annotations

from typing import Any

import numpy as np

from skinny_mj.cli.bench_floor import floor_lines

__all__ = ["BENCH_EXTRA", "GOALS", "shown", "summary", "table"]

#: Each figure's goal, (comparison, value); :mod:`skinny_mj.cli.bench` says what each is.
GOALS = {
    "esn_run_vs_reservoirpy_N200": (">=", 2.0),
    "esn_run_vs_reservoirpy_N1000": (">=", 3.0),
    "control_step_over_physics": ("<=", 3.0),
    "lockstep_speedup": (">=", 3.0),
    "fast_vs_naive": (">=", 6.0),
    "paper_e_full_s": ("<=", 20.0),
    "torque_over_kinematic": ("<=", 2.0),
    "mackey_glass_log10_nrmse84": ("<=", -4.5),
}
#: How to install what the reservoirpy figures need (the ``bench`` extra).
BENCH_EXTRA = 'pip install -e ".[bench]"'


def summary(figures: dict) -> dict[str, dict]:
    """Each goal's measured value and whether it is met (None: not measured, with the
    figure's ``skipped`` reason when it gave one)."""
    def node_at(path: list) -> Any:
        node: Any = figures
        for key in path:
            if isinstance(node, dict) and key in node:
                node = node[key]
            elif isinstance(node, list) and isinstance(key, int) and key < len(node):
                node = node[key]
            else:
                return None
        return node

    paths = {
        "esn_run_vs_reservoirpy_N200": ["esn_run_vs_reservoirpy", 0, "ratio"],
        "esn_run_vs_reservoirpy_N1000": ["esn_run_vs_reservoirpy", 1, "ratio"],
        "control_step_over_physics": ["control_step_over_physics", "ratio"],
        "lockstep_speedup": ["lockstep_speedup", "ratio"],
        "fast_vs_naive": ["fast_vs_naive", "ratio"],
        "paper_e_full_s": ["paper_e_full_s", "wall_s"],
        "torque_over_kinematic": ["torque_over_kinematic", "ratio"],
        "mackey_glass_log10_nrmse84": ["mackey_glass", "ours_log10_nrmse84"],
    }
    out = {}
    for key, path in paths.items():
        node, figure = node_at(path), node_at(path[:-1])
        value = float(node) if isinstance(node, int | float) else None
        op, goal = GOALS[key]
        met = None if value is None else (value >= goal if op == ">=" else value <= goal)
        out[key] = {"value": value, "goal": f"{op} {goal:g}", "met": met}
        if value is None and isinstance(figure, dict) and "skipped" in figure:
            out[key]["skipped"] = str(figure["skipped"])
    return out


def shown(value: float, op: str, goal: float) -> str:
    """``value`` to 3 significant digits, or to as many more as it takes for the printed
    number to be on the goal's side that ``value`` is on and not to read as the goal
    itself (``2.0004`` against ``<= 2`` prints as 2.0004, not as 2); past 12 digits, the
    shortest text that reads back as ``value`` (``repr``)."""
    def met(x: float) -> bool:
        return x >= goal if op == ">=" else x <= goal

    for digits in (3, 6, 9, 12):
        text = f"{value:.{digits}g}"
        if met(float(text)) == met(value) and (float(text) != goal or value == goal):
            return text
    return repr(value)


def table(figures: dict) -> str:
    """The summary as a plain-text table, with the machine load; a figure not measured
    says why (a missing extra names its install command)."""
    rows = []
    for key, row in figures["summary"].items():
        if row["value"] is None:
            value = "skipped"
        else:
            op, goal = GOALS[key]
            value = shown(row["value"], op, goal)
        met = {True: "yes", False: "NO", None: "-"}[row["met"]]
        if "skipped" in row:
            met += f"  {row['skipped']}"
        rows.append((key, value, row["goal"], met))
    width = max(10, *(len(value) for _, value, _, _ in rows))
    lines = [f"{'figure':<30} {'measured':>{width}} {'goal':>8}  met",
             "-" * (46 + width)]
    lines += [f"{key:<30} {value:>{width}} {goal:>8}  {met}" for key, value, goal, met in rows]
    strict = figures.get("control_step_over_physics", {}).get("ratio_vs_batch_physics")
    if strict is not None:
        lines.append(f"{'  same, over batch-model physics':<30} {strict:>{width}.3g} {'-':>8}  "
                     "(the R-robot model the fast path steps: a stricter floor)")
        step = figures["control_step_over_physics"]
        floor = step.get("floor_vs_batch_physics")
        if floor is not None and np.isfinite(floor):
            lines.append(f"{'  floor, over batch physics':<30} {floor:>{width}.3g} {'-':>8}  "
                         "(physics + sparse product + tanh + noise)")
        if "python_lines_per_step" in step:
            lines.append(f"{'  Python lines per step':<30} "
                         f"{step['python_lines_per_step']:>{width}.4g} {'-':>8}  "
                         "(the package's own)")
    lines += floor_lines(figures.get("esn_run_vs_reservoirpy", []))
    if figures.get("quick"):
        lines.append("--quick: short timings, few trials; torque_over_kinematic times one "
                     "epoch of each row, not the rows' 15 and 10, so it is a smoke test, not "
                     "that goal's figure")
    start, end = figures["load_avg_start"], figures["load_avg_end"]
    lines.append(f"load average (1 min) {start[0]:.2f} -> {end[0]:.2f} on "
                 f"{figures['cpu_count']} CPUs: ratios are timed interleaved, "
                 "absolute times shift with load")
    return "\n".join(lines)
