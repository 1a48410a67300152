"""Bimanual coordination under sensory delay: does a forward model per arm rescue it?

The thesis's future work (§4.3) joins paper B and paper A: "add delays in the
sensory-motor loop during the bimanual experiments ... each arm could have both an
inverse model and a forward model as in the delay experiments ... the control system of
one arm could have access to the prediction made by the other arm's forward model", and
(§4.1) "we would consider sharing motor commands instead of position".

Rows ``<pattern>-<architecture>-d<delay>``: paper B's plant and run (a forced leading
arm, the lagging arm's ESN inverse model seeing both arms' sensed joint angles, FEL with
K 1 -> 0, tests with the leader at 1x, 0.5x, 1.5x and K = 0:
:data:`skinny_mj.experiments.paper_b.TESTS`) with paper A's delay (``plant.delay``: the
internal models' sensed input lags by 0-10 steps, the feedback controller's does not)
and, per architecture,
the lagging arm's inverse model gets besides the delayed sensed state of both arms:

- ``inverse``: nothing more (paper B's network, delayed);
- ``forward``: its own forward model's prediction of its next position (paper A's
  parallel forward model, per arm: :mod:`skinny_mj.controllers.arm_forward`);
- ``share-predictions``: that, and the leading arm's forward model's prediction of the
  leader's next position (from the leader's delayed state and its forced command);
- ``share-commands``: its own prediction and the leading arm's last motor command (an
  efference copy, not delayed) in place of the leader's prediction.

Coordination is paper B's: the lagging shoulder's timing error against its desired
(which is defined relative to the leader) in degrees of its period
(:func:`skinny_mj.plant.bimanual.phase_lag_deg`) and the relative error (RMS error / RMS of
the desired swing), at the trained and at the new speeds; plus the lagging arm's
position NRMSE at 1x.
"""

from __future__ import annotations

from skinny_mj.experiments import paper_b

from skinny_mj.engine.study import Quick, Row, Study

NAME = "bimanual-delay"
#: architecture -> the forward models' ``forward.sharing`` (None: no forward model)
ARCHITECTURES = {"inverse": None, "forward": "none", "share-predictions": "predictions",
                 "share-commands": "commands"}
DELAYS = (0, 2, 4, 6, 10)
PATTERNS = ("phase0", "phase180")
SPEEDS = paper_b.SPEEDS
#: Paper B's run (:data:`skinny_mj.experiments.paper_b.MODEL`: N = 100, sensed-only inputs, new
#: method, K 1 -> 0) with a shorter schedule to fit the compute budget (our choice):
#: β = 0.1 with 3 learning cycles per epoch and 10 epochs (paper E's experiment 5) in
#: place of paper B's β = 0.01, 5 cycles, 50 epochs; forward networks N = 100 (paper A;
#: ``forward`` holds their settings, each row chooses whether it has them).
MODEL = paper_b.MODEL.override({"method.beta": 0.1, "method.cycles": 3, "method.epochs": 10,
                                "forward": "parallel", "forward.reservoir": 100})


def row_id(pattern: str, architecture: str, delay: int) -> str:
    return f"{pattern}-{architecture}-d{delay}"


def _row(pattern: str, architecture: str, delay: int) -> Row:
    """The row's run: its pattern, its delay and (but for ``inverse``) the per-arm
    forward models."""
    sharing = ARCHITECTURES[architecture]
    forward = {"forward": "none"} if sharing is None else \
        {"forward": "parallel", "forward.sharing": sharing}
    return Row(row_id(pattern, architecture, delay),
               {"movement.trajectory": paper_b.PREFIX + pattern, "plant.delay": delay,
                **forward},
               params={"pattern": pattern, "architecture": architecture, "delay": delay})


def _tag(speed: float) -> str:
    return f"x{speed:g}"


def metrics(result) -> dict:
    """Paper B's metrics (:func:`skinny_mj.experiments.paper_b.metrics`) of the row's run,
    with |timing error| per speed and the worst over the three speeds."""
    out = paper_b.metrics(result)
    lags = [abs(out[f"phase_lag_deg_{_tag(s)}"]) for s in SPEEDS]
    for s, v in zip(SPEEDS, lags, strict=True):
        out[f"abs_phase_lag_deg_{_tag(s)}"] = v
    out["worst_abs_phase_lag_deg"] = max(lags)
    out["worst_relative_error"] = max(out[f"relative_error_{_tag(s)}"] for s in SPEEDS)
    return out


TABLE_COLUMNS = ("position_nrmse_x1", "relative_error_x1", "worst_relative_error",
                 "abs_phase_lag_deg_x1", "abs_phase_lag_deg_x0.5", "abs_phase_lag_deg_x1.5")


STUDY = Study(
    name=NAME, description=__doc__, base=MODEL, runs=10,
    # paper B's run: its tests at three leader speeds, its failures, its metrics and ours
    tests=paper_b.TESTS, failure=paper_b.failure, metrics=metrics,
    rows=tuple(_row(p, a, d) for p in PATTERNS for a in ARCHITECTURES for d in DELAYS),
    groups={**{a: [row_id(p, a, d) for p in PATTERNS for d in DELAYS] for a in ARCHITECTURES},
            **{p: [row_id(p, a, d) for a in ARCHITECTURES for d in DELAYS] for p in PATTERNS}},
    columns=TABLE_COLUMNS,
    # a smoke test (2 epochs, one pattern, delays 0 and 4, one run), not a result
    quick=Quick({"method.epochs": 2, "method.cycles": 1}, runs=1,
                rows=tuple(row_id("phase0", a, d) for a in ARCHITECTURES for d in (0, 4))),
    # --dof 8 runs the patterns on the 3D body; the movements are paper B's patterns and
    # the signals its joint angles (the per-arm forward models need joint signals)
    takes=("body",), report="skinny_mj.experiments.bimanual_delay.report:report",
)
