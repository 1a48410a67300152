"""Adaptive computed torque through the training path (``actuation.feedback=adaptive-ct``):
:class:`skinny_mj.controllers.adaptive_ct.AdaptiveArmLoop` on the nominal twin's
:class:`skinny_mj.plant.regressor.InertialRegressor`.

The estimate's prior (each parameter's standard deviation about the nominal 0): link mass
scales 0.5, payload 1 kg, viscous damping 1 N m s/rad, Coulomb friction 1 N m; the
residual's noise 1 N m; no forgetting. The estimate is clipped to a physical body (mass
scales > -0.9, payload >= 0, damping and friction >= 0) and kept across the cycles of one
loop (``test.washout_cycles`` gives it unscored cycles to adapt in).
"""

from __future__ import annotations

import functools

import numpy as np

from skinny_mj.controllers.adaptive_ct import AdaptiveArmLoop, ParameterRLS
from skinny_mj.plant.body import BodyLike
from skinny_mj.plant.regressor import InertialRegressor

#: prior standard deviations: (mass scale, payload kg, viscous N m s/rad, Coulomb N m)
PRIOR_SD = (0.5, 1.0, 1.0, 1.0)
NOISE_NM = 1.0


@functools.lru_cache(maxsize=4)
def regressor(which: BodyLike) -> InertialRegressor:
    """The nominal torque twin's regressor of the body ``which`` (cached)."""
    return InertialRegressor(which)


def estimator(reg: InertialRegressor) -> ParameterRLS:
    """The RLS estimate of ``reg``'s parameters with the module's prior and bounds."""
    n_mass, n = len(reg.names) - 1 - 2 * reg.n_dof, reg.n_dof
    sd_mass, sd_payload, sd_visc, sd_coul = PRIOR_SD
    prior = np.array([sd_mass] * n_mass + [sd_payload] + [sd_visc] * n + [sd_coul] * n)
    lo = np.array([-0.9] * n_mass + [0.0] * (1 + 2 * n))
    return ParameterRLS(prior, noise_sd=NOISE_NM, lo=lo, hi=np.full(len(prior), np.inf))


def loop(which: BodyLike, *args, **common) -> AdaptiveArmLoop:
    """The adaptive computed-torque loop of the body ``which``: ``args`` and ``common`` as
    :class:`skinny_mj.controllers.torque_arm_loop.ArmLoop` takes them."""
    reg = regressor(which)
    return AdaptiveArmLoop(*args, **common, regressor=reg, estimator=estimator(reg))
