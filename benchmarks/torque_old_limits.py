"""Any ``skinny`` command on the torque twin with its joint limits as they were before
they were made stiff (MuJoCo's default: solref (0.02, 1), solimp (0.9, 0.95, 0.001,
0.5, 2)): the "before" of a before -> after comparison.

    MUJOCO_GL=disabled OMP_NUM_THREADS=1 python benchmarks/torque_old_limits.py \\
        experiment dynamic --rows 2d-ymca-pd --runs 10 --out results/old-limits
"""

from __future__ import annotations

import sys

from skinny_mj.cli.parser import main
from skinny_mj.plant import model

model.TORQUE_LIMIT_SOLREF = (0.02, 1.0)
model.TORQUE_LIMIT_SOLIMP = (0.9, 0.95, 0.001, 0.5, 2.0)

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
