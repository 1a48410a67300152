"""Paper C on the 3D body: paper C's sweep on Skinny's 8 DOF, with paper C's own joint-angle
signals and one command full scale shared by every joint.

The thesis ran paper C in 2D only. Paper C's rule, full scale = 2x YMCA's fastest speed of
each joint, gives the 3D body's joints full scales from 1.4 rad/s (shoulder flexion) to
14.4 rad/s (shoulder abduction); here every joint gets the fastest one's, 14.4 rad/s, so one
command unit is the same velocity on every joint. Everything else is paper C's
(:mod:`skinny_mj.experiments.paper_c.study`: spectral radius 0.1, noise 0.2,
150 epochs of 7 cycles, K x 0.9 per epoch, the original target, 10 runs), and so are its
report and claims. ``--movement`` is paper C's real movement; ``--quick`` paper C's smoke
test; the body and signals are this study's (for another body: ``skinny experiment paper-c
--dof/--signals``). Measured in docs/results/claims.md ("Paper C in 3D").

N = 200, not paper C's 1000: paper C's 1000 learns YMCA, the mirrors, YM and the speeds
but not Y and Y pure. The joints Y barely moves (6 of 8) are then held only by a weak loop
fitted to noise once K is small (:mod:`skinny_mj.experiments.paper_c.why_3d` measures
it per joint). N = 200 is the thesis's own best reservoir size for paper C's original
method (paper E, Fig. 4), one size for every row. It learns 7 of the 8 rows at or below
their 2D error (YMCA 0.0053, Y 0.0087, Y pure 0.0092; 3 runs each). N = 300 learns Y but
fails YMCA, and N = 500 learns YMCA but fails Y. YMCA at 1.5x fails at N = 200 (0.39): one
cycle of it has 208 samples against the readout's 217 regressors, the pinv readout's
interpolation threshold.
"""

from __future__ import annotations

import dataclasses

from skinny_mj.experiments.paper_c import study as paper_c

NAME = "paper-c-3d"
#: The reservoir size: the thesis's best for the original method (paper E, Fig. 4), not
#: paper C's 1000 (see the module docstring).
N_RESERVOIR = 200
STUDY = dataclasses.replace(
    paper_c.STUDY, name=NAME, description=__doc__,
    base=paper_c.STUDY.base.override({"plant.dof": 8, "plant.signals": "joint",
                                      "movement.full_scale": "shared",
                                      "esn.n_reservoir": N_RESERVOIR}),
    takes=("movement",))
