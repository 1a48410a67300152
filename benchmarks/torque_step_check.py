"""Which physics step and integrator the torque twin needs: accuracy against a 0.1 ms
RK4 reference and stability, per integrator and timestep. Prints a table per arm.

    MUJOCO_GL=disabled OMP_NUM_THREADS=1 python benchmarks/torque_step_check.py [--quick]

Runs (the same seeded torques for every candidate; torques held for each 20 ms control
step, as the plant applies them):

- ``swing``: 2 s free swing under gravity from a raised, bent pose, damping on, joint
  limits off (the abduction range starts at the hanging arm, so a swing would strike
  it; a soft-limit impact is not smooth dynamics to measure an integrator on).
- ``rand``: 1 s of random torques (30 % of the limits), limits off.
- ``drift``: 5 s free swing with damping and limits off: max |E(t) - E(0)| over the
  swing's kinetic-energy peak (a conservative system; MuJoCo's energy terms).
- ``full``: 2 s of full random torques (100 % of the limits) with the limits on (the
  plant's worst case): does the run stay finite without a MuJoCo warning, how fast does
  it get, how far past a limit it presses, and its error after 0.1 s.

Errors are max |q - q_ref| over the joints at the 20 ms sample times, rad. ``evals`` is
the number of force evaluations per 20 ms control step (RK4 takes four per step);
``cost`` the measured wall time of a control step relative to implicitfast at 2 ms (best
of 5; a ratio, as every benchmark here prints). The last line names the cheapest
candidate (fewest evaluations) that meets :data:`TOLERANCE` and stays stable on both
arms.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("MUJOCO_GL", "disabled")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from skinny_mj.plant.body import by_dof  # noqa: E402
from skinny_mj.plant.model import load_model  # noqa: E402

CONTROL_DT_S = 0.02
REF = ("rk4", 0.0001)
INTEGRATORS = {"euler": mujoco.mjtIntegrator.mjINT_EULER,
               "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
               "rk4": mujoco.mjtIntegrator.mjINT_RK4}
TIMESTEPS_S = (0.0005, 0.001, 0.002, 0.004, 0.005, 0.01, 0.02)
# raised, bent start poses (rad), well inside every range
START = {4: np.array([1.3, 0.9, 1.1, 0.6]),
         8: np.array([1.3, 0.4, 0.7, 0.9, 1.1, -0.3, -0.5, 0.6])}


def _model(dof: int, integrator: str, timestep: float, *, limits: bool, damping: bool):
    model = load_model(by_dof(dof, "torque"))
    model.opt.integrator = INTEGRATORS[integrator]
    model.opt.timestep = timestep
    model.opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    if not limits:
        model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_LIMIT)
    if not damping:
        model.dof_damping[:] = 0.0
    return model


def simulate(dof, integrator, timestep, seconds, torque_fraction, *, limits, damping,
             seed=0):
    """Angles (n+1, nq) rad and energies (n+1, 2: potential, kinetic) J at the control
    samples, max |qvel|, the worst limit overshoot (rad) and whether a MuJoCo warning
    fired."""
    model = _model(dof, integrator, timestep, limits=limits, damping=damping)
    data = mujoco.MjData(model)
    data.qpos[:] = START[dof]
    mujoco.mj_forward(model, data)
    n = int(round(seconds / CONTROL_DT_S))
    sub = int(round(CONTROL_DT_S / timestep))
    ctrl = np.random.default_rng(seed).uniform(-1, 1, (n, model.nu)) * torque_fraction
    q, energy = [data.qpos.copy()], [data.energy.copy()]
    lo, hi = model.jnt_range.T
    vmax, over = 0.0, 0.0
    for k in range(n):
        data.ctrl[:] = ctrl[k]
        mujoco.mj_step(model, data, sub)
        if not np.all(np.isfinite(data.qpos)):
            break
        mujoco.mj_forward(model, data)  # energy of the new state
        q.append(data.qpos.copy())
        energy.append(data.energy.copy())
        vmax = max(vmax, float(np.abs(data.qvel).max()))
        over = max(over, float(np.max(np.maximum(lo - data.qpos, data.qpos - hi))))
    warned = any(w.number for w in data.warning)
    return np.array(q), np.array(energy), vmax, over, warned


RUNS = {  # name: (seconds, torque fraction, limits, damping)
    "swing": (2.0, 0.0, False, True),
    "rand": (1.0, 0.3, False, True),
    "drift": (5.0, 0.0, False, False),
    "full": (2.0, 1.0, True, True),
}


def _error(q, q_ref, upto=None):
    n = min(len(q), len(q_ref)) if upto is None else upto + 1
    if len(q) < n:
        return np.inf
    return float(np.abs(q[:n] - q_ref[:n]).max())


# what a candidate must meet on both arms (rad, rad, relative energy): the chosen one
# is the cheapest that does, counted in force evaluations per 20 ms control step
TOLERANCE = {"swing": 1e-4, "rand": 1e-3, "drift": 1e-3}


def step_cost(dof: int, integrator: str, timestep: float, repeats: int = 5,
              n_steps: int = 50) -> float:
    """Best-of-``repeats`` wall time (s) of one 20 ms control step (random torques)."""
    model = _model(dof, integrator, timestep, limits=True, damping=True)
    data = mujoco.MjData(model)
    sub = int(round(CONTROL_DT_S / timestep))
    ctrl = np.random.default_rng(1).uniform(-0.3, 0.3, (n_steps, model.nu))
    best = np.inf
    for _ in range(repeats):
        mujoco.mj_resetData(model, data)
        data.qpos[:] = START[dof]
        t0 = time.perf_counter()
        for k in range(n_steps):
            data.ctrl[:] = ctrl[k]
            mujoco.mj_step(model, data, sub)
        best = min(best, (time.perf_counter() - t0) / n_steps)
    return best


def evaluations(integrator: str, timestep: float) -> int:
    """Force evaluations per control step (RK4 takes four per step)."""
    return int(round(CONTROL_DT_S / timestep)) * (4 if integrator == "rk4" else 1)


def check(dof: int, timesteps=TIMESTEPS_S, quick: bool = False) -> list[dict]:
    runs = dict(RUNS)
    if quick:
        runs = {k: (v[0] / 4, *v[1:]) for k, v in runs.items()}
    ref = {name: simulate(dof, *REF, s, f, limits=lim, damping=dmp)
           for name, (s, f, lim, dmp) in runs.items()}
    base = step_cost(dof, "implicitfast", 0.002)
    rows = []
    for integ in INTEGRATORS:
        for h in timesteps:
            row = {"dof": dof, "integrator": integ, "timestep_ms": 1e3 * h,
                   "evals": evaluations(integ, h)}
            for name, (s, f, lim, dmp) in runs.items():
                q, e, vmax, over, warned = simulate(dof, integ, h, s, f, limits=lim,
                                                       damping=dmp)
                if name == "drift":
                    kinetic_peak = ref[name][1][:, 1].max()
                    total = e.sum(axis=1)
                    finite = len(e) == len(ref[name][1])
                    row["drift"] = (float(np.abs(total - total[0]).max() / kinetic_peak)
                                    if finite else np.inf)
                elif name == "full":
                    row["full_ok"] = len(q) == len(ref[name][0]) and not warned
                    row["full_vmax"] = vmax
                    row["full_over"] = over
                    row["full_err_0.1s"] = _error(q, ref[name][0], upto=5)
                else:
                    row[name] = _error(q, ref[name][0])
            row["cost"] = step_cost(dof, integ, h) / base
            row["meets"] = row["full_ok"] and all(row[k] <= v for k, v in TOLERANCE.items())
            rows.append(row)
    return rows


def choose(rows: list[dict]) -> tuple[str, float] | None:
    """The cheapest (integrator, timestep_ms) meeting :data:`TOLERANCE` on every arm."""
    keys = {(r["integrator"], r["timestep_ms"]) for r in rows}
    ok = [k for k in keys if all(r["meets"] for r in rows
                                 if (r["integrator"], r["timestep_ms"]) == k)]
    evals = {(r["integrator"], r["timestep_ms"]): r["evals"] for r in rows}
    return min(ok, key=lambda k: (evals[k], -k[1])) if ok else None


def table(rows: list[dict]) -> str:
    head = ("| dof | integrator | dt (ms) | swing err (rad) | rand err (rad) | drift |"
            " full: ok | full: max qvel (rad/s) | full: past limit (rad) |"
            " full: err 0.1 s (rad) | evals / 20 ms | cost | meets |")
    lines = [head, "|" + "---|" * 13]
    for r in rows:
        lines.append(
            f"| {r['dof']} | {r['integrator']} | {r['timestep_ms']:g} | {r['swing']:.1e} |"
            f" {r['rand']:.1e} | {r['drift']:.1e} | {'yes' if r['full_ok'] else 'NO'} |"
            f" {r['full_vmax']:.3g} | {r['full_over']:.2g} | {r['full_err_0.1s']:.1e} |"
            f" {r['evals']} | {r['cost']:.2f} | {'yes' if r['meets'] else ''} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="quarter-length runs")
    parser.add_argument("--dof", type=int, nargs="*", default=[4, 8])
    args = parser.parse_args()
    rows = []
    for dof in args.dof:
        print(f"\n{dof} DOF (reference: RK4 at {REF[1] * 1e3:g} ms)\n")
        rows += check(dof, quick=args.quick)
        print(table([r for r in rows if r["dof"] == dof]))
    best = choose(rows)
    tol = ", ".join(f"{k} <= {v:g}" for k, v in TOLERANCE.items())
    print(f"\ncheapest meeting {tol} and stable under full torques on every arm: "
          + (f"{best[0]} at {best[1]:g} ms" if best else "none"))


if __name__ == "__main__":
    main()
