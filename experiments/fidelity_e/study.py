"""Paper E's fidelity: where does the original method's exp 2 / exp 5 ratio reach ×4.4?

Paper E's exps 1, 2 and 5 (their rows in ``skinny_mj.experiments.paper_e.study.ROWS``)
× movement {recorded-like YMCA (``ymca-recorded``), ``ymca-smooth`` (today's ``ymca``),
md_02 by positions, md_02 by angles} × u_error gain {0.5, 1, 2}; each trained network is
tested twice, reservoir noise off and on (the toolbox's protocol), so the test-noise
comparison is paired (the noisy test runs after the clean one, on the ESN's own noise
stream). Row ids ``<movement>-g<gain>-e<exp>``; groups per movement and ``all``.
``--quick``: gain 1 only, 2 runs of 2 epochs.

The thesis's ratio: exp 2 / exp 5 = 0.1088 / 0.0245 = 4.4 (position), 0.2435 / 0.0717
= 3.4 (motor), paper E Table 2.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from skinny_mj.experiments.paper_e import study as paper_e

from skinny_mj.engine.study import Quick, Row, Study, Test
from skinny_mj.trajectories.samples import sample_clip

if TYPE_CHECKING:
    from skinny_mj.training.result import RunResult

NAME = "fidelity-e"
MD02 = "md_02.amc@start=3,duration=6.26"  # paper E's md_02 excerpt (docs/papers/paper-e.md)
#: movement key -> (trajectory, retarget); md_02's path is the installed sample clip.
MOVEMENTS = {"recorded": ("ymca-recorded", "angles"), "smooth": ("ymca-smooth", "angles"),
             "md02pos": (MD02, "positions"), "md02ang": (MD02, "angles")}
GAINS = (0.5, 1.0, 2.0)
EXPS = ("1", "2", "5")
THESIS_RATIO = {"position_nrmse": 0.1088 / 0.0245, "motor_nrmse": 0.2435 / 0.0717}


def _trajectory(key: str) -> tuple[str, str]:
    name, retarget = MOVEMENTS[key]
    if name == MD02:
        name = f"{sample_clip('md_02')}@start=3,duration=6.26"
    return name, retarget


def _row(m: str, g: float, e: str) -> Row:
    trajectory, retarget = _trajectory(m)
    paper = paper_e.STUDY.row(e)
    return Row(f"{m}-g{g:g}-e{e}", {**paper.overrides, "movement.trajectory": trajectory,
                                    "movement.retarget": retarget, "method.u_error_gain": g},
               paper.paper, group=m)


#: Each trained network is tested twice: reservoir noise off (the standard test), then on.
TESTS = (Test(), Test("noisy", overrides={"test.noise": True}))


def metrics(result: RunResult) -> dict:
    """The clean and the noisy test's NRMSEs (the noisy test may diverge alone)."""
    clean, noisy = result.test, result.tests["noisy"]
    return {"position_nrmse": clean.position_nrmse, "motor_nrmse": clean.motor_nrmse,
            "noisy_position_nrmse": noisy.position_nrmse,
            "noisy_motor_nrmse": noisy.motor_nrmse, "noisy_failed": bool(noisy.failed)}


STUDY = Study(
    name=NAME, description=__doc__, tests=TESTS, metrics=metrics,
    report="skinny_mj.experiments.fidelity_e.report:report",
    rows=tuple(_row(m, g, e) for m in MOVEMENTS for g in GAINS for e in EXPS),
    runs=10,  # paper E ran 20; 10 fit a 2-core machine (the report says so)
    columns=("position_nrmse", "noisy_position_nrmse", "motor_nrmse", "noisy_motor_nrmse"),
    quick=Quick({"method.epochs": 2}, runs=2,
                rows=tuple(f"{m}-g1-e{e}" for m in MOVEMENTS for e in EXPS)),
    takes=("body", "signals"),  # the movements are the study's
)
