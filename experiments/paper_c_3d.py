"""Paper C on the 3D body: paper C's sweep on Skinny's 8 DOF, with paper C's own joint-angle
signals and one command full scale shared by every joint.

The thesis ran paper C in 2D only. Paper C's rule, full scale = 2x YMCA's fastest speed of
each joint, gives the 3D body's joints full scales from 1.4 rad/s (shoulder flexion) to
14.4 rad/s (shoulder abduction); here every joint gets the fastest one's, 14.4 rad/s, so one
command unit is the same velocity on every joint. Everything else is paper C's
(:mod:`skinny_mj.experiments.paper_c.study`: N = 1000, spectral radius 0.1, noise 0.2,
150 epochs of 7 cycles, K x 0.9 per epoch, the original target, 10 runs), and so are its
report and claims. ``--movement`` is paper C's real movement; ``--quick`` paper C's smoke
test. Measured in docs/results/claims.md ("Paper C in 3D").
"""

from __future__ import annotations

import dataclasses

from skinny_mj.experiments.paper_c import study as paper_c

from skinny_mj.engine.experiment import Experiment
from skinny_mj.errors import SkinnyInputError

NAME = "paper-c-3d"
DOF, SIGNALS, FULL_SCALE = 8, "joint", "shared"


def build(quick: bool = False, movement: str | None = None, asf: str | None = None,
          dof: int | None = None, signals: str | None = None) -> Experiment:
    """Paper C's sweep (:func:`skinny_mj.experiments.paper_c.study.build`) on the 3D body,
    joint-angle signals, one shared full scale; ``--dof``/``--signals`` are this study's."""
    if dof is not None or signals is not None:
        raise SkinnyInputError(f"{NAME} is paper C on the {DOF}-DOF body with {SIGNALS} "
                               "signals; for another body run paper-c --dof/--signals")
    exp = paper_c.build(quick=quick, movement=movement, asf=asf, dof=DOF, signals=SIGNALS,
                        full_scale=FULL_SCALE)
    return dataclasses.replace(exp, name=NAME)


report = paper_c.report
train_configs = paper_c.train_configs  # what a row trains, for the memory estimate
