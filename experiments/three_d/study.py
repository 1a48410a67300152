"""Three-d: papers A, B and C on the 3D body (8 DOF, Cartesian signals) beside
their own 2D joint-angle setting, in one sweep with the same seeds.

Rows ``<paper>-<dim>-<paper row>`` (``a-2d-serial-d4``, ``b-3d-phase90``,
``c-3d-mirror-left``): each is the paper's own row, run by the paper module's
``run_batch`` as that paper's ``build(dof=..., signals=...)`` makes it, so no recipe is
copied here. ``2d`` is the paper's setting (4 DOF, joint angles); ``3d`` is ``dof=8,
signals="cartesian"`` (``--dof`` / ``--signals`` replace it). A 3D row takes its 2D
twin's seeds (:attr:`skinny_mj.engine.experiment.Row.seeds_of`): run k of both starts from the
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
import importlib
from dataclasses import asdict, dataclass, field
from pathlib import Path

from skinny_mj.engine.experiment import Experiment, Row

NAME = "three-d"
#: paper id -> its module
PAPERS = {"a": "skinny_mj.experiments.paper_a", "b": "skinny_mj.experiments.paper_b",
          "c": "skinny_mj.experiments.paper_c.study"}
#: The paper rows run here (module docstring: what is left out and why).
SUBSET = {"a": ("inverse-d4", "serial-d4", "inverse-d10", "serial-d10"),
          "b": ("phase0", "phase90", "phase180"),
          "c": ("ymca",)}
#: ``--quick``: rows that every paper's own --quick build has (a smoke test).
QUICK_SUBSET = {"a": ("inverse-d0", "serial-d4"), "b": ("phase0", "phase90"),
                "c": ("ymca", "mirror-left")}
DIMS = ("2d", "3d")
#: Group ``core``: the fewest rows per paper that its headline claims need (a loaded
#: machine's sweep); ``--resume`` without ``--rows`` adds the others.
CORE = {"a": ("inverse-d4", "serial-d4"), "b": ("phase0",), "c": ("ymca",)}


@dataclass(frozen=True)
class Config:
    """The 3D body (``dof``, ``signals``), the runs per row, and each paper's own config
    per body (``papers``: ``"<paper>-<dim>"`` -> that paper's Config, as its ``build``
    makes it; recorded in config.json)."""

    quick: bool = False
    dof: int = 8
    signals: str = "cartesian"
    runs: int = 10
    papers: dict = field(default_factory=dict)


def row_id(paper: str, dim: str, paper_row: str) -> str:
    return f"{paper}-{dim}-{paper_row}"


def module(paper: str):
    """Paper ``paper``'s study: its module's ``STUDY``, or the module (the older contract)."""
    mod = importlib.import_module(PAPERS[paper])
    return getattr(mod, "STUDY", mod)


@functools.lru_cache(maxsize=16)
def paper_experiment(paper: str, dim: str, quick: bool, dof: int, signals: str) -> Experiment:
    """Paper ``paper``'s own sweep on ``dim``'s body (2D: the paper's default)."""
    body = {} if dim == "2d" else {"dof": dof, "signals": signals}
    return module(paper).build(quick=quick, **body)


def recorded(exp: Experiment) -> dict:
    """A paper's own sweep config as its config.json records it."""
    return exp.config.to_dict() if hasattr(exp.config, "to_dict") else asdict(exp.config)


def _paper_of(cfg: Config, row: Row) -> tuple[Experiment, Row]:
    p = row.params
    exp = paper_experiment(p["paper"], p["dim"], cfg.quick, cfg.dof, cfg.signals)
    return exp, next(r for r in exp.rows if r.row_id == p["row"])


def run_batch(cfg: Config, row: Row, seeds: list[int]) -> list:
    """The paper's own ``run_batch`` of the paper's row on this row's body."""
    exp, paper_row = _paper_of(cfg, row)
    return exp.run_batch(paper_row, seeds)


def train_configs(cfg: Config, row: Row) -> dict:
    """The TrainConfigs the paper's own row trains (its module's ``train_config(s)``), for
    the sweep's memory estimate."""
    from skinny_mj.memory import row_configs

    exp, paper_row = _paper_of(cfg, row)
    return dict(enumerate(row_configs(module(row.params["paper"]), exp, paper_row)))


def run_one(cfg: Config, row: Row, seed: int) -> dict:
    exp, paper_row = _paper_of(cfg, row)
    return dict(exp.run_one(paper_row, seed))


#: One run's CPU seconds on the 2D body, idle core, lockstep batches of 10 (measured;
#: only the schedule uses it, to start the costliest batches first), and the 3D factor.
SECONDS_2D = {"a": 3.0, "b": 5.0, "c": 25.0}
FACTOR_3D = 1.8


def cost(cfg: Config, row: Row) -> float:
    """Seconds-like cost: the paper's own relative cost of the row, scaled to seconds
    by the paper's mean over :data:`SUBSET` (paper costs are in different units)."""
    exp, paper_row = _paper_of(cfg, row)
    p = row.params["paper"]
    own = [exp.cost(r) for r in exp.rows if r.row_id in subset(cfg.quick)[p]]
    scale = SECONDS_2D[p] * (FACTOR_3D if row.params["dim"] == "3d" else 1.0)
    return scale * exp.cost(paper_row) / (sum(own) / len(own))


def subset(quick: bool) -> dict[str, tuple[str, ...]]:
    return QUICK_SUBSET if quick else SUBSET


def rows(cfg: Config) -> tuple[Row, ...]:
    """Every paper row of the subset on the 2D body, then on the 3D one (its 2D twin's
    seeds); params: paper, dim, row (the paper's row id) and the paper row's params."""
    out = []
    for dim in DIMS:
        for p, ids in subset(cfg.quick).items():
            exp = paper_experiment(p, dim, cfg.quick, cfg.dof, cfg.signals)
            by_id = {r.row_id: r for r in exp.rows}
            for rid in ids:
                r = by_id[rid]
                out.append(Row(row_id(p, dim, rid),
                               {"paper": p, "dim": dim, "row": rid, **r.params}, r.paper,
                               seeds_of=None if dim == "2d" else row_id(p, "2d", rid)))
    return tuple(out)


def build(quick: bool = False, movement: str | None = None, asf: str | None = None,
          dof: int | None = None, signals: str | None = None) -> Experiment:
    """The 2D + 3D sweep; ``dof`` / ``signals`` replace the 3D body's (default 8 DOF,
    Cartesian); ``quick``: each paper's --quick config on 2 of its rows, 2 runs (a smoke
    test). ``movement`` does not apply (each paper's rows name their movements)."""
    if movement is not None or asf is not None:
        from skinny_mj.errors import SkinnyInputError

        raise SkinnyInputError("three-d runs the papers' own movements; --movement/--asf "
                               "do not apply")
    base = Config(quick=quick, dof=8 if dof is None else int(dof),
                  signals="cartesian" if signals is None else str(signals),
                  runs=2 if quick else 10)
    papers = {f"{p}-{d}": recorded(paper_experiment(p, d, quick, base.dof, base.signals))
              for p in PAPERS for d in DIMS}
    cfg = Config(base.quick, base.dof, base.signals, base.runs, papers)
    groups = {**{p: tuple(row_id(p, d, r) for d in DIMS for r in ids)
                 for p, ids in subset(quick).items()},
              **{d: tuple(row_id(p, d, r) for p, ids in subset(quick).items() for r in ids)
                 for d in DIMS},
              **{f"{p}-{d}": tuple(row_id(p, d, r) for r in ids)
                 for p, ids in subset(quick).items() for d in DIMS}}
    if not quick:
        groups["core"] = tuple(row_id(p, d, r) for d in DIMS for p, ids in CORE.items()
                               for r in ids)
    return Experiment(name=NAME, rows=rows(cfg), run_one=functools.partial(run_one, cfg),
                      run_batch=functools.partial(run_batch, cfg),
                      cost=functools.partial(cost, cfg), config=cfg, runs=cfg.runs,
                      groups=groups, table_columns=("performance_nrmse", "feedback_share",
                                                    "relative_error_x1",
                                                    "ymca__position_nrmse", "wall_s"))


def report(results: dict, out_dir: Path) -> str:
    """The 2D vs 3D table, each paper's figures and claims per body, the claims side by
    side and the figure (:mod:`skinny_mj.experiments.three_d.report`)."""
    from skinny_mj.experiments.three_d import report as three_d_report

    return three_d_report.report(results, Path(out_dir))
