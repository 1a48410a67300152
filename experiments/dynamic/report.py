"""The dynamic study's report: what the movements ask of the motors, the goals, the torque
limits and warnings, and the wall-time ratio, from a sweep's run files
(:mod:`skinny_mj.experiments.dynamic.study`)."""

from __future__ import annotations

import statistics
from pathlib import Path

from skinny_mj.experiments.claims import values
from skinny_mj.experiments.dynamic import general
from skinny_mj.experiments.dynamic.study import (
    ARM_GOALS,
    BODIES,
    CT_JOINT_GOAL,
    GOALS,
    RECORDED,
    TORQUE_BUDGET,
    YMCA,
)

from skinny_mj.plant import body
from skinny_mj.training.config import TrainConfig
from skinny_mj.training.imitation import movement_stats
from skinny_mj.training.parts import load_trajectory
from skinny_mj.training.torque import feasibility


def torque_movement(dof: int, name: str):
    """The movement ``name`` as the torque body of ``dof`` DOFs loads it."""
    return load_trajectory(TrainConfig().override({
        "plant.dof": dof, "movement.trajectory": name, "actuation": "torque"}))[0]


def feasibility_table(movements: tuple[str, ...], bodies: tuple[str, ...]) -> list[str]:
    """Markdown rows: what each movement asks of each body's motors (inverse dynamics of
    the desired motion, :meth:`skinny_mj.plant.dynamics.Dynamics.feasibility`), the DOF
    with the largest peak named."""
    lines = ["| movement | body | peak \\|τ\\|/limit (DOF) | p99 | steps over a limit | "
             "mean \\|τ\\| (N m) | peak speed (rad/s) | peak accel (rad/s²) | motor work (J) "
             "| feasible |", "|---|---|---|---|---|---|---|---|---|---|"]
    for mv in movements:
        for bd in bodies:
            dof = BODIES[bd]
            f = feasibility(dof, torque_movement(dof, mv))
            worst = int(f["peak_ratio"].argmax())
            lines.append(
                f"| {mv} | {bd} | {f['peak_ratio'][worst]:.2f} "
                f"({body.body_of(dof).dof_names[worst]}) | {f['p99_ratio'].max():.2f} | "
                f"{100 * f['over_limit_share'].max():.1f} % | {f['mean_abs_nm'].mean():.2f} | "
                f"{f['peak_speed_rad_s'].max():.1f} | {f['peak_accel_rad_s2'].max():.0f} | "
                f"{f['work_j'].sum():.0f} | {'yes' if f['feasible'] else '**no**'} |")
    return lines


def floor(dof: int, name: str) -> float:
    """The position NRMSE of the best reachable pose of a movement (no controller beats it)."""
    return movement_stats(torque_movement(dof, name))["reachable_floor_position_nrmse"]


def _mean(out_dir: Path, row: str, metric: str) -> float | None:
    v = values(out_dir, row, metric)
    return statistics.fmean(v) if v else None


def arm_report(out_dir: Path, bodies: tuple[str, ...]) -> list[str]:
    """The goals of the arm-dynamics rows, from the run files."""
    lines = []
    for bd in bodies:
        dof = BODIES[bd]
        for mv, name in (("ymca", YMCA), ("rec", RECORDED)):
            ct = _mean(out_dir, f"{bd}-{mv}-arm-ct", "joint_nrmse")
            if ct is not None:
                tau = _mean(out_dir, f"{bd}-{mv}-arm-ct", "mean_abs_torque_nm")
                need = float(feasibility(dof, torque_movement(dof, name))["mean_abs_nm"].mean())
                peak = max(values(out_dir, f"{bd}-{mv}-arm-ct", "max_torque_ratio"))
                lines.append(f"goal {bd} {mv} computed torque joint NRMSE <= {CT_JOINT_GOAL}: "
                             f"{ct:.4f}; mean |τ| {tau:.2f} N m = {tau / need:.2f}x the "
                             f"movement's need {need:.2f} (goal <= {TORQUE_BUDGET}x); max "
                             f"|τ|/limit {peak:.3f}")
            fel = _mean(out_dir, f"{bd}-{mv}-fel-arm", "position_nrmse")
            pd = _mean(out_dir, f"{bd}-{mv}-arm-pd", "position_nrmse")
            if fel is not None:
                goal = f" (goal <= {ARM_GOALS[bd]})" if mv == "ymca" else \
                    f" (goal <= the reachable floor {floor(dof, name):.4f} + 0.01)"
                lines.append(f"goal {bd} {mv} ESN + FEL inertia-scaled teacher (K = 0) "
                             f"position NRMSE{goal}: {fel:.4f} over "
                             f"{len(values(out_dir, f'{bd}-{mv}-fel-arm', 'position_nrmse'))} "
                             "runs" + (f"; PD alone with the same gains {pd:.4f} "
                                       f"({pd / fel:.1f}x, goal >= 3x)" if pd else ""))
    return lines


def learning_curves(results, rows: tuple[str, ...]) -> list[str]:
    """Per epoch, the mean over a row's ok runs of the position NRMSE and the feedback
    share |K u_fb| / |u| on the epoch's evaluation cycle (the learning curve)."""
    lines = []
    for row in rows:
        curves = {k: [r["metrics"][f"curve_{k}"] for r in results.runs(row)
                      if isinstance(r["metrics"].get(f"curve_{k}"), list)]
                  for k in ("position_nrmse", "feedback_share")}
        if not curves["position_nrmse"]:
            continue
        for key, label in (("position_nrmse", "position NRMSE"),
                           ("feedback_share", "feedback share")):
            per_epoch = [statistics.fmean(v) for v in zip(*curves[key], strict=True)]
            lines.append(f"learning curve {row}, {label} per epoch (mean of "
                         f"{len(curves[key])} runs): " + " ".join(f"{x:.4f}" for x in per_epoch))
    return lines


def _ratio(out_dir: Path, row: str, kin: list[float]) -> float | None:
    v = values(out_dir, row, "train_wall_s")
    return statistics.fmean(v) / statistics.fmean(kin) if v and kin else None


def report(results, plan, out_dir: Path) -> str:
    """The movements' feasibility, the goals, the torque limits and warnings, and the
    wall-time ratio, from the run files on disk."""
    out_dir = Path(out_dir)
    bodies = tuple(bd for bd, dof in BODIES.items()
                   if any(c.plant.dof == dof for c in plan.configs.values()))
    clip = plan.base.movement.trajectory
    lines = ["what the movements ask of the motors (inverse dynamics of the desired motion):",
             *feasibility_table((YMCA, RECORDED, clip), bodies)]
    lines += [f"NOT FEASIBLE on this body: {ln.split('|')[1].strip()} "
              f"({ln.split('|')[2].strip()}): no controller within the limits can track it"
              for ln in lines[3:] if ln.endswith("**no** |")]
    for bd in bodies:
        for ctl in ("fel-orig", "fel-new", "fel-new-gff", "tt"):
            v = values(out_dir, f"{bd}-ymca-{ctl}", "position_nrmse")
            if v:
                hits = sum(x <= GOALS[bd] for x in v)
                lines.append(f"goal {bd} YMCA {ctl} (K = 0) position NRMSE <= {GOALS[bd]}: "
                             f"{hits} / {len(v)} runs, best {min(v):.4f}")
    lines += arm_report(out_dir, bodies)
    lines += learning_curves(results, tuple(f"{bd}-ymca-fel-arm" for bd in bodies))
    rows = [r.id for r in plan.rows]
    lines += general.report_lines(out_dir, tuple(rows), {bd: BODIES[bd] for bd in bodies})
    ratios = [x for r in rows for x in values(out_dir, r, "max_torque_ratio")]
    warns = [x for r in rows for x in values(out_dir, r, "warnings")]
    if ratios:
        lines.append(f"max |torque| / limit over {len(ratios)} runs: {max(ratios):.6f}")
    if warns:
        lines.append(f"MuJoCo warnings over {len(warns)} runs: {int(sum(warns))}")
    kin = values(out_dir, "2d-ymca-kinematic", "train_wall_s")
    timed = ("training wall per run in this sweep (the rows ran at different times, under "
             "whatever load the machine had: not the goal's figure, which `skinny bench` "
             "times interleaved as torque_over_kinematic)")
    if (ratio := _ratio(out_dir, "2d-ymca-fel-new", kin)) is not None:
        lines.append(f"{timed}, torque FEL new / kinematic (2D YMCA): {ratio:.2f}x")
    if (ratio := _ratio(out_dir, "2d-ymca-fel-arm", kin)) is not None:
        arm, ref = plan.config("2d-ymca-fel-arm"), plan.config("2d-ymca-kinematic")
        lines.append(f"{timed}, torque FEL inertia-scaled teacher ({arm.method.epochs} "
                     f"epochs) / kinematic ({ref.method.epochs} epochs), 2D YMCA: "
                     f"{ratio:.2f}x")
    return "\n".join(lines)
