"""The one run configuration every experiment and command configures.

:class:`TrainConfig` says everything one training run of an ESN inverse model needs, as
a composition of the parts' own configurations:

- ``plant`` (:class:`Plant`): the ``body`` by name (``2d``, ``3d``, their torque twins
  ``2d-torque`` and ``3d-torque``, or a registered one; ``plant.dof=4|8`` names Skinny's
  2D and 3D), its ``signals`` (joint
  angles or Cartesian segment vectors), ``sensor_noise``, the sensory ``delay`` of the
  internal models' sensed input (paper A), paper B's forced ``leading_arm`` and the
  simulation ``backend`` (the lockstep MuJoCo batch, or the dm_control env);
- ``actuation``: :class:`Velocity` (the servo) or :class:`Torque` (the torque twin, with
  its feedback teacher, poles, gravity feed-forward, velocity inputs and the test
  plant's payload and mass scale: settings that exist only on the torque body). The
  body and the actuation agree: ``plant.body`` alone sets the actuation its MJCF has,
  ``actuation`` picks the body's twin of that actuation (``2d`` and ``2d-torque``), and
  ``plant.dof`` names Skinny's body of that many hinges;
- ``movement`` (:class:`Movement`): trajectory, speed, repetitions, full scale;
- ``esn``: :class:`skinny_mj.controllers.reservoir.ESNConfig` as it is (its sizes come from the
  plant; ``noise_level`` None: the method's default);
- ``method``, the learning method: :class:`Original` or :class:`New` (feedback-error
  learning, with its schedule), :class:`TrueTarget`, or :class:`NoLearning` (the
  feedback controller alone);
- ``forward``: :class:`NoForward` or a :class:`Forward` model (paper A);
- ``test`` (:class:`TestSetup`): the feedback gain, washout and reservoir noise at test;
- ``inputs``: what the inverse model sees (desired + sensed, or sensed only, paper B).

Every setting has a dotted key (``esn.spectral_radius``, ``method.beta``); a type is chosen
by its name (``method=original``, ``actuation=torque``). :meth:`TrainConfig.override` takes
such keys (from the command line, a config file or a study's row);
:meth:`TrainConfig.to_dict` writes them flat, and :meth:`TrainConfig.from_dict` reads
them back, and also reads the flat files of earlier versions (``"method": "new",
"reservoir": 200, ...``, see :data:`LEGACY_KEYS`). The defaults are paper E's
experiment 5.
"""

from __future__ import annotations

import contextlib
import contextvars
import dataclasses
import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

from skinny_mj.controllers import methods
from skinny_mj.controllers.feedback import FeedbackController
from skinny_mj.controllers.fel import Test
from skinny_mj.controllers.loop import INPUTS
from skinny_mj.controllers.methods import PAPER_CYCLES_FOR_BETA
from skinny_mj.controllers.reservoir import ESNConfig
from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant.body import (
    ACTUATIONS,
    MAX_SENSOR_NOISE,
    SIGNALS,
    actuation_of,
    body_name,
    body_of,
    by_dof,
    check_actuation,
    check_signals,
    twin_name,
)
from skinny_mj.training import fits, overrides
from skinny_mj.training.legacy import LEGACY_KEYS, from_legacy, is_legacy

__all__ = ["TrainConfig", "Plant", "Velocity", "Torque", "Movement", "Original", "New",
           "TrueTarget", "NoLearning", "Encoders", "OracleSensing", "NoForward", "Forward",
           "TestSetup", "relative_cost",
           "check_signals", "check_actuation", "METHODS", "SIGNALS",
           "ACTUATIONS", "DEFAULT_NOISE", "PAPER_CYCLES_FOR_BETA", "ARM_LAWS", "LEGACY_KEYS"]

METHODS = ("original", "new", "true-target", "none")
#: Laws of skinny_mj.controllers.torque_arm (inertia-scaled pole placement), by feedback name:
#: three controllers alone, and FEL's teachers "inertia-pd" (M(q) of the controllers'
#: model at the sensed pose) and "const-pd" (one constant M: the nominal body's at home)
ARM_LAWS = {"ct": "ct", "id-pd": "id-pd", "pd-gravity": "pd-g", "inertia-pd": "fel",
            "const-pd": "fel-const"}
#: feedback names of loops of their own: adaptive computed torque
FEEDBACKS = ("pd", "computed-torque", *ARM_LAWS, "adaptive-ct")
#: what the torque controllers' model is (``actuation.model``)
MODELS = ("nominal", "true")
#: how joint velocities are sensed (``actuation.sensing.velocity``)
VELOCITY_SENSING = ("finite-difference", "finite-difference-2", "observer", "oracle")
FORWARD_INPUTS = ("sensed", "chained")
FORWARD_SHARING = ("none", "predictions", "commands")
ARMS = ("right", "left")
RETARGETS = ("angles", "positions")
FULL_SCALES = ("per-joint", "shared")
BACKENDS = ("batch", "env")
#: Reservoir noise the paper chose per method (paper E, Fig. 5).
DEFAULT_NOISE = {"original": 0.03, "new": 0.2, "true-target": 0.2, "none": 0.0}


def _refuse(checks: list[tuple[bool, str]]) -> None:
    methods.check(checks, SkinnyInputError)


def _at_least(value: float, low: float) -> bool:
    return isinstance(value, int | float) and math.isfinite(value) and value >= low


@dataclass(frozen=True)
class Plant:
    """The body (by name, :data:`skinny_mj.plant.body.BODIES`) and its sensors."""

    body: str = "2d"
    signals: str = "cartesian"
    sensor_noise: float = 0.01
    delay: int = 0  # steps by which the internal models' sensed input lags (paper A)
    leading_arm: str | None = None  # paper B: this arm is forced, the ESN drives the other
    backend: str = "batch"  # "batch" (MjData stepped directly) or "env" (dm_control)

    def __post_init__(self) -> None:
        if not isinstance(self.body, str):
            raise SkinnyInputError(f"plant.body is a body's name, got {self.body!r}")
        body_of(self.body)
        check_signals(self.signals)
        _refuse([
            (_at_least(self.sensor_noise, 0) and self.sensor_noise <= MAX_SENSOR_NOISE,
             f"sensor noise must be in [0, {MAX_SENSOR_NOISE:g}], got {self.sensor_noise}"),
            (isinstance(self.delay, int) and self.delay >= 0,
             f"delay must be >= 0 steps, got {self.delay}"),
            (self.leading_arm is None or self.leading_arm in ARMS,
             f"leading arm must be none or one of {ARMS}, got {self.leading_arm!r}"),
            (self.backend in BACKENDS, f"backend must be one of {BACKENDS}, got {self.backend!r}"),
        ])

    @property
    def dof(self) -> int:
        """The body's number of hinges (from its MJCF)."""
        return body_of(self.body).dof


@dataclass(frozen=True)
class Velocity:
    """The velocity servo (the thesis's kinematic plant): no settings of its own."""

    kind: str = "velocity"


@dataclass(frozen=True)
class Encoders:
    """What a robot senses of its joints (:class:`skinny_mj.controllers.sensing.JointSensing`):
    encoder angles with Gaussian noise ``encoder_noise`` (rad; 5e-4 rad ~ 0.03 deg, the
    quantization noise of a 12-bit absolute encoder), velocities by the second-order
    backward difference of the encoder angles at the 50 Hz control rate
    (``velocity="finite-difference-2"``; ``"finite-difference"``: the first-order one,
    which lags by half a step; optionally low-passed at ``velocity_filter_hz``;
    ``"observer"``: an alpha-beta filter on the encoder angles whose prediction is the
    controllers' model of the arm (nominal unless ``actuation.model=true``) stepped under
    the torque commanded, gains ``observer_alpha``, ``observer_beta``; ``"oracle"``: the
    true velocities), and ``delay`` control steps of
    latency (also on the ESN's position inputs)."""

    kind: str = "encoders"
    encoder_noise: float = 5e-4
    velocity: str = "finite-difference-2"
    velocity_filter_hz: float | None = None
    delay: int = 0
    #: the observer's gains: the steady-state alpha-beta (Kalman) gains for a tracking
    #: index of 1; chosen among (1, 1), these and (0.36, 0.08) (index 0.1) on the ESN's
    #: YMCA test error, 2D and 3D, 3 seeds
    observer_alpha: float = 0.75
    observer_beta: float = 0.5

    def __post_init__(self) -> None:
        _refuse([
            (_at_least(self.encoder_noise, 0),
             f"encoder noise must be >= 0 rad, got {self.encoder_noise}"),
            (self.velocity in VELOCITY_SENSING,
             f"velocity must be one of {VELOCITY_SENSING}, got {self.velocity!r}"),
            (self.velocity_filter_hz is None or (_at_least(self.velocity_filter_hz, 0)
                                                 and self.velocity_filter_hz > 0),
             f"velocity filter must be none or > 0 Hz, got {self.velocity_filter_hz}"),
            (isinstance(self.delay, int) and self.delay in (0, 1, 2),
             f"sensing delay must be 0, 1 or 2 steps, got {self.delay}"),
            (_at_least(self.observer_alpha, 0) and 0 < self.observer_alpha <= 1
             and _at_least(self.observer_beta, 0) and 0 < self.observer_beta <= 2,
             "observer gains need 0 < alpha <= 1 and 0 < beta <= 2, got "
             f"{self.observer_alpha}, {self.observer_beta}"),
            (self.velocity != "observer" or self.velocity_filter_hz is None,
             "the observer velocity takes no low-pass (its gains filter it)"),
        ])


@dataclass(frozen=True)
class OracleSensing:
    """The oracle's information: joint angles through the position sensors (their noise
    mapped to the joints), noise-free joint velocities (a perfect tachometer), no delay."""

    kind: str = "oracle"


Sensing = Encoders | OracleSensing


@dataclass(frozen=True)
class Torque:
    """The torque twin: mass, gravity, torque limits, and how it is taught and tested.

    The plant as it is may differ from the nominal body the controllers' model describes
    (``payload_kg``, ``mass_scale``, ``friction_nm``, ``damping_nm_s_rad``: training and
    test plant alike); ``test_*`` change the test plant alone. ``model``: what the
    controllers' M(q) and bias come from, ``"nominal"`` (the nominal twin, payload 0,
    masses x 1, no friction) or ``"true"`` (the plant's own model: an oracle)."""

    kind: str = "torque"
    feedback: str = "pd"  # FEL's teacher; "computed-torque", "ct", ...: a controller alone
    omega: float | None = None  # poles of ARM_LAWS, rad/s (None: the law's default)
    zeta: float = 1.0  # ARM_LAWS' damping ratio
    gravity_feedforward: bool = False  # add qfrc_bias / limit to the command (not learned)
    velocity_inputs: bool = True  # [qd_d(t+1); qd(t)] / v_max as extra inputs
    #: with a sensing delay of d steps, FEL's teacher (an arm law) compares the sensed
    #: state with the desired state of the step it was sensed at, and FEL pairs command(t)
    #: with that teacher's error d steps later, when the arm it moved is sensed (False:
    #: the error of step t + 1, which then describes the arm d steps earlier)
    align_delay: bool = True
    sensing: Sensing = field(default_factory=Encoders)
    model: str = "nominal"  # the controllers' model: "nominal" or "true" (oracle)
    payload_kg: float = 0.0  # point mass at the right hand's CoM (training and test plant)
    mass_scale: float = 1.0  # every arm link's mass and inertia x this (training and test)
    friction_nm: float = 0.0  # unmodelled Coulomb friction of every arm joint, N m
    damping_nm_s_rad: float = 0.0  # unmodelled viscous damping added to every arm joint
    test_payload_kg: float = 0.0  # point mass at the right hand's CoM in the test plant
    test_mass_scale: float = 1.0  # every arm link's mass and inertia x this at test
    test_friction_nm: float = 0.0  # Coulomb friction added to every arm joint at test

    def __post_init__(self) -> None:
        _refuse([
            (self.model in MODELS, f"model must be one of {MODELS}, got {self.model!r}"),
            (_at_least(self.payload_kg, 0), f"payload must be >= 0 kg, got {self.payload_kg}"),
            (_at_least(self.mass_scale, 0) and self.mass_scale > 0,
             f"mass scale must be > 0, got {self.mass_scale}"),
            (_at_least(self.friction_nm, 0) and _at_least(self.test_friction_nm, 0),
             "friction must be >= 0 N m"),
            (_at_least(self.damping_nm_s_rad, 0),
             f"damping must be >= 0 N m s/rad, got {self.damping_nm_s_rad}"),
            (self.feedback in FEEDBACKS, f"feedback must be one of {FEEDBACKS}, "
                                         f"got {self.feedback!r}"),
            (isinstance(self.align_delay, bool),
             f"align_delay must be true or false, got {self.align_delay!r}"),

            (self.omega is None or _at_least(self.omega, 0),
             f"feedback omega must be >= 0 rad/s, got {self.omega}"),
            (_at_least(self.zeta, 0), f"feedback zeta must be >= 0, got {self.zeta}"),
            (_at_least(self.test_payload_kg, 0),
             f"test payload must be >= 0 kg, got {self.test_payload_kg}"),
            (_at_least(self.test_mass_scale, 0) and self.test_mass_scale > 0,
             f"test mass scale must be > 0, got {self.test_mass_scale}"),
        ])


@dataclass(frozen=True)
class Movement:
    """What is imitated, how fast and how often."""

    trajectory: str = "ymca"
    asf: str | None = None  # skeleton of an .amc trajectory
    speed: float = 1.0
    reps: int = 1
    max_speed_from: str | None = None  # movement whose speeds set full scale (None: this)
    full_scale_factor: float = 2.0  # full scale = this x the fastest speed per DOF
    #: "per-joint": each DOF its own full scale; "shared": the fastest DOF's for every DOF
    full_scale: str = "per-joint"
    retarget: str = "angles"  # motion capture: by joint angles, or "positions"

    def __post_init__(self) -> None:
        _refuse([
            (_at_least(self.speed, 0) and 0 < self.speed <= 10,
             f"speed must be in (0, 10], got {self.speed}"),
            (isinstance(self.reps, int) and self.reps >= 1, f"reps must be >= 1, got {self.reps}"),
            (_at_least(self.full_scale_factor, 0) and self.full_scale_factor > 0,
             f"full scale factor must be > 0, got {self.full_scale_factor}"),
            (self.full_scale in FULL_SCALES,
             f"full scale must be one of {FULL_SCALES}, got {self.full_scale!r}"),
            (self.retarget in RETARGETS,
             f"retarget must be one of {RETARGETS}, got {self.retarget!r}"),
        ])


def _input_checked(post_init) -> None:
    """A controllers type's own checks, its refusals as the user's input errors."""
    try:
        post_init()
    except SkinnyInputError:
        raise
    except ValueError as err:
        raise SkinnyInputError(str(err)) from None


@dataclass(frozen=True)
class _FEL(methods.FELMethod):
    """Feedback-error learning's schedule (:class:`skinny_mj.controllers.methods.FELMethod`),
    shared by its two methods, and how the training runs it."""

    u_error_gain: float = 1.0  # scalar on the feedback controller's u_error (unstated)
    #: the feedback controller's damped-least-squares lambda (signal per command units)
    u_error_damping: float = FeedbackController.damping
    #: the readout fit and its settings (``method.fit=NAME``, ``method.fit.<param>=value``;
    #: :mod:`skinny_mj.training.fits`): each cycle alone ("cycle"), lambda chosen per fit
    #: on a validation cycle ("ridge-select"), or remembering earlier cycles
    #: ("forgetting", "rls": ``method.fit.forgetting``, old cycles' weight per cycle)
    fit: fits.FitSettings = fits.FitSettings()

    #: old keys -> (the key they name now, the settings type checking a value the chosen
    #: fit has no use for; old run files list ``method.forgetting`` with every fit)
    ALIASES: ClassVar[dict[str, tuple[str, type]]] = {
        "forgetting": ("fit.forgetting", fits.ForgettingSettings)}

    @property
    def forgetting(self) -> float:
        """``method.fit.forgetting`` under its old name (a fit without it: its default,
        what the old key held)."""
        return getattr(self.fit, "forgetting", fits.ForgettingSettings.forgetting)

    def __post_init__(self) -> None:
        _input_checked(super().__post_init__)  # the schedule's (and β's) own checks
        _refuse([
            (_at_least(self.u_error_gain, 0) and self.u_error_gain > 0,
             f"u_error gain must be > 0, got {self.u_error_gain}"),
            (_at_least(self.u_error_damping, 0),
             f"u_error damping must be >= 0, got {self.u_error_damping}"),
            (isinstance(self.fit, fits.FitSettings) and fits.known(self.fit.kind)
             and isinstance(self.fit, fits.FITS[self.fit.kind].settings),
             fits.refusal(getattr(self.fit, "kind", self.fit))),
        ])


@dataclass(frozen=True)
class Original(_FEL, methods.Original):
    """FEL's original method (:class:`skinny_mj.controllers.methods.Original`): the readout
    fitted to y_ESN + u_error (one learning cycle an epoch unless ``cycles`` says more, as
    paper A)."""


@dataclass(frozen=True)
class New(_FEL, methods.New):
    """FEL's new method (:class:`skinny_mj.controllers.methods.New`, paper E): the target
    blended, β (y_ESN + u_error) + (1 − β) y_ESN, over ``cycles`` learning cycles an epoch
    (None: paper E's Table 1 for its β)."""


@dataclass(frozen=True)
class TrueTarget(methods.TrueTarget):
    """The true-target architecture (:class:`skinny_mj.controllers.methods.TrueTarget`,
    paper D): teacher-forced fits to the analytic commands, ``cycles`` of them blended
    with ``beta`` (β = 1: one fit)."""

    def __post_init__(self) -> None:
        _input_checked(super().__post_init__)


@dataclass(frozen=True)
class NoLearning:
    """Nothing learned: the test is the feedback controller alone (test.gain > 0)."""

    kind: str = "none"


@dataclass(frozen=True)
class NoForward:
    """No forward model."""

    kind: str = "none"


@dataclass(frozen=True)
class Forward:
    """A forward model beside the inverse one (paper A): ``parallel``, ``serial`` or
    ``hybrid``; its position input the (delayed) sensed one or its own ``chained``
    prediction; paper B's per-arm ``sharing`` (None: one model for the body)."""

    KINDS: ClassVar[tuple[str, ...]] = ("parallel", "serial", "hybrid")
    kind: str = "parallel"
    reservoir: int = 100
    input: str = "sensed"
    sharing: str | None = None

    def __post_init__(self) -> None:
        _refuse([
            (self.kind in self.KINDS, f"forward must be one of {self.KINDS}, got {self.kind!r}"),
            (isinstance(self.reservoir, int) and self.reservoir >= 1,
             f"forward reservoir must be >= 1, got {self.reservoir}"),
            (self.input in FORWARD_INPUTS,
             f"forward input must be one of {FORWARD_INPUTS}, got {self.input!r}"),
            (self.sharing is None or self.sharing in FORWARD_SHARING,
             f"forward sharing must be none or one of {FORWARD_SHARING}, got {self.sharing!r}"),
        ])


@dataclass(frozen=True)
class TestSetup(Test):
    """The scored test after training (:class:`skinny_mj.controllers.fel.Test`): K at test
    (0 = the ESN alone, > 0 = the feedback left on), unscored cycles before the scored one
    (papers B, C), reservoir noise during the test (the thesis's toolbox: on)."""

    def __post_init__(self) -> None:
        _input_checked(super().__post_init__)


_CROSS_CHECKS_OFF: contextvars.ContextVar[bool] = contextvars.ContextVar(
    "cross_checks_off", default=False)


@contextlib.contextmanager
def _unchecked() -> Iterator[None]:
    """TrainConfig's cross-field checks off inside (see :meth:`TrainConfig.override`)."""
    token = _CROSS_CHECKS_OFF.set(True)
    try:
        yield
    finally:
        _CROSS_CHECKS_OFF.reset(token)


#: The ESN of a training run: sizes from the plant, noise from the method (paper E, exp. 5).
DEFAULT_ESN = ESNConfig(n_reservoir=200, spectral_radius=0.5, noise_level=None)
Actuation = Velocity | Torque
Method = Original | New | TrueTarget | NoLearning
ForwardModel = NoForward | Forward
FEL_METHODS = (Original, New)


@dataclass(frozen=True)
class TrainConfig:
    """One training run, composed of its parts' configurations (see the module
    docstring). Defaults: paper E experiment 5 (2D, Cartesian, N = 200, spectral radius
    0.5, reservoir noise 0.2, β = 0.1 with 3 learning cycles per epoch, 10 epochs, K 1 → 0
    linearly, sensor noise 0.01)."""

    plant: Plant = field(default_factory=Plant)
    actuation: Actuation = field(default_factory=Velocity)
    movement: Movement = field(default_factory=Movement)
    esn: ESNConfig = DEFAULT_ESN
    method: Method = field(default_factory=New)
    forward: ForwardModel = field(default_factory=NoForward)
    test: TestSetup = field(default_factory=TestSetup)
    inputs: str = "desired+sensed"

    #: old names of renamed fields: ``rule.*`` keys still set ``method.*``, with a warning
    #: (:func:`skinny_mj.training.overrides.canonical`)
    RENAMED: ClassVar[dict[str, str]] = {"rule": "method"}

    def __post_init__(self) -> None:
        if _CROSS_CHECKS_OFF.get():
            return
        fel, torque, fwd = isinstance(self.method, FEL_METHODS), self.torque, self.forward
        sharing = getattr(fwd, "sharing", None)
        _refuse(
            [
                (
                    self.esn.n_inputs is None and self.esn.n_outputs is None,
                    "esn.n_inputs and esn.n_outputs are set by the plant and the inputs",
                ),
                (self.inputs in INPUTS, f"inputs must be one of {INPUTS}, got {self.inputs!r}"),
                (
                    not fel or self.method.fit.kind != "ridge-select"
                    or self.esn.readout == "ridge",
                    "method.fit=ridge-select chooses the ridge lambda of FEL fits on a validation "
                    "cycle: it needs esn.readout=ridge",
                ),  # (its body: the fit's own, skinny_mj.training.fits)
                (
                    not fel or self.actuation.kind in fits.FITS[self.method.fit.kind].bodies,
                    f"method.fit={self.method.fit.kind if fel else ''} runs on actuation="
                    f"{' or '.join(fits.FITS[self.method.fit.kind].bodies) if fel else ''}",
                ),
                (
                    sharing is None
                    or (
                        self.plant.leading_arm is not None
                        and fwd.kind == "parallel"
                        and self.plant.signals == "joint"
                    ),
                    "forward.sharing needs a leading arm, forward=parallel and joint signals",
                ),
                (
                    not isinstance(self.method, TrueTarget)
                    or (
                        isinstance(fwd, NoForward)
                        and self.plant.delay == 0
                        and self.plant.leading_arm is None
                    ),
                    "the true-target architecture takes no forward model, delay or leading arm",
                ),
                (
                    not isinstance(self.method, NoLearning) or self.test.gain > 0,
                    "method=none tests the feedback controller alone: it needs test.gain > 0",
                ),
                (
                    torque is None
                    or torque.feedback in ("pd", "inertia-pd")
                    or isinstance(self.method, NoLearning),
                    f"the {getattr(torque, 'feedback', '')} controller runs alone (method=none); "
                    "FEL's teacher is 'pd' or 'inertia-pd'",
                ),
                (
                    torque is None
                    or torque.feedback != "inertia-pd"
                    or not isinstance(self.method, TrueTarget),
                    "the 'inertia-pd' teacher goes with feedback-error learning or runs alone",
                ),
                (
                    torque is None or not torque.gravity_feedforward or fel,
                    "gravity feed-forward goes with feedback-error learning (original or new)",
                ),
                (
                    torque is None
                    or (
                        isinstance(fwd, NoForward)
                        and self.plant.delay == 0
                        and self.plant.leading_arm is None
                        and self.inputs == "desired+sensed"
                    ),
                    "the torque body runs without a forward model, delay, leading arm or "
                    "sensed-only inputs",
                ),
                (
                    self.plant.backend != "env" or torque is None
                    or getattr(torque.sensing, "velocity", None) != "observer",
                    "the observer velocity (actuation.sensing.velocity=observer) steps the "
                    "controllers' model beside the lockstep plant: use plant.backend=batch",
                ),
                (
                    self.plant.backend != "env"
                    or (self.plant.leading_arm is None and isinstance(fwd, NoForward)),
                    "the dm_control plant (plant.backend=env) runs neither paper B's "
                    "forced arm nor a forward model; use plant.backend=batch",
                ),
            ]
        )
        try:  # the ESN's own checks, with the sizes it will get
            dataclasses.replace(self.esn, n_inputs=1, n_outputs=1, noise_level=self.noise_level)
        except ValueError as err:
            raise SkinnyInputError(f"esn: {err}") from None

    # -- derived settings ---------------------------------------------------------------
    @property
    def torque(self) -> Torque | None:
        """The torque body's settings, None on the velocity servo."""
        return self.actuation if isinstance(self.actuation, Torque) else None

    @property
    def learns_by_fel(self) -> bool:
        return isinstance(self.method, FEL_METHODS)

    @property
    def noise_level(self) -> float:
        """Reservoir noise: ``esn.noise_level``, or by default the method's (paper E Fig. 5)."""
        return DEFAULT_NOISE[self.method.kind] if self.esn.noise_level is None \
            else self.esn.noise_level

    @property
    def uses_velocity_inputs(self) -> bool:
        return self.torque is not None and self.torque.velocity_inputs

    @property
    def learning_cycles(self) -> int:
        """Learning cycles per epoch: the FEL method's (:attr:`skinny_mj.controllers.methods.
        FELMethod.learning_cycles`), 1 for the other methods."""
        return self.method.learning_cycles if isinstance(self.method, FEL_METHODS) else 1

    def esn_config(self, n_inputs: int, n_outputs: int, n_reservoir: int | None = None
                   ) -> ESNConfig:
        """The controllers' ESN config with the sizes and the noise filled in."""
        return dataclasses.replace(
            self.esn, n_inputs=n_inputs, n_outputs=n_outputs, noise_level=self.noise_level,
            n_reservoir=self.esn.n_reservoir if n_reservoir is None else n_reservoir)

    # -- overrides and files ------------------------------------------------------------
    def override(self, changes: Mapping[str, Any] | None = None, /, *, check: bool = True,
                 **kw: Any) -> TrainConfig:
        """This config with dotted keys set (``{"esn.spectral_radius": 0.9}``); keyword
        arguments take ``__`` for the dot (``esn__spectral_radius=0.9``). ``check=False``
        skips the cross-field checks (each part still checks its own settings): a
        probe of which keys the chosen types have, never a config to run."""
        merged = _with_body(self, {**(changes or {}),
                                   **{k.replace("__", "."): v for k, v in kw.items()}})
        if check:
            return overrides.override(self, merged)
        with _unchecked():
            return overrides.override(self, merged)

    def to_dict(self) -> dict[str, Any]:
        """Flat dotted keys (JSON-ready), with the derived ``learning_cycles`` and
        ``noise_level``."""
        return {**overrides.flatten(self), "learning_cycles": self.learning_cycles,
                "noise_level": self.noise_level}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> TrainConfig:
        """From :meth:`to_dict` (derived keys ignored), or from an earlier version's flat
        file (:data:`LEGACY_KEYS`)."""
        d = {k: v for k, v in d.items() if k not in DERIVED}
        if is_legacy(d):
            return from_legacy(d, cls())
        return cls().override(d)


DERIVED = ("learning_cycles", "noise_level")
#: ``plant.dof``: Skinny's body of that many hinges (4: 2d, 8: 3d) for the actuation.
DOF_KEY = "plant.dof"


def _with_body(cfg: TrainConfig, changes: dict[str, Any]) -> dict[str, Any]:
    """``changes`` with the body and the actuation agreeing (see the module docstring):
    ``plant.dof`` becomes the ``plant.body`` of that many hinges; ``plant.body`` alone
    brings the actuation it has (:func:`~skinny_mj.plant.body.actuation_of`); an
    ``actuation`` given picks the body's twin of that actuation
    (:func:`~skinny_mj.plant.body.twin_name`; none is refused)."""
    if DOF_KEY in changes:
        dof = changes[DOF_KEY]
        changes = {k: v for k, v in changes.items() if k != DOF_KEY}
        if "plant.body" in changes:  # the same body twice is no conflict
            named = changes["plant.body"]
            if by_dof(dof, actuation_of(named)) != named:
                raise SkinnyInputError(f"plant.dof={dof} (--dof) is the {by_dof(dof)} body "
                                       f"and plant.body={named} (--body) another: give one "
                                       "of them")
        else:
            kind = changes.get("actuation", cfg.actuation.kind)
            check_actuation(kind)
            changes = {**changes, "plant.body": by_dof(dof)}
            if "actuation" not in changes:
                changes["actuation"] = kind
    named = changes.get("plant.body", cfg.plant.body)
    if "actuation" in changes:
        kind = check_actuation(changes["actuation"])
        if actuation_of(named) != kind:
            changes = {**changes, "plant.body": twin_name(body_name(named), kind)}
    elif "plant.body" in changes:
        actuation = actuation_of(named)
        if actuation != cfg.actuation.kind:
            changes = {**changes, "actuation": actuation}
    return changes


def relative_cost(cfg: TrainConfig) -> float:
    """A training's size, for scheduling sweeps (longest first): its cycles through the
    movement (FEL: epochs x (learning cycles + washout + evaluation); true target: its
    cycles; x reps; + the test), x N / 200 for reservoirs above 200 units."""
    method = cfg.method
    cycles = method.cycles if isinstance(method, TrueTarget) else \
        method.epochs * (cfg.learning_cycles + 2) if isinstance(method, FEL_METHODS) else 0
    return (cycles * cfg.movement.reps + 1 + cfg.test.washout_cycles) \
        * max(1.0, cfg.esn.n_reservoir / 200)
