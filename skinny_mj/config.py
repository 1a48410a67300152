"""The one run configuration every experiment and command configures.

:class:`TrainConfig` says everything one training run of an ESN inverse model needs,
grouped as the thesis's papers vary it:

- plant: ``dof`` (4 = 2D, 8 = 3D), ``signals`` (joint angles or Cartesian segment
  vectors), ``actuation`` (velocity servo or torque), ``sensor_noise``,
  ``leading_arm`` (paper B: that arm is forced along the movement and the ESN drives
  the other one), ``plant`` (the lockstep MuJoCo batch, or the dm_control env);
- movement: ``trajectory`` (+ ``asf``), ``speed``, ``reps``, ``max_speed_from`` (the
  movement whose speeds set full scale);
- ESN: ``reservoir``, ``spectral_radius``, ``noise``, ``readout``, ``ridge``,
  ``ridge_select`` (lambda per FEL fit from a log grid, on a validation cycle:
  :mod:`controllers.ridge_select`), ``inputs`` (desired + sensed, or sensed only as in paper B);
- architecture: ``delay`` (steps on the sensed input to the internal models, paper A),
  ``forward`` (a forward model: parallel, serial or hybrid, paper A), its size and its
  ``forward_input`` (the delayed sensed position, or its own chained prediction);
  ``forward_sharing`` (paper B's plant: one forward model per arm and what the lagging
  arm gets of the leading arm's, :mod:`controllers.arm_forward`; issue 16);
- schedule: ``method`` (original, new β, true target), ``beta``, ``cycles``,
  ``epochs``, the feedback gain schedule (linear 1 → 0, ×factor per epoch, fixed),
  ``tt_cycles``, and ``test_washout_cycles`` (unscored cycles before the scored test);
- torque (``actuation="torque"``; :mod:`skinny_mj.torque_training`): the
  ``feedback`` teacher ("pd" limit-scaled, "inertia-pd" in the arm's own coordinates;
  "computed-torque", "ct", "id-pd", "pd-gravity" for a controller alone), the poles
  ``feedback_omega`` / ``feedback_zeta`` of the arm's laws (:mod:`controllers.torque_arm`),
  FEL's ``readout_fit`` ("cycle", or remembering earlier cycles: "forgetting", "rls") and
  its ``readout_forgetting``,
  ``gravity_feedforward`` (bias torque / limit added to the command, not learned),
  ``velocity_inputs`` (None: on for torque) and the test plant's ``test_payload_kg``
  (in the right hand) and ``test_mass_scale`` (every arm link);
- test: ``test_gain`` (K at test: 0 = the ESN alone; > 0 = the feedback left on);
  ``method="none"`` trains nothing, so the test is the feedback controller alone.

A paper's row is ``dataclasses.replace(base, ...)`` of this one dataclass; the
defaults are paper E's experiment 5.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import asdict, dataclass, replace
from typing import Any

from skinny_mj.body import ACTUATIONS, SIGNALS, check_actuation, check_dof, check_signals
from skinny_mj.errors import SkinnyInputError

__all__ = ["TrainConfig", "relative_cost", "with_overrides", "check_dof", "check_signals",
           "check_actuation", "METHODS", "SIGNALS", "ACTUATIONS", "DEFAULT_NOISE",
           "PAPER_CYCLES_FOR_BETA"]

METHODS = ("original", "new", "true-target", "none")
#: Laws of controllers.torque_arm (inertia-scaled pole placement), by feedback name:
#: three controllers alone, and FEL's teacher "inertia-pd"
ARM_LAWS = {"ct": "ct", "id-pd": "id-pd", "pd-gravity": "pd-g", "inertia-pd": "fel"}
FEEDBACKS = ("pd", "computed-torque", *ARM_LAWS)
READOUT_FITS = ("cycle", "forgetting", "rls")
INPUTS = ("desired+sensed", "sensed")
FORWARD_MODES = ("parallel", "serial", "hybrid")
FORWARD_INPUTS = ("sensed", "chained")
FORWARD_SHARING = ("none", "predictions", "commands")
GAIN_SCHEDULES = ("linear", "multiplicative", "fixed")
ARMS = ("right", "left")
RETARGETS = ("angles", "positions")
#: Learning cycles per epoch the paper derived from its Figure 3 (paper E, Table 1).
PAPER_CYCLES_FOR_BETA = {0.3: 2, 0.1: 3, 0.05: 6}
#: Reservoir noise the paper chose per method (paper E, Fig. 5).
DEFAULT_NOISE = {"original": 0.03, "new": 0.2, "true-target": 0.2, "none": 0.0}


def _finite_at_least(value: float, low: float) -> bool:
    return isinstance(value, int | float) and math.isfinite(value) and value >= low


@dataclass(frozen=True)
class TrainConfig:
    """One training run. Defaults: paper E experiment 5 (2D, Cartesian, N = 200,
    spectral radius 0.5, reservoir noise 0.2, β = 0.1 with 3 learning cycles per
    epoch, 10 epochs, K 1 → 0 linearly, sensor noise 0.01)."""

    # plant
    dof: int = 4
    signals: str = "cartesian"
    actuation: str = "velocity"
    sensor_noise: float = 0.01
    leading_arm: str | None = None  # paper B: this arm is forced, the ESN drives the other
    plant: str = "batch"  # "batch" (MjData stepped directly) or "env" (dm_control)
    # movement
    trajectory: str = "ymca"
    asf: str | None = None
    speed: float = 1.0
    reps: int = 1
    max_speed_from: str | None = None  # movement whose speeds set full scale (None: this one)
    full_scale_factor: float = 2.0  # full scale = this x the fastest speed per DOF (issue 13)
    # ESN
    reservoir: int = 200
    spectral_radius: float = 0.5
    noise: float | None = None  # reservoir noise ν; None: DEFAULT_NOISE[method]
    readout: str = "pinv"
    ridge: float = 1e-6
    ridge_select: bool = False  # ridge: lambda per run and fit on a validation cycle (issue 16)
    inputs: str = "desired+sensed"
    # architecture (paper A)
    delay: int = 0  # steps by which the internal models' sensed input lags
    forward: str | None = None  # forward model: None, "parallel", "serial" or "hybrid"
    forward_reservoir: int = 100
    forward_input: str = "sensed"  # its position input: the (delayed) sensed s(t - d), or
    # "chained": its own previous prediction p(t) when the delay hides s(t) (fidelity-a)
    # paper B + A (issue 16): per-arm forward models; the lagging arm gets of the leader's
    # "none", its forward model's "predictions" or its "commands" (None: one forward model)
    forward_sharing: str | None = None
    # schedule
    method: str = "new"
    beta: float = 0.1
    cycles: int | None = None  # learning cycles per epoch (new method); None: from β
    epochs: int = 10
    gain_schedule: str = "linear"  # K per epoch: linear 1 -> 0, multiplicative, fixed
    gain_factor: float = 0.9  # multiplicative: K = factor ** epoch (paper C)
    gain_value: float = 0.65  # fixed: K (paper A)
    tt_cycles: int = 50  # true-target with β < 1: cycles (paper D: 50 rounds); β = 1: one fit
    test_washout_cycles: int = 0  # unscored K = 0 cycles before the scored test (papers B, C)
    test_gain: float = 0.0  # K at test: 0 = the ESN alone, > 0 = the feedback left on
    # torque (actuation="torque" only; skinny_mj.torque_training)
    feedback: str = "pd"  # FEL's teacher; "computed-torque" (PD + ID): the controller alone
    gravity_feedforward: bool = False  # add qfrc_bias / limit to the command (not learned)
    velocity_inputs: bool | None = None  # [qd_d(t+1); qd(t)] / v_max inputs; None: torque
    feedback_omega: float | None = None  # ARM_LAWS' poles, rad/s (None: the law's default)
    feedback_zeta: float = 1.0  # ARM_LAWS' damping ratio
    readout_fit: str = "cycle"  # FEL fits: "cycle" (each cycle alone), "forgetting", "rls"
    readout_forgetting: float = 0.8  # their memory: old cycles' weight per learning cycle
    test_payload_kg: float = 0.0  # point mass at the right hand's CoM in the test plant
    test_mass_scale: float = 1.0  # every arm link's mass and inertia x this at test
    # the toolbox's protocol (issue 12); defaults are today's behaviour, bit for bit
    test_noise: bool = False  # reservoir noise during the K = 0 test (the toolbox: on)
    u_error_gain: float = 1.0  # scalar on the feedback controller's u_error (thesis: unstated)
    tt_input_noise: float = 0.0  # Gaussian SD on the true-target's teacher-forced inputs
    retarget: str = "angles"  # motion capture: by joint angles, or "positions" (segment vectors)

    def __post_init__(self) -> None:
        check_dof(self.dof)
        check_signals(self.signals)
        check_actuation(self.actuation)
        checks = [
            (self.method in METHODS, f"method must be one of {METHODS}, got {self.method!r}"),
            (_finite_at_least(self.beta, 0) and 0 < self.beta <= 1,
             f"--beta must be in (0, 1], got {self.beta}"),
            (self.cycles is None or self.cycles >= 1, f"--cycles must be >= 1, got {self.cycles}"),
            (self.epochs >= 1, f"--epochs must be >= 1, got {self.epochs}"),
            (self.reservoir >= 1, f"--reservoir must be >= 1, got {self.reservoir}"),
            (self.forward_reservoir >= 1,
             f"forward_reservoir must be >= 1, got {self.forward_reservoir}"),
            (_finite_at_least(self.spectral_radius, 0),
             f"--spectral-radius must be >= 0, got {self.spectral_radius}"),
            (self.noise is None or _finite_at_least(self.noise, 0),
             f"--noise must be >= 0, got {self.noise}"),
            (_finite_at_least(self.sensor_noise, 0),
             f"--sensor-noise must be >= 0, got {self.sensor_noise}"),
            (self.readout in ("pinv", "ridge"),
             f"--readout must be pinv or ridge, got {self.readout!r}"),
            (_finite_at_least(self.ridge, 0), f"--ridge must be >= 0, got {self.ridge}"),
            (not self.ridge_select or (self.readout == "ridge" and self.method in
                                       ("original", "new") and self.actuation == "velocity"),
             "ridge_select chooses the ridge lambda of FEL fits on a validation cycle: it "
             "needs readout='ridge', method original or new, and the velocity body"),
            (self.reps >= 1, f"--reps must be >= 1, got {self.reps}"),
            (_finite_at_least(self.full_scale_factor, 1e-9) and self.full_scale_factor > 0,
             f"full_scale_factor must be > 0, got {self.full_scale_factor}"),
            (_finite_at_least(self.speed, 0) and 0 < self.speed <= 10,
             f"--speed must be in (0, 10], got {self.speed}"),
            (self.plant in ("batch", "env"), f"plant must be 'batch' or 'env', got {self.plant!r}"),
            (self.inputs in INPUTS, f"inputs must be one of {INPUTS}, got {self.inputs!r}"),
            (self.delay >= 0, f"delay must be >= 0 steps, got {self.delay}"),
            (self.forward is None or self.forward in FORWARD_MODES,
             f"forward must be None or one of {FORWARD_MODES}, got {self.forward!r}"),
            (self.forward_input in FORWARD_INPUTS and (self.forward_input == "sensed"
                                                       or self.forward is not None),
             f"forward_input must be one of {FORWARD_INPUTS} ('chained' with a forward "
             f"model), got {self.forward_input!r}"),
            (self.forward_sharing is None or (
                self.forward_sharing in FORWARD_SHARING and self.leading_arm is not None
                and self.forward == "parallel" and self.signals == "joint"),
             f"forward_sharing must be None or one of {FORWARD_SHARING}, with a leading "
             f"arm, forward='parallel' and joint signals; got {self.forward_sharing!r}"),
            (self.gain_schedule in GAIN_SCHEDULES,
             f"gain schedule must be one of {GAIN_SCHEDULES}, got {self.gain_schedule!r}"),
            (0 < self.gain_factor <= 1, f"gain factor must be in (0, 1], got {self.gain_factor}"),
            (_finite_at_least(self.gain_value, 0),
             f"feedback gain must be >= 0, got {self.gain_value}"),
            (self.tt_cycles >= 1, f"tt_cycles must be >= 1, got {self.tt_cycles}"),
            (self.test_washout_cycles >= 0,
             f"test washout cycles must be >= 0, got {self.test_washout_cycles}"),
            (isinstance(self.test_noise, bool), f"test_noise must be a bool, got "
                                                 f"{self.test_noise!r}"),
            (_finite_at_least(self.u_error_gain, 0) and self.u_error_gain > 0,
             f"--u-error-gain must be > 0, got {self.u_error_gain}"),
            (_finite_at_least(self.tt_input_noise, 0),
             f"--tt-input-noise must be >= 0, got {self.tt_input_noise}"),
            (self.retarget in RETARGETS,
             f"--retarget must be one of {RETARGETS}, got {self.retarget!r}"),
            (self.leading_arm is None or self.leading_arm in ARMS,
             f"leading arm must be None or one of {ARMS}, got {self.leading_arm!r}"),
            (self.method != "true-target" or (self.forward is None and self.delay == 0
                                              and self.leading_arm is None),
             "the true-target architecture takes no forward model, delay or leading arm"),
            (_finite_at_least(self.test_gain, 0), f"test gain must be >= 0, got {self.test_gain}"),
            (self.method != "none" or self.test_gain > 0,
             "method 'none' tests the feedback controller alone: it needs test_gain > 0"),
            (self.feedback in FEEDBACKS,
             f"feedback must be one of {FEEDBACKS}, got {self.feedback!r}"),
            (self.feedback in ("pd", "inertia-pd") or self.method == "none",
             f"the {self.feedback} controller runs alone (method 'none'); FEL's teacher is "
             "'pd' or 'inertia-pd'"),
            (self.feedback != "inertia-pd" or self.method in ("original", "new", "none"),
             "the 'inertia-pd' teacher goes with feedback-error learning (original or new) "
             "or runs alone (method 'none')"),
            (self.readout_fit in READOUT_FITS and (self.readout_fit == "cycle" or (
                self.actuation == "torque" and self.method in ("original", "new"))),
             f"readout_fit must be one of {READOUT_FITS} ('forgetting' and 'rls' with FEL "
             f"on the torque body), got {self.readout_fit!r}"),
            (_finite_at_least(self.readout_forgetting, 0) and self.readout_forgetting <= 1,
             f"readout_forgetting must be in [0, 1], got {self.readout_forgetting}"),
            (self.feedback_omega is None or _finite_at_least(self.feedback_omega, 0),
             f"feedback_omega must be >= 0 rad/s, got {self.feedback_omega}"),
            (_finite_at_least(self.feedback_zeta, 0),
             f"feedback_zeta must be >= 0, got {self.feedback_zeta}"),
            (self.actuation == "torque" or (
                self.feedback == "pd" and not self.gravity_feedforward
                and self.feedback_omega is None and self.feedback_zeta == 1.0
                and not self.velocity_inputs and self.test_payload_kg == 0
                and self.test_mass_scale == 1),
             "feedback, gravity_feedforward, velocity_inputs, test_payload_kg and "
             "test_mass_scale are torque settings: use actuation='torque'"),
            (self.actuation != "torque" or (self.forward is None and self.delay == 0
                                            and self.leading_arm is None
                                            and self.inputs == "desired+sensed"),
             "the torque body runs without a forward model, delay, leading arm or "
             "sensed-only inputs"),
            (not self.gravity_feedforward or self.method in ("original", "new"),
             "gravity_feedforward goes with feedback-error learning (original or new)"),
            (_finite_at_least(self.test_payload_kg, 0),
             f"test payload must be >= 0 kg, got {self.test_payload_kg}"),
            (_finite_at_least(self.test_mass_scale, 0) and self.test_mass_scale > 0,
             f"test mass scale must be > 0, got {self.test_mass_scale}"),
            (self.plant != "env" or (self.leading_arm is None and self.forward is None),
             "the dm_control plant (plant='env') runs neither paper B's forced arm nor a "
             "forward model; use plant='batch'"),
        ]
        for ok, message in checks:
            if not ok:
                raise SkinnyInputError(message)

    @property
    def noise_level(self) -> float:
        return DEFAULT_NOISE[self.method] if self.noise is None else self.noise

    @property
    def uses_velocity_inputs(self) -> bool:
        """Velocity inputs on: as set, else on for the torque body."""
        return self.actuation == "torque" if self.velocity_inputs is None \
            else bool(self.velocity_inputs)

    @property
    def learning_cycles(self) -> int:
        """Learning cycles per epoch: 1 for the original method; for the new method the
        paper's Table 1 where it has β, else enough cycles for (1 − β)^n to fall below
        5 % over all epochs (which reproduces the table for β = 0.1 and 0.05)."""
        if self.cycles is not None:
            return self.cycles
        if self.method != "new":
            return 1
        for beta, cycles in PAPER_CYCLES_FOR_BETA.items():
            if abs(self.beta - beta) < 1e-12:
                return cycles
        if self.beta >= 1:
            return 1
        total = math.ceil(math.log(0.05) / math.log(1.0 - self.beta))
        return max(1, math.ceil(total / self.epochs))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready, with the derived ``learning_cycles`` and ``noise_level``."""
        return {**asdict(self), "learning_cycles": self.learning_cycles,
                "noise_level": self.noise_level}

    def override(self, mapping: dict[str, Any]) -> TrainConfig:
        """This config with the fields of ``mapping`` replaced (validated again)."""
        if unknown := sorted(set(mapping) - {f.name for f in dataclasses.fields(self)}):
            raise SkinnyInputError(f"unknown training config key(s) {unknown}")
        return replace(self, **mapping)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> TrainConfig:
        """From :meth:`to_dict` (or a ``config.json``'s ``config``): unknown keys are an
        error, derived keys are ignored."""
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(d) - names - {"learning_cycles", "noise_level"})
        if unknown:
            raise SkinnyInputError(f"unknown training config field(s) {unknown}")
        fields = {k: v for k, v in d.items() if k in names}
        for f in dataclasses.fields(cls):  # a file's "reps": null must not reach a `>=`
            if f.name in fields and not _has_type(fields[f.name], str(f.type)):
                raise SkinnyInputError(f"bad training config (field {f.name!r} must be "
                                       f"{f.type}, got {fields[f.name]!r})")
        return cls(**fields)


_TYPES = {"int": (int,), "float": (int, float), "str": (str,), "bool": (bool,),
          "None": (type(None),)}


def _has_type(value: Any, annotation: str) -> bool:
    """``value`` fits a field annotated ``annotation`` ("int", "float | None", ...); a
    bool is no int or float here (JSON true is not 1)."""
    kinds = [k.strip() for k in annotation.split("|")]
    if isinstance(value, bool):
        return "bool" in kinds
    return any(isinstance(value, _TYPES.get(k, (object,))) for k in kinds)


def relative_cost(cfg: TrainConfig) -> float:
    """A training's size, for scheduling sweeps (longest first): its cycles through the
    movement (FEL: epochs x (learning cycles + washout + evaluation); true target: its
    cycles; x reps; + the test), x N / 200 for reservoirs above 200 units."""
    cycles = cfg.tt_cycles if cfg.method == "true-target" \
        else 0 if cfg.method == "none" else cfg.epochs * (cfg.learning_cycles + 2)
    return (cycles * cfg.reps + 1 + cfg.test_washout_cycles) * max(1.0, cfg.reservoir / 200)


def with_overrides(cfg: TrainConfig, **changes: Any) -> TrainConfig:
    """``cfg`` with the fields that are not None replaced (validated again)."""
    return replace(cfg, **{k: v for k, v in changes.items() if v is not None})
