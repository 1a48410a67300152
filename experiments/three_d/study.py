"""Three-d: papers A, B and C on the 3D body (8 DOF, Cartesian signals) beside
their own 2D joint-angle setting, in one sweep with the same seeds.

Rows ``<paper>-<dim>-<paper row>`` (``a-2d-serial-d4``, ``b-3d-phase90``,
``c-3d-mirror-left``): each is the paper's own row, run as the paper's own sweep runs it
when ``skinny experiment <paper> [--dof ... --signals ...]`` builds it
(:class:`skinny_mj.engine.study.Of`), so no recipe is copied here: the row's
configuration only says the body (``plant.dof`` and ``plant.signals``). ``2d`` is the
paper's setting (4 DOF, joint angles); ``3d`` is ``dof=8, signals="cartesian"``
(``--dof`` / ``--signals`` replace it). A 3D row takes its
2D twin's seeds (:attr:`skinny_mj.engine.study.Row.seeds_of`): run k of both starts from the
same seed. :mod:`skinny_mj.experiments.three_d.report` writes the table (2D vs 3D, mean ± sd,
failed / n), each paper's own figures and claims on each body, and the claims side by side.

The subset (:data:`SUBSET`): the whole 2D + 3D sweep at 10 runs per row was to take
<= ~25 min on one idle core. Measured (lockstep batches of 10 seeds, CPU time on a loaded
machine): a paper-A run 3 s in 2D, 5.3 s in 3D (1.8x); paper B 5 s / 7 s (1.4x); paper C's
YMCA row > 20 s in 2D. So each paper keeps the rows its main claims need (the full papers
in 3D: ``skinny experiment paper-a --dof 8 --signals cartesian`` etc.), and the group
``core`` (:data:`CORE`) is one pair per paper for a machine shared by many sweeps:

- paper A: inverse only and serial (the best forward model in 2D) at delays 4 and 10
  (left out: delays 0-3 and 5-9, the parallel and hybrid architectures; so the claims on
  pre-training at delay 0 and on parallel / hybrid are n/a);
- paper B: relative phase 0°, 90°, 180° (left out: the frequency and amplitude ratios);
- paper C: trained on YMCA, tested on all nine movements (left out: training on Y, Y
  pure, YM, the mirrors and the other speeds, so the claims on Y, Y pure and the mirror
  networks are n/a; YMCA-trained networks tested on the mirrors are in).

Where 3D needs a choice (every paper is 2D only):

- paper B: the shoulder abduction swings as in 2D; shoulder flexion and rotation are held
  at 0 and the elbows at 20° (:mod:`skinny_mj.trajectories.patterns`); the relative error
  and the phase lag are of the lagging shoulder's abduction angle, as in 2D.
- paper C: a mirror movement copies one arm's four YMCA joint angles to the other arm;
  the body mirrors the left arm's axes, so equal angles are a mirror image in the
  sagittal plane (in 3D the two arms' YMCA differ also in shoulder rotation, a 30° vs
  50° range). Y pure holds the elbows only: shoulder flexion and rotation move 7-10° in Y.
- papers A and C score positions in the run's signals: normalized joint angles in 2D,
  normalized Cartesian elbow and wrist positions in 3D, so their 2D and 3D errors are two
  measures. Paper B's relative error (of a joint angle) and paper C's joint-angle NRMSE on
  YMCA and YM (``angle_nrmse``, from the joint angles the runs keep) are one measure.
"""

from __future__ import annotations

import functools

from skinny_mj.engine import registry
from skinny_mj.engine.plan import Experiment
from skinny_mj.engine.study import Of, Quick, Row, Study
from skinny_mj.training.config import TrainConfig

NAME = "three-d"
#: paper id -> its study's name
PAPERS = {"a": "paper-a", "b": "paper-b", "c": "paper-c"}
#: The paper rows run here (module docstring: what is left out and why).
SUBSET = {"a": ("inverse-d4", "serial-d4", "inverse-d10", "serial-d10"),
          "b": ("phase0", "phase90", "phase180"),
          "c": ("ymca",)}
#: ``--quick``: rows that every paper's own --quick sweep has (a smoke test).
QUICK_SUBSET = {"a": ("inverse-d0", "serial-d4"), "b": ("phase0", "phase90"),
                "c": ("ymca", "mirror-left")}
#: Both sweeps' paper rows in one order that keeps each sweep's own order (its seeds).
ORDER = {"a": ("inverse-d0", "inverse-d4", "serial-d4", "inverse-d10", "serial-d10"),
         "b": ("phase0", "phase90", "phase180"), "c": ("ymca", "mirror-left")}
DIMS = ("2d", "3d")
#: Group ``core``: the fewest rows per paper that its headline claims need (a loaded
#: machine's sweep); ``--resume`` without ``--rows`` adds the others.
CORE = {"a": ("inverse-d4", "serial-d4"), "b": ("phase0",), "c": ("ymca",)}
#: The 2D rows' body: each paper's own setting.
BODY_2D = {"plant.dof": 4, "plant.signals": "joint"}


def row_id(paper: str, dim: str, paper_row: str) -> str:
    return f"{paper}-{dim}-{paper_row}"


@functools.lru_cache(maxsize=16)
def paper_experiment(paper: str, dim: str, quick: bool, dof: int, signals: str) -> Experiment:
    """Paper ``paper``'s own sweep on ``dim``'s body (2D: the paper's default)."""
    body = {} if dim == "2d" else {"body": dof, "signals": signals}
    return registry.get(PAPERS[paper]).build(quick=quick, **body)


def paper_of(config: TrainConfig, row: Row) -> tuple[Experiment, Row]:
    """The paper's own sweep (on ``config``'s body) and row that ``row`` runs."""
    p = row.params
    exp = paper_experiment(p["paper"], p["dim"], p["quick"], config.plant.dof,
                           config.plant.signals)
    return exp, next(r for r in exp.rows if r.id == p["row"])


#: One run's CPU seconds on the 2D body, idle core, lockstep batches of 10 (measured;
#: only the schedule uses it, to start the costliest batches first), and the 3D factor.
SECONDS_2D = {"a": 3.0, "b": 5.0, "c": 25.0}
FACTOR_3D = 1.8


def cost(config: TrainConfig, row: Row) -> float:
    """Seconds-like cost: the paper's own relative cost of the row, scaled to seconds
    by the paper's mean over the sweep's subset (paper costs are in different units)."""
    exp, paper_row = paper_of(config, row)
    p = row.params["paper"]
    own = [exp.cost(r) for r in exp.rows if r.id in subset(row.params["quick"])[p]]
    scale = SECONDS_2D[p] * (FACTOR_3D if row.params["dim"] == "3d" else 1.0)
    return scale * exp.cost(paper_row) / (sum(own) / len(own))


def subset(quick: bool) -> dict[str, tuple[str, ...]]:
    return QUICK_SUBSET if quick else SUBSET


def _paper_numbers(paper: str, paper_row: str) -> dict[str, float]:
    """The paper's numbers of its row (a study's; papers B and C state none)."""
    study = registry.get(PAPERS[paper])
    return dict(study.row(paper_row).paper)


def _row(paper: str, dim: str, paper_row: str) -> Row:
    """Paper ``paper``'s row, run as its own sweep runs it: in 2D the paper's own
    setting, in 3D on this row's body; a 3D row takes its 2D twin's seeds."""
    full, quick = paper_row in SUBSET[paper], paper_row in QUICK_SUBSET[paper]
    return Row(row_id(paper, dim, paper_row), BODY_2D if dim == "2d" else {},
               _paper_numbers(paper, paper_row) if full else {},
               seeds_of=None if dim == "2d" else row_id(paper, "2d", paper_row),
               group=f"{paper}-{dim}", params={"paper": paper, "dim": dim, "row": paper_row},
               quick_only=quick and not full,
               of=Of(registry.get(PAPERS[paper]), paper_row, on_body=dim == "3d"))


ROWS = tuple(_row(p, dim, r) for dim in DIMS for p, ids in ORDER.items() for r in ids)


STUDY = Study(
    name=NAME, description=__doc__, rows=ROWS, runs=10,
    # the 3D body; the 2D rows' overrides set each paper's own (--dof/--signals: the 3D one)
    base=TrainConfig().override({"plant.dof": 8, "plant.signals": "cartesian"}),
    params={"quick": False}, cost=cost,
    groups={**{p: [row_id(p, d, r) for d in DIMS for r in ORDER[p]] for p in PAPERS},
            **{d: [row_id(p, d, r) for p in PAPERS for r in ORDER[p]] for d in DIMS},
            "core": [row_id(p, d, r) for d in DIMS for p, ids in CORE.items() for r in ids]},
    columns=("performance_nrmse", "feedback_share", "relative_error_x1",
             "ymca__position_nrmse", "wall_s"),
    # each paper's --quick sweep on 2 of its rows, 2 runs: a smoke test
    quick=Quick(runs=2, rows=tuple(row_id(p, d, r) for d in DIMS
                                   for p, ids in QUICK_SUBSET.items() for r in ids),
                params={"quick": True}),
    takes=("body", "signals"),  # the papers' own rows name their movements
    report="skinny_mj.experiments.three_d.report:report",
)
