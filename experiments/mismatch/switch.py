"""A payload switched on mid-movement: how many cycles until the controller is back?

Rows ``2d-ymca-switch-<learner>`` (the mismatch study's group ``switch``): the plant is the
nominal arm for ``PRE`` cycles of YMCA; halfway through the next cycle 1 kg appears at the
right hand's centre of mass (:func:`skinny_mj.plant.perturb.mass_change`, in the running
model) and stays for ``POST`` more cycles: a test the rows declare
(:class:`skinny_mj.training.result.Perform`). The controllers keep the nominal model:

- ``esn-rls``: the ESN + FEL of the mismatch study's ``none`` row (trained on the nominal
  arm), its teacher on at K = ``GAIN``, its readout updated every control step by
  recursive least squares (:class:`skinny_mj.controllers.online.OnlineRLS`, forgetting
  ``FORGETTING`` per step, P_0 from the last training cycle's states with ridge 1);
- ``esn-rls-0.99``: the same with forgetting 0.99 per step (a memory of ~100 steps, 2 s;
  chosen after seeing ``esn-rls``'s slow recovery);
- ``esn-refit``: the same ESN and K, its readout refitted after every cycle by its
  training's own rule (the normal equations with forgetting 0.8 per cycle, the
  statistics carried on from training): FEL's learning cycle, performed;
- ``esn-refit-0.5``: the same with forgetting 0.5 per cycle (chosen after seeing
  ``esn-refit``'s slow recovery);
- ``esn-frozen``: the same ESN and K, its readout left as trained;
- ``ct-adaptive``: adaptive computed torque (its estimate running from the first cycle);
- ``ct-nominal``: computed torque on the nominal model.

Metrics per run: the joint-angle and position NRMSE of every cycle (the curves), the
pre-switch error (mean of the first ``PRE`` cycles), the switch cycle's, the last cycle's,
and cycles to recover: the first cycle after the switch cycle within 1.2x the pre-switch
position error (``POST`` + 1: never).
"""

from __future__ import annotations

import numpy as np

from skinny_mj.engine.study import Shape
from skinny_mj.training.result import Perform, RunResult

PRE, POST, PAYLOAD_KG, GAIN, FORGETTING = 2, 8, 1.0, 0.5, 0.999
LEARNERS = ("esn-rls", "esn-frozen", "ct-adaptive", "ct-nominal", "esn-rls-0.99", "esn-refit",
            "esn-refit-0.5")
#: the forgetting per cycle of each refitting learner (None: its training's)
REFIT = {"esn-refit": None, "esn-refit-0.5": 0.5}
#: forgetting per step of each RLS learner
RLS_FORGETTING = {"esn-rls": FORGETTING, "esn-rls-0.99": 0.99}


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


def metrics(result: RunResult) -> dict:
    """One run's file: the switch's figures (:func:`summary`)."""
    performed = result.tests["switch"]
    return summary(performed.position_nrmse, performed.angle_nrmse)


def failure(result: RunResult) -> str | None:
    """A run fails when its training or its performance diverged."""
    if not result.tests["switch"].failed:
        return None
    return result.train.fail_reason or "diverged after the switch"


def shape(learner: str) -> Shape:
    """Learner ``learner``'s run: trained (the ESN rows; a controller alone trains
    nothing), then PRE + 1 + POST cycles with the payload switched on in the middle of
    cycle PRE."""
    esn = learner.startswith("esn")
    perform = Perform("switch", PRE + 1 + POST, GAIN if esn else 1.0, PRE,
                      payload_kg=PAYLOAD_KG, rls_forgetting=RLS_FORGETTING.get(learner),
                      refit=learner in REFIT, refit_forgetting=REFIT.get(learner))
    return Shape(metrics, tests=(perform,), failure=failure)
