"""Does the torque twin survive saturated torques? A stress test per model variant, and
what the chosen armature costs in fidelity. Prints two tables.

    MUJOCO_GL=disabled OMP_NUM_THREADS=1 python benchmarks/torque_stability_check.py [--runs 20]

Stress test: ``--runs`` episodes of 10 s per variant, each from a random pose inside the
joint ranges, every motor at full torque (ctrl = ±1, the chattering FEL-original rows'
commands) with a random sign held for 1 .. ``hold`` control steps of 20 ms. An episode
fails at its first MuJoCo warning (``data.warning``: MuJoCo then resets the state).
Reported: failed / n, the first warning's kind, and over the episodes that stayed
finite the worst overshoot past a joint limit (rad) and the largest |qvel| (rad/s).

Variants of the 3D arm (the 2D arm is the control): the model as it was (armature 0,
RK4 at 5 ms), smaller RK4 steps with the same 20 ms control step, ``implicitfast`` and
``implicit`` at 1 ms, stiffer joint limits (solref time constant 10 ms = 2 steps,
MuJoCo's lower bound), and armature on the three shoulder hinges (0.5 ... 3.6e-3 kg m^2;
3.6e-3 = :data:`skinny_mj.plant.model.TORQUE_ARMATURE_3D_SHOULDER`, the chosen one).

``--limits``: the joint limits' hold alone, the worst overshoot past a limit with the
twin's limits (time constant 5 ms) and with MuJoCo's default 20 ms and 10 ms, on both
arms (``torque_limits_check.py`` adds full-torque drives into each limit).

The variants above set their limits' time constant as listed (the default 20 ms unless
"limits 10 ms").

Fidelity table: each 3D DOF's own inertia (diagonal of M) over 200 random poses with and
without the armature, and the largest change of the YMCA inverse-dynamics torques it
makes (share of the limit). Integrator accuracy of the chosen model: run
``benchmarks/torque_step_check.py`` (it loads the model as it is).
"""

from __future__ import annotations

import argparse
import os

os.environ.setdefault("MUJOCO_GL", "disabled")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from skinny_mj.plant import body  # noqa: E402
from skinny_mj.plant.body import body_of, by_dof  # noqa: E402
from skinny_mj.plant.model import TORQUE_ARMATURE_3D_SHOULDER, load_model  # noqa: E402

CONTROL_DT_S = 0.02
SECONDS = 10.0
RK4, IMPLICITFAST, IMPLICIT = (mujoco.mjtIntegrator.mjINT_RK4,
                               mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
                               mujoco.mjtIntegrator.mjINT_IMPLICIT)
#: label: (dof, shoulder armature kg m^2, integrator, timestep s, limit time constant s)
VARIANTS = {
    "2D as it is": (4, 0.0, RK4, 0.005, 0.02),
    "3D, armature 0 (before)": (8, 0.0, RK4, 0.005, 0.02),
    "3D, armature 0, RK4 2.5 ms": (8, 0.0, RK4, 0.0025, 0.02),
    "3D, armature 0, RK4 1 ms": (8, 0.0, RK4, 0.001, 0.02),
    "3D, armature 0, implicitfast 1 ms": (8, 0.0, IMPLICITFAST, 0.001, 0.02),
    "3D, armature 0, implicit 1 ms": (8, 0.0, IMPLICIT, 0.001, 0.02),
    "3D, armature 0, limits 10 ms": (8, 0.0, RK4, 0.005, 0.01),
    "3D, armature 5e-4": (8, 5e-4, RK4, 0.005, 0.02),
    "3D, armature 1e-3": (8, 1e-3, RK4, 0.005, 0.02),
    "3D, armature 3.6e-3 (chosen)": (8, TORQUE_ARMATURE_3D_SHOULDER, RK4, 0.005, 0.02),
}


def shoulder_dofs(model: mujoco.MjModel) -> np.ndarray:
    """DOF addresses of the shoulder hinges (both arms)."""
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or ""
             for j in range(model.njnt)]
    return np.array([model.jnt_dofadr[j] for j, n in enumerate(names) if "shoulder" in n])


def variant(dof: int, armature: float, integrator, timestep: float,
            limit_timeconst: float | None) -> mujoco.MjModel:
    """The torque twin with its shoulder armature, integrator, step and limits replaced."""
    model = load_model(by_dof(dof, "torque"))
    if dof == 8:
        model.dof_armature[shoulder_dofs(model)] = armature
    model.opt.integrator = integrator
    model.opt.timestep = timestep
    if limit_timeconst is not None:
        model.jnt_solref[:] = [limit_timeconst, 1.0]
    mujoco.mj_setConst(model, mujoco.MjData(model))
    return model


def episode(model: mujoco.MjModel, seed: int, hold: int) -> dict:
    """One stress episode (see the module docstring)."""
    data = mujoco.MjData(model)
    rng = np.random.default_rng(seed)
    lo, hi = model.jnt_range.T
    data.qpos[:] = rng.uniform(lo + 0.05, hi - 0.05)
    mujoco.mj_forward(model, data)
    sub = int(round(CONTROL_DT_S / model.opt.timestep))
    over, vmax, left = 0.0, 0.0, 0
    for _ in range(int(round(SECONDS / CONTROL_DT_S))):
        if left <= 0:
            data.ctrl[:] = rng.choice([-1.0, 1.0], model.nu)
            left = int(rng.integers(1, hold + 1))
        left -= 1
        mujoco.mj_step(model, data, sub)
        fired = [mujoco.mjtWarning(i).name for i, w in enumerate(data.warning) if w.number]
        if fired:
            return {"ok": False, "warning": fired[0]}
        over = max(over, float(np.max(np.maximum(lo - data.qpos, data.qpos - hi))))
        vmax = max(vmax, float(np.abs(data.qvel).max()))
    return {"ok": True, "over": over, "vmax": vmax}


def episodes(model: mujoco.MjModel, runs: int, hold: int) -> tuple[int, str, str, str]:
    """``runs`` stress episodes: failed count, first warnings' kinds, and over the ok
    episodes the worst overshoot past a limit (rad) and the largest |qvel| (rad/s)."""
    res = [episode(model, 1000 * hold + s, hold) for s in range(runs)]
    ok = [r for r in res if r["ok"]]
    kinds = sorted({r["warning"].replace("mjWARN_", "") for r in res if not r["ok"]})
    over = f"{max(r['over'] for r in ok):.2f}" if ok else "—"
    vmax = f"{max(r['vmax'] for r in ok):.0f}" if ok else "—"
    return len(res) - len(ok), ", ".join(kinds) or "—", over, vmax


def stress_table(runs: int, holds=(1, 5)) -> str:
    lines = ["| variant | hold (steps) | failed / n | first warnings | past limit (rad) |"
             " max \\|qvel\\| (rad/s) |", "|---|---|---|---|---|---|"]
    print("\n".join(lines))
    for label, spec in VARIANTS.items():
        model = variant(*spec)
        for hold in holds:
            failed, kinds, over, vmax = episodes(model, runs, hold)
            lines.append(f"| {label} | 1–{hold} | {failed} / {runs} |"
                         f" {kinds} | {over} | {vmax} |")
            print(lines[-1], flush=True)
    return "\n".join(lines)


def fidelity_table() -> str:
    from skinny_mj.plant.dynamics import Dynamics
    from skinny_mj.trajectories import get

    with_arm = Dynamics(load_model("3d-torque"), body_of("3d-torque"))
    bare_model = load_model("3d-torque")
    bare_model.dof_armature[:] = 0.0
    bare = Dynamics(bare_model, body_of("3d-torque"))
    (lo_a, hi_a), (lo_b, hi_b) = with_arm.inertia_range(), bare.inertia_range()
    angles = get("ymca", 8).angles
    d_tau = np.abs(with_arm.normalize(with_arm.trajectory_torques_nm(angles))
                   - bare.normalize(bare.trajectory_torques_nm(angles))).max(axis=0)
    lines = ["| DOF | own inertia, armature 0 (kg m²) | with armature (kg m²) |"
             " armature / smallest own inertia | YMCA: max \\|Δτ\\| / limit |",
             "|---|---|---|---|---|"]
    for i, name in enumerate(body.body_of(8).dof_names):
        arm = with_arm.model.dof_armature[with_arm.layout.dof_adr[i]]
        lines.append(f"| {name} | {lo_b[i]:.4f} – {hi_b[i]:.4f} | {lo_a[i]:.4f} – {hi_a[i]:.4f} |"
                     f" {arm / lo_b[i]:.0%} | {d_tau[i]:.1e} |")
    return "\n".join(lines)


def limits_table(runs: int, holds=(1, 5)) -> str:
    """The joint limits' hold under the same bang-bang torques: worst overshoot past a
    limit with the twin's limits (:data:`skinny_mj.plant.model.TORQUE_LIMIT_SOLREF`: time
    constant :data:`skinny_mj.plant.model.TORQUE_LIMIT_TIMECONST_S`) and with MuJoCo's
    default 20 ms and 10 ms (two physics steps, the bound of a positive time constant),
    on both arms."""
    from skinny_mj.plant.model import TORQUE_LIMIT_TIMECONST_S

    lines = ["| arm | limit time constant | hold (steps) | failed / n | past limit (rad) |"
             " max \\|qvel\\| (rad/s) |", "|---|---|---|---|---|---|"]
    print("\n".join(lines))
    for dof in (4, 8):
        arm = TORQUE_ARMATURE_3D_SHOULDER if dof == 8 else 0.0
        for label, tc in ((f"{1000 * TORQUE_LIMIT_TIMECONST_S:g} ms (the twin)", None),
                          ("20 ms (MuJoCo's default)", 0.02), ("10 ms", 0.01)):
            model = variant(dof, arm, RK4, 0.005, tc)
            for hold in holds:
                failed, _, over, vmax = episodes(model, runs, hold)
                lines.append(f"| {'2D' if dof == 4 else '3D'} | {label} | 1–{hold} | "
                             f"{failed} / {runs} | {over} | {vmax} |")
                print(lines[-1], flush=True)
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=20, help="episodes per variant and hold")
    parser.add_argument("--limits", action="store_true",
                        help="only the joint limits' overshoot, before and after")
    args = parser.parse_args()
    if args.limits:
        limits_table(args.runs)
        return
    print(f"stress: {args.runs} episodes x {SECONDS:g} s of full random-sign torques\n")
    stress_table(args.runs)
    print("\nfidelity of the chosen armature (3D)\n")
    print(fidelity_table())


if __name__ == "__main__":
    main()
