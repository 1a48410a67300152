"""Does a feedback loop faster than the ESN's 50 Hz help? The inertia-scaled PD (FEL's
teacher, omega 5 rad/s, zeta 1) recomputed at every 5 ms physics step (200 Hz) while the
rest of the command (the ESN's output) is held over the 20 ms control step, against the
PD held over the step as the study runs it; on the 2D YMCA.

    MUJOCO_GL=disabled OMP_NUM_THREADS=1 python benchmarks/torque_inner_loop.py [--seeds 5]

A measurement, not an option of the training path: the plant's step is replaced here.
Within a control step t, physics step s applies

    ctrl_s = clip(command_t + K (tau_fb,s - tau_fb,t) / limit)

where command_t = clip(y_ESN + K tau_fb,t / limit) is what the 50 Hz loop sent and
tau_fb,s = M(q_s) (omega^2 e_s + 2 zeta omega e_dot_s) the teacher's law at the physics
step's state (the error aimed at the middle of the 5 ms step, as the 50 Hz law aims at
the middle of its 20 ms; the desired motion there from the mid-step samples and the
step's acceleration, to second order). The inner loop reads the joint angles and
velocities at every physics step, with the position sensors' noise of the control step
held: it senses nothing the 50 Hz loop does not, only fresher. FEL still learns from the
50 Hz teacher torque tau_fb,t. The command was clipped before the inner loop adds to it
(exact whenever the 50 Hz command is within the limits).

Rows (each a study row's configuration, seeds 0 .. --seeds-1; ``--omega`` replaces
the teacher's omega): ``2d-ymca-arm-pd`` (the PD alone, K = 1) and ``2d-ymca-fel-arm``
(ESN + FEL, tested at K = 0: the inner loop then only changes what the ESN learned
from), each held and with the inner loop.
"""

from __future__ import annotations

import argparse
import os

os.environ.setdefault("MUJOCO_GL", "disabled")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402
from skinny_mj.controllers import fel  # noqa: E402
from skinny_mj.controllers.torque_arm import feedback_torque  # noqa: E402
from skinny_mj.controllers.torque_arm_loop import ArmLoop  # noqa: E402
from skinny_mj.experiments.dynamic.study import STUDY  # noqa: E402

from skinny_mj.plant.adapters import BatchPlant  # noqa: E402
from skinny_mj.training.loop import train_batch  # noqa: E402

ROWS = ("2d-ymca-arm-pd", "2d-ymca-fel-arm")
#: the originals the measurement wraps
STEP, U_ERROR, ROLLOUT = BatchPlant.step, ArmLoop.u_error, fel.rollout
INNER = False  # the inner loop on for the runs being trained


def _u_error(self, t, desired, sensed, plant):
    """ArmLoop.u_error, keeping the control step's sensed angles for the inner loop."""
    self.sensed_q = self.state_of(sensed).q
    self.t = t
    return U_ERROR(self, t, desired, sensed, plant)


def _inner_step(self, command):
    """BatchPlant.step with the teacher recomputed every physics step (module docstring)."""
    loop, gain = getattr(self, "inner", (None, None))
    if loop is None:
        return STEP(self, command)
    ctrl = np.clip(np.asarray(command, float).reshape(self.n_runs, self.n_dof), -1, 1)
    t, mo, h = loop.t, loop.motion, self.model.opt.timestep
    t = min(t, len(mo.q_mid) - 1)
    noise = loop.sensed_q - self.joint_angles()
    fb_t = loop.feedback_nm[loop.t]
    for s in range(self.n_substeps):
        if s:  # s = 0 is the control step's own state: the command as sent
            q, qd = self.joint_angles() + noise, self.joint_velocities()
            tau = (s + 0.5) * h - 0.5 * loop.dt  # from the 20 ms step's middle
            q_d = mo.q_mid[t] + tau * mo.qd_mid[t] + 0.5 * tau ** 2 * mo.qdd_step[t]
            qd_d = mo.qd_mid[t] + tau * mo.qdd_step[t]
            e, e_dot = q_d - (q + 0.5 * h * qd), qd_d - qd
            fb_s = feedback_torque(_Mass(loop.state_of.mass()), e, e_dot, loop.gains)
            self._ctrl[:, self._act_sel] = np.clip(ctrl + gain * (fb_s - fb_t) / loop._limit,
                                                   -1, 1)
        else:
            self._ctrl[:, self._act_sel] = ctrl
        mujoco.mj_step(self.model, self.data)
        mujoco.mj_fwdPosition(self.model, self.data)  # M(q) of the new state
    mujoco.mj_step1(self.model, self.data)
    self._signals = None
    return self._sensed()


class _Mass:
    """What :func:`feedback_torque` reads of an ArmState: M(q) (R, n, n)."""

    def __init__(self, mass: np.ndarray):
        self.mass = mass


def _rollout(esn, plant, desired, gain, **kw):
    """fel.rollout, telling the plant its hook and K when the inner loop is on."""
    hook = kw.get("hook")
    if INNER and isinstance(hook, ArmLoop):
        plant.inner = (hook, np.broadcast_to(np.asarray(gain, float), (plant.n_runs,))[:, None])
    try:
        return ROLLOUT(esn, plant, desired, gain, **kw)
    finally:
        plant.inner = (None, None)



def run(row_id: str, seeds: list[int], inner: bool, omega: float | None) -> np.ndarray:
    global INNER
    row = next(r for r in STUDY.rows if r.id == row_id)
    cfg = STUDY.base.override({**row.overrides,
                               **({} if omega is None else {"actuation.omega": omega})})
    INNER = inner
    try:
        out = train_batch(cfg, seeds)
    finally:
        INNER = False
    return np.array([o.metrics["test"]["position_nrmse"] for o in out])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--rows", default=",".join(ROWS))
    parser.add_argument("--omega", default="",
                        help="comma-separated teacher omegas (rad/s) instead of the rows' own")
    args = parser.parse_args()
    omegas = [float(w) for w in args.omega.split(",") if w] or [None]
    BatchPlant.step, ArmLoop.u_error, fel.rollout = _inner_step, _u_error, _rollout
    seeds = list(range(args.seeds))
    print("| row | omega (rad/s) | loop | position NRMSE per seed | mean ± sd |\n"
          "|---|---|---|---|---|")
    for row_id, omega in ((r, w) for r in args.rows.split(",") for w in omegas):
        for inner in (False, True):
            x = run(row_id, seeds, inner, omega)
            print(f"| {row_id} | {'row' if omega is None else f'{omega:g}'} | "
                  f"{'200 Hz inner PD' if inner else '50 Hz (held)'} | "
                  f"{', '.join(f'{v:.4f}' for v in x)} | {x.mean():.4f} ± {x.std(ddof=1):.4f} |",
                  flush=True)


if __name__ == "__main__":
    main()
