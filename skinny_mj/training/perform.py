"""A performance after training, with the plant changed mid-run: a test a study declares.

A :class:`~skinny_mj.training.result.Perform` is one of the tests a run takes (beside a
:class:`~skinny_mj.training.result.Test`): after training, the training movement is
performed ``cycles`` times on the training plant, the feedback controller on at gain
``gain`` (its model the nominal arm), reservoir noise off; halfway through cycle
``switch_cycle`` (counted from 0) the plant changes (``payload_kg`` at the right hand's
centre of mass, every arm link's mass and inertia x ``mass_scale``:
:func:`skinny_mj.plant.perturb.mass_change`, in the running model) and stays changed to
the end. The readout stays as trained, or (``rls_forgetting``) learns every control step
by recursive least squares (:class:`skinny_mj.controllers.online.OnlineRLS`, P_0 from the
last training cycle's states with ridge ``rls_lambda``), or (``refit``) is refitted after
every cycle by the training's own rule, as in a learning cycle of FEL. Its outcome, per run a
:class:`~skinny_mj.training.result.Performance` (the per-cycle curves), is the run's test
of that name (``RunResult.tests[name]``). :func:`perform` takes it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from skinny_mj.controllers import fel
from skinny_mj.controllers.learning import CycleFit
from skinny_mj.controllers.metrics import position_nrmse
from skinny_mj.controllers.online import OnlineRLS
from skinny_mj.plant import body
from skinny_mj.plant.perturb import mass_change
from skinny_mj.training import torque
from skinny_mj.training.result import Perform, Performance

__all__ = ["SwitchHook", "perform"]


class SwitchHook:
    """A rollout hook that runs ``change()`` once, after step ``step`` of cycle ``cycle``
    (counted from 0 by ``begin``), and is ``hook`` otherwise."""

    def __init__(self, hook: Any, cycle: int, step: int, change) -> None:
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


def perform(run: Any, test: Perform, trained: Any) -> list[Performance]:
    """The R trained networks of ``run`` (a :class:`skinny_mj.training.loop.Run`; its
    ``trained`` :class:`~skinny_mj.training.loop.Training`) perform ``test``."""
    cfg, n_runs = run.cfg, len(run.seeds)
    alive, online, rule = np.ones(n_runs, bool), None, None
    if trained.fel is not None:  # a network was trained: the runs that diverged are out
        alive = ~trained.fel.failed
        if test.refit:
            rule = trained.rule or CycleFit()
            if test.refit_forgetting is not None:
                if not hasattr(rule, "forgetting"):
                    raise ValueError("refit_forgetting needs a readout fit with forgetting "
                                     "(method.fit=forgetting)")
                rule.forgetting = float(test.refit_forgetting)
        if test.rls_forgetting is not None:
            online = OnlineRLS(run.esn, test.rls_forgetting, test.rls_lambda,
                               states=np.array(trained.fel.last_rollout.states), runs=alive)
    plant = run.plant
    hook = torque.hook_for(cfg, run.training, run.max_speed_rad_s, plant, nominal=True)
    change = mass_change(plant, test.payload_kg, test.mass_scale)
    switch = SwitchHook(hook, test.switch_cycle, len(run.desired) // 2, change.apply)
    loop = run.loop(switch).learning(online)
    curve = np.full((n_runs, test.cycles), np.nan)
    angle_curve = curve.copy()
    dof = cfg.plant.dof
    shape = body.body_of(dof)
    desired_angles = shape.normalize_angles(run.training.angles)
    run.esn.reset()
    for c in range(test.cycles):
        ro = fel.rollout(run.esn, plant, run.desired, test.gain, loop, noise=False)
        alive &= np.array([r is None for r in fel.health(run.esn, ro)])
        curve[alive, c] = position_nrmse(ro.true_signals, run.desired)[alive]
        angles = shape.normalize_angles(ro.angles[:, :, :dof])
        angle_curve[alive, c] = position_nrmse(angles, desired_angles)[alive]
        if rule is not None:  # FEL's learning cycle, on this cycle of the performance
            rule.fit(run.esn, fel.learning_cycle(ro, cfg.method.beta, alive.copy(), 0,
                                                 loop.target_lead))
    change.undo()
    return [Performance(curve[r], angle_curve[r], not alive[r]) for r in range(n_runs)]
