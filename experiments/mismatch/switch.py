"""A payload switched on mid-movement: how many cycles until the controller is back?

Rows ``2d-ymca-switch-<learner>`` (the mismatch study's group ``switch``): the plant is the
nominal arm for ``PRE`` cycles of YMCA; halfway through the next cycle 1 kg appears at the
right hand's centre of mass (:func:`skinny_mj.plant.perturb.mass_change`, in the running
model) and stays for ``POST`` more cycles. The controllers keep the nominal model:

- ``esn-rls``: the ESN + FEL of the mismatch study's ``none`` row (trained on the nominal
  arm), its teacher on at K = ``GAIN``, its readout updated every control step by
  recursive least squares (:class:`skinny_mj.controllers.online.OnlineRLS`, forgetting
  ``FORGETTING`` per step, P_0 from the last training cycle's states with ridge 1);
- ``esn-rls-0.99``: the same with forgetting 0.99 per step (a memory of ~100 steps, 2 s;
  chosen after seeing ``esn-rls``'s slow recovery);
- ``esn-frozen``: the same ESN and K, its readout left as trained;
- ``ct-adaptive``: adaptive computed torque (its estimate running from the first cycle);
- ``ct-nominal``: computed torque on the nominal model.

Metrics per run: the joint-angle and position NRMSE of every cycle (the curves), the
pre-switch error (mean of the first ``PRE`` cycles), the switch cycle's, the last cycle's,
and cycles to recover: the first cycle after the switch cycle within 1.2x the pre-switch
position error (``POST`` + 1: never).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from skinny_mj.controllers import fel
from skinny_mj.controllers.metrics import position_nrmse
from skinny_mj.controllers.online import OnlineRLS

from skinny_mj.engine.experiment import RunFailed
from skinny_mj.engine.study import Row
from skinny_mj.plant import body
from skinny_mj.plant.perturb import mass_change
from skinny_mj.training import torque
from skinny_mj.training.config import TrainConfig
from skinny_mj.training.loop import build_run, train_run

PRE, POST, PAYLOAD_KG, GAIN, FORGETTING = 2, 8, 1.0, 0.5, 0.999
LEARNERS = ("esn-rls", "esn-frozen", "ct-adaptive", "ct-nominal", "esn-rls-0.99")
#: forgetting per step of each RLS learner
RLS_FORGETTING = {"esn-rls": FORGETTING, "esn-rls-0.99": 0.99}


class SwitchHook:
    """A rollout hook that runs ``change()`` once, after step ``step`` of cycle ``cycle``
    (counted from 0 by ``begin``), and is ``hook`` otherwise."""

    def __init__(self, hook: Any, cycle: int, step: int, change):
        self.hook, self.cycle, self.step, self.change = hook, cycle, step, change
        self.cycles = -1

    def begin(self, plant, n_steps: int) -> None:
        self.cycles += 1
        self.hook.begin(plant, n_steps)

    def after_step(self, t: int, plant) -> None:
        self.hook.after_step(t, plant)
        if self.cycles == self.cycle and t == self.step:
            self.change()

    def __getattr__(self, name: str) -> Any:
        return getattr(self.hook, name)


def summary(curve: np.ndarray, angle_curve: np.ndarray) -> dict:
    """The switch's figures of one run's per-cycle curves."""
    pre = float(np.mean(curve[:PRE]))
    after = curve[PRE + 1:]
    within = np.flatnonzero(after <= 1.2 * pre)
    return {"position_nrmse": float(curve[-1]), "pre_switch": pre,
            "switch_cycle": float(curve[PRE]), "last": float(curve[-1]),
            "recover_cycles": float(within[0] + 1 if within.size else POST + 1),
            "joint_pre_switch": float(np.mean(angle_curve[:PRE])),
            "joint_last": float(angle_curve[-1]),
            "curve": [float(v) for v in curve], "angle_curve": [float(v) for v in angle_curve]}


def run_switch(config: TrainConfig, row: Row, seeds: list[int]) -> list:
    """Train (the ESN rows), then PRE + 1 + POST cycles with the payload switched on in
    the middle of cycle PRE."""
    learner = row.params["learner"]
    run = build_run(config, seeds)
    alive = np.ones(len(seeds), bool)
    reasons: list = [None] * len(seeds)
    online = None
    if learner.startswith("esn"):
        trained = train_run(run).fel
        alive, reasons = ~trained.failed, trained.fail_reason
        if learner in RLS_FORGETTING:
            online = OnlineRLS(run.esn, RLS_FORGETTING[learner], 1.0,
                               states=np.array(trained.last_rollout.states), runs=alive)
    plant = run.plant
    hook = torque.hook_for(config, run.training, run.max_speed_rad_s, plant, nominal=True)
    change = mass_change(plant, PAYLOAD_KG, 1.0)
    switch = SwitchHook(hook, PRE, len(run.desired) // 2, change.apply)
    loop = run.loop(switch).learning(online)
    gain = GAIN if learner.startswith("esn") else 1.0
    n = PRE + 1 + POST
    curve = np.full((len(seeds), n), np.nan)
    angle_curve = curve.copy()
    desired_angles = body.body_of(config.plant.dof).normalize_angles(run.training.angles)
    run.esn.reset()
    for c in range(n):
        ro = fel.rollout(run.esn, plant, run.desired, gain, loop, noise=False)
        alive &= np.array([r is None for r in fel.health(run.esn, ro)])
        curve[alive, c] = position_nrmse(ro.true_signals, run.desired)[alive]
        angles = body.body_of(config.plant.dof).normalize_angles(ro.angles[:, :, :config.plant.dof])
        angle_curve[alive, c] = position_nrmse(angles, desired_angles)[alive]
    change.undo()
    return [summary(curve[r], angle_curve[r]) if alive[r]
            else RunFailed(reasons[r] or "diverged after the switch") for r in range(len(seeds))]
