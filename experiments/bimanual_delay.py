"""Bimanual coordination under sensory delay: does a forward model per arm rescue it?

The thesis's future work (§4.3) joins paper B and paper A: "add delays in the
sensory-motor loop during the bimanual experiments ... each arm could have both an
inverse model and a forward model as in the delay experiments ... the control system of
one arm could have access to the prediction made by the other arm's forward model", and
(§4.1) "we would consider sharing motor commands instead of position".

Rows ``<pattern>-<architecture>-d<delay>``: paper B's plant and run (a forced leading
arm, the lagging arm's ESN inverse model seeing both arms' sensed joint angles, FEL with
K 1 -> 0, tests with the leader at 1x, 0.5x, 1.5x and K = 0: :func:`experiments.paper_b.
run_batch`) with paper A's delay (``plant.delay``: the internal models' sensed
input lags by 0-10 steps, the feedback controller's does not) and, per architecture,
the lagging arm's inverse model gets besides the delayed sensed state of both arms:

- ``inverse``: nothing more (paper B's network, delayed);
- ``forward``: its own forward model's prediction of its next position (paper A's
  parallel forward model, per arm: :mod:`controllers.arm_forward`);
- ``share-predictions``: that, and the leading arm's forward model's prediction of the
  leader's next position (from the leader's delayed state and its forced command);
- ``share-commands``: its own prediction and the leading arm's last motor command (an
  efference copy, not delayed) in place of the leader's prediction.

Coordination is paper B's: the lagging shoulder's timing error against its desired
(which is defined relative to the leader) in degrees of its period
(:func:`skinny_mj.bimanual.phase_lag_deg`) and the relative error (RMS error / RMS of
the desired swing), at the trained and at the new speeds; plus the lagging arm's
position NRMSE at 1x.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field, replace
from pathlib import Path

from experiments import paper_b
from skinny_mj.config import TrainConfig, relative_cost
from skinny_mj.experiment import Experiment, Row, RunFailed
from skinny_mj.sweep import one_of_batch

NAME = "bimanual-delay"
#: architecture -> the forward models' ``forward.sharing`` (None: no forward model)
ARCHITECTURES = {"inverse": None, "forward": "none", "share-predictions": "predictions",
                 "share-commands": "commands"}
DELAYS = (0, 2, 4, 6, 10)
PATTERNS = ("phase0", "phase180")
SPEEDS = paper_b.SPEEDS
#: Paper B's run (:data:`experiments.paper_b.MODEL`: N = 100, sensed-only inputs, new
#: method, K 1 -> 0) with a shorter schedule to fit the compute budget (our choice):
#: β = 0.1 with 3 learning cycles per epoch and 10 epochs (paper E's experiment 5) in
#: place of paper B's β = 0.01, 5 cycles, 50 epochs; forward networks N = 100 (paper A;
#: ``forward`` holds their settings, each row chooses whether it has them).
MODEL = paper_b.MODEL.override({"rule.beta": 0.1, "rule.cycles": 3, "rule.epochs": 10,
                                "forward": "parallel", "forward.reservoir": 100})


@dataclass(frozen=True)
class Config:
    """The sweep: the run (``model``; each row sets its pattern, delay and architecture),
    the patterns, the delays and the runs per row."""

    model: TrainConfig = field(default_factory=lambda: MODEL)
    patterns: tuple[str, ...] = PATTERNS
    delays: tuple[int, ...] = DELAYS
    runs: int = 10


def row_id(pattern: str, architecture: str, delay: int) -> str:
    return f"{pattern}-{architecture}-d{delay}"


def rows(cfg: Config) -> tuple[Row, ...]:
    return tuple(Row(row_id(p, a, d), {"pattern": p, "architecture": a, "delay": d})
                 for p in cfg.patterns for a in ARCHITECTURES for d in cfg.delays)


def train_config(cfg: Config, row: Row) -> TrainConfig:
    """The row's run: its delay and (but for ``inverse``) the per-arm forward models."""
    sharing = ARCHITECTURES[row.params["architecture"]]
    forward = {"forward": "none"} if sharing is None else \
        {"forward": "parallel", "forward.sharing": sharing}
    return cfg.model.override({"movement.trajectory": paper_b.PREFIX + row.params["pattern"],
                               "plant.delay": int(row.params["delay"]), **forward})


def _tag(speed: float) -> str:
    return f"x{speed:g}"


def run_batch(cfg: Config, row: Row, seeds: list[int]) -> list:
    """Paper B's training and tests (:func:`experiments.paper_b.run_batch`) of the row's
    config, for several seeds in lockstep; adds |timing error| per speed and the worst
    over the three speeds."""
    pb = paper_b.Config(model=train_config(cfg, row), runs=cfg.runs)
    outs = paper_b.run_batch(pb, Row(row.params["pattern"], {}), seeds)
    for out in outs:
        if isinstance(out, RunFailed):
            continue
        lags = [abs(out[f"phase_lag_deg_{_tag(s)}"]) for s in SPEEDS]
        for s, v in zip(SPEEDS, lags, strict=True):
            out[f"abs_phase_lag_deg_{_tag(s)}"] = v
        out["worst_abs_phase_lag_deg"] = max(lags)
        out["worst_relative_error"] = max(out[f"relative_error_{_tag(s)}"] for s in SPEEDS)
    return outs


def run_one(cfg: Config, row: Row, seed: int) -> dict:
    """One run of ``row``: :func:`run_batch` of one seed."""
    return dict(one_of_batch(functools.partial(run_batch, cfg), row, seed))


def cost(cfg: Config, row: Row) -> float:
    """One run's relative cost: its training's size x its networks (a forward network
    costs about as much as the inverse one)."""
    nets = {None: 1, "none": 2, "commands": 2, "predictions": 3}
    tcfg = train_config(cfg, row)
    return relative_cost(tcfg) * nets[getattr(tcfg.forward, "sharing", None)]


def quick_config() -> Config:
    """A smoke test (2 epochs, one pattern, delays 0 and 4, one run), not a result."""
    return Config(model=MODEL.override({"rule.epochs": 2, "rule.cycles": 1}),
                  patterns=("phase0",), delays=(0, 4), runs=1)


TABLE_COLUMNS = ("position_nrmse_x1", "relative_error_x1", "worst_relative_error",
                 "abs_phase_lag_deg_x1", "abs_phase_lag_deg_x0.5", "abs_phase_lag_deg_x1.5")


def build(quick: bool = False, movement: str | None = None, asf: str | None = None,
          dof: int | None = None, signals: str | None = None) -> Experiment:
    """The sweep over (pattern, architecture, delay); ``quick``: :func:`quick_config`.
    ``dof`` 8 runs the patterns on the 3D body; the movements are paper B's patterns
    and the signals its joint angles (``--movement``/``--asf``/``--signals`` do not apply:
    the per-arm forward models need joint signals)."""
    if movement is not None or asf is not None or signals not in (None, "joint"):
        from skinny_mj.errors import SkinnyInputError

        raise SkinnyInputError("bimanual-delay runs paper B's patterns on joint signals; "
                               "--movement/--asf/--signals do not apply")
    cfg = quick_config() if quick else Config()
    if dof is not None:
        cfg = replace(cfg, model=cfg.model.override({"plant.dof": dof}))
    groups = {a: tuple(row_id(p, a, d) for p in cfg.patterns for d in cfg.delays)
              for a in ARCHITECTURES}
    groups.update({p: tuple(row_id(p, a, d) for a in ARCHITECTURES for d in cfg.delays)
                   for p in cfg.patterns})
    return Experiment(name=NAME, rows=rows(cfg), run_one=functools.partial(run_one, cfg),
                      run_batch=functools.partial(run_batch, cfg),
                      cost=functools.partial(cost, cfg), config=cfg, runs=cfg.runs,
                      groups=groups, table_columns=TABLE_COLUMNS)


def report(results: dict, out_dir: Path) -> str:
    """Figures (metrics against delay per architecture; traces at the largest delay)
    and the comparisons with the inverse-only network: :mod:`experiments.bimanual_delay_report`."""
    from experiments.bimanual_delay_report import report as _report

    return _report(results, Path(out_dir))
