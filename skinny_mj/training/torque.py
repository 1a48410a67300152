"""The torque body in the one training path: what ``actuation=torque`` adds.

:class:`skinny_mj.training.actuation.TorqueActuation` (``cfg.actuation`` a
:class:`skinny_mj.training.config.Torque`) supplies these to the training path:

- :func:`hook_for`: the :class:`skinny_mj.controllers.torque_fel.TorqueLoop` of a movement (the
  rollout hook: velocity inputs, the PD teacher, the gravity feed-forward);
- :func:`true_torques`: the inverse model's true target, the torques of
  ``mj_inverse`` along the desired motion (:meth:`skinny_mj.plant.dynamics.Dynamics.
  trajectory_torques_nm`), normalized by the limits (T-1, n_dof);
- :func:`teacher_inputs`: the true-target architecture's extra teacher-forced inputs
  [qd_d(t+1); qd_d(t)] / v_max, as the rollout's [qd_d(t+1); qd(t)] / v_max;
- :func:`perturb` (:func:`skinny_mj.plant.perturb.perturb`): the robustness test plant
  (payload, link masses);
- :func:`controller`: the PD teacher with gains scaled to the limits;
- :func:`hook_for` with an arm law (``actuation.feedback`` in
  :data:`skinny_mj.training.config.ARM_LAWS`):
  an :class:`skinny_mj.controllers.torque_arm_loop.ArmLoop` fed by
  :class:`skinny_mj.plant.dynamics.BatchArmState`, its gains :func:`arm_gains`, the movement
  :func:`desired_motion`; :func:`readout_fitter` (FEL fits that remember) and
  :class:`ShareRecorder` (the feedback share per epoch); :func:`feasibility`.

The feedback teacher (:class:`skinny_mj.controllers.torque_feedback.TorqueFeedbackController`):
gains :meth:`TorqueGains.from_limits` (0.1 rad asks for 50 % of the limit, critically
damped, capped at omega dt = 0.5 with each joint's smallest own inertia over its range,
dt = 20 ms), joint-space error for joint signals, the damped Jacobian otherwise.
Desired velocities are those of the clamped cubic spline that
``trajectory_torques_nm`` differentiates (so the PD's velocity reference and the
true target describe one motion). Velocity inputs and the PD's velocity are the
plant's noise-free joint velocities (sensor noise is on the positions only).
"""

from __future__ import annotations

import functools

import numpy as np

from skinny_mj.controllers.metrics import position_nrmse
from skinny_mj.controllers.sensing import JointSensing
from skinny_mj.controllers.torque_arm import ArmGains, DesiredMotion
from skinny_mj.controllers.torque_arm_loop import ArmLoop
from skinny_mj.controllers.torque_feedback import TorqueFeedbackController, TorqueGains
from skinny_mj.controllers.torque_fel import TorqueLoop
from skinny_mj.controllers.torque_readout import ForgettingReadout, RLSReadout
from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.plant.body import BodyLike, body_of
from skinny_mj.plant.dynamics import BatchArmState, feasibility_lines
from skinny_mj.plant.path_dynamics import torque_dynamics
from skinny_mj.plant.perturb import perturb  # noqa: F401  (re-exported: the robustness test plant)
from skinny_mj.training import adaptive
from skinny_mj.training.config import ARM_LAWS, OracleSensing, Torque, TrainConfig

#: Default pole placement omega (rad/s) per law, zeta 1 (critically damped): computed
#: torque and PD + gravity at 15 rad/s (omega dt = 0.3 at the 20 ms hold), the ID
#: feed-forward's low-gain PD and FEL's teacher at 5 rad/s.
#: Ridge of the remembering readout fits when the ESN's readout is not "ridge".
MEMORY_RIDGE = 1e-2
ARM_OMEGA = {"ct": 15.0, "pd-gravity": 15.0, "id-pd": 5.0, "inertia-pd": 5.0,
             "const-pd": 5.0, "adaptive-ct": 15.0}


@functools.lru_cache(maxsize=8)
def controller(which: BodyLike, signals: str) -> TorqueFeedbackController:
    """The PD teacher of the torque body (see the module docstring)."""
    dyn = torque_dynamics(which)
    inertia_min, _ = dyn.inertia_range()
    gains = TorqueGains.from_limits(dyn.torque_limits_nm(), inertia_min, dt=body.CONTROL_DT_S)
    if signals == "joint":
        lo, hi = body_of(which).joint_ranges().T
        return TorqueFeedbackController(gains, mode="joint",
                                        signal_per_rad=tuple((2.0 / (hi - lo)).tolist()))
    return TorqueFeedbackController(gains)


def torque_limits_nm(which: BodyLike) -> np.ndarray:
    """(n_dof,) peak torques of the body's torque twin, N m (what a normalized command of
    1 means)."""
    return torque_dynamics(which).torque_limits_nm()


def desired_velocities_rad_s(angles: np.ndarray, dt: float) -> np.ndarray:
    """(T, n_dof) joint velocities, rad/s, of the clamped cubic spline through ``angles``
    (T, n_dof) rad (at rest at both ends, as ``trajectory_torques_nm`` assumes)."""
    from scipy.interpolate import CubicSpline  # here: scipy.interpolate takes ~0.25 s

    angles = np.asarray(angles, float)
    t = dt * np.arange(len(angles))
    return CubicSpline(t, angles, axis=0, bc_type="clamped")(t, 1)


def true_torques(which: BodyLike, trajectory) -> np.ndarray:
    """(T-1, n_dof) the zero-order-hold inverse-dynamics torques of ``trajectory``
    divided by the limits (normalized torque; can exceed 1 where the movement asks
    more than the motors have)."""
    dyn = torque_dynamics(which)
    return dyn.normalize(dyn.trajectory_torques_nm(trajectory.angles, trajectory.dt))


def teacher_inputs(cfg: TrainConfig, trajectory, max_speed_rad_s: np.ndarray) -> np.ndarray | None:
    """(T-1, 2 n_dof) [qd_d(t+1); qd_d(t)] / v_max, or None without velocity inputs."""
    if not cfg.uses_velocity_inputs:
        return None
    v = desired_velocities_rad_s(trajectory.angles, trajectory.dt) / max_speed_rad_s
    return np.concatenate([v[1:], v[:-1]], axis=1)


def n_extra_inputs(cfg: TrainConfig) -> int:
    """ESN inputs the torque loop appends (2 n_dof with velocity inputs, else 0)."""
    return 2 * cfg.plant.dof if cfg.uses_velocity_inputs else 0


def desired_motion(which: BodyLike, trajectory, with_id: bool = False) -> DesiredMotion:
    """The :class:`DesiredMotion` of ``trajectory`` for a held-torque loop: the clamped
    cubic spline's states, mid-step samples and (``with_id``) held inverse dynamics."""
    from scipy.interpolate import CubicSpline  # here: scipy.interpolate takes ~0.25 s

    angles, dt = np.asarray(trajectory.angles, float), trajectory.dt
    t = dt * np.arange(len(angles))
    spline = CubicSpline(t, angles, axis=0, bc_type="clamped")
    mid = t[:-1] + 0.5 * dt
    tau = torque_dynamics(which).trajectory_torques_nm(angles, dt) if with_id else None
    return DesiredMotion.from_samples(angles, spline(t, 1), dt, spline(mid), spline(mid, 1),
                                      tau)


def arm_gains(act: Torque) -> ArmGains:
    """The pole placement of ``act.feedback``'s law (:data:`ARM_OMEGA` unless set)."""
    omega = ARM_OMEGA[act.feedback] if act.omega is None else act.omega
    return ArmGains(omega, act.zeta)


#: the stream of a run's encoder noise beside its plant's sensor noise (same plant seed)
SENSING_STREAM = 0x5E45


def sensing_of(act: Torque, plant, dt: float) -> JointSensing | None:
    """The joints' sensing of ``act`` for ``plant``'s R runs (None: the oracle's
    information); run r's encoder noise from ``default_rng([seeds[r], SENSING_STREAM])``."""
    s = act.sensing
    if isinstance(s, OracleSensing):
        return None
    seeds = getattr(plant, "seeds", None) or range(plant.n_runs)
    return JointSensing(s.encoder_noise, s.velocity, s.velocity_filter_hz, s.delay, dt,
                        [np.random.default_rng([int(x), SENSING_STREAM]) for x in seeds],
                        observer_gains=(s.observer_alpha, s.observer_beta))


def sensing_delay(act: Torque | None) -> int:
    """Control steps by which ``act``'s sensing lags (0 for the oracle and the servo)."""
    return getattr(getattr(act, "sensing", None), "delay", 0)


def teacher_lag(cfg: TrainConfig) -> int:
    """Steps by which FEL's teacher compares the sensed state with an earlier desired
    state, and FEL's target pairs a command with a later error: the sensing delay when
    ``actuation.align_delay`` and FEL learns from an arm law's teacher, else 0."""
    act = cfg.torque
    if act is None or not act.align_delay or cfg.method.kind == "none" \
            or act.feedback not in ARM_LAWS:
        return 0
    return sensing_delay(act)


def home_mass(which: BodyLike) -> np.ndarray:
    """(n, n) M of the body's nominal torque twin at its home pose (every angle 0 or its
    range's nearest end: arms hanging, elbows straight), kg m^2: the constant-inertia
    teacher's M."""
    lo, hi = body_of(which).joint_ranges().T
    return torque_dynamics(which).mass_matrix(np.clip(0.0, lo, hi))


def hook_for(cfg: TrainConfig, trajectory, max_speed_rad_s: np.ndarray,
             plant=None, nominal: bool | None = None) -> TorqueLoop | None:
    """The torque loop of ``trajectory`` (None for the velocity servo); the laws of
    :mod:`skinny_mj.controllers.torque_arm` read the arm's state from ``plant`` (a BatchPlant).
    ``nominal``: the controllers use the nominal twin's model (None: :func:`nominal_model`;
    True for a plant that will change while the loop runs)."""
    act, which, signals = cfg.torque, cfg.plant.body, cfg.plant.signals
    if act is None:
        return None
    sensing = None if plant is None else sensing_of(act, plant, trajectory.dt)
    if act.feedback in ARM_LAWS or act.feedback == "adaptive-ct":
        law = ARM_LAWS.get(act.feedback, "ct")
        if plant is None or not hasattr(plant, "model"):
            raise SkinnyInputError(f"feedback {act.feedback!r} needs the lockstep plant "
                                   "(plant.backend=batch)")
        if nominal is None:
            nominal = nominal_model(act)
        state_of = BatchArmState(plant, gravity=law == "pd-g", nominal=nominal,
                                 sensing=sensing,
                                 constant_mass=home_mass(which) if law == "fel-const" else None)
        common = dict(velocity_inputs=act.velocity_inputs,
                      gravity_feedforward=act.gravity_feedforward, law=law,
                      gains=arm_gains(act),
                      motion=desired_motion(which, trajectory, law == "id-pd"),
                      state_of=state_of, dt=trajectory.dt, sensing=sensing,
                      predict=_predictor(sensing, state_of))
        if act.feedback != "adaptive-ct":
            common["lag"] = teacher_lag(cfg)
        args = (controller(which, signals),
                desired_velocities_rad_s(trajectory.angles, trajectory.dt),
                np.asarray(max_speed_rad_s, float))
        if act.feedback == "adaptive-ct":
            return adaptive.loop(which, *args, **common)
        return ArmLoop(*args, **common)
    ff = true_torques(which, trajectory) if act.feedback == "computed-torque" else None
    predict = None
    if sensing is not None and sensing.needs_prediction:
        model = BatchArmState(plant, nominal=nominal_model(act) if nominal is None
                              else nominal, sensing=sensing)
        predict = model.predict
    return TorqueLoop(controller(which, signals),
                      desired_velocities_rad_s(trajectory.angles, trajectory.dt),
                      np.asarray(max_speed_rad_s, float),
                      velocity_inputs=act.velocity_inputs,
                      gravity_feedforward=act.gravity_feedforward, inverse_dynamics=ff,
                      sensing=sensing, predict=predict)


def _predictor(sensing: JointSensing | None, state: BatchArmState):
    """The model's one-step prediction the sensing's observer needs (None: none)."""
    return state.predict if sensing is not None and sensing.needs_prediction else None


def nominal_model(act: Torque) -> bool:
    """Do the controllers of ``act`` use the nominal twin's model rather than the plant's
    own? (With ``model="nominal"``, whenever the plant or its test differs from the
    nominal twin; on an unchanged plant the two give the same numbers.)"""
    return act.model == "nominal" and (perturbed(act) or plant_changed(act))


def plant_changed(act: Torque) -> bool:
    """Does the plant as it is (training and test) differ from the nominal twin?"""
    return (act.payload_kg, act.mass_scale, act.friction_nm, act.damping_nm_s_rad) \
        != (0.0, 1.0, 0.0, 0.0)


def perturbed(act: Torque) -> bool:
    """Does the test plant of ``act`` differ from the training plant?"""
    return act.test_payload_kg != 0 or act.test_mass_scale != 1 or act.test_friction_nm != 0


def change_plant(act: Torque, plant, test: bool) -> None:
    """The plant as it is (``act.payload_kg`` ...), and at test (``test``) the test
    plant's changes on top (:func:`skinny_mj.plant.perturb.perturb`)."""
    perturb(plant, act.payload_kg, act.mass_scale, act.friction_nm, act.damping_nm_s_rad)
    if test:
        perturb(plant, act.test_payload_kg, act.test_mass_scale, act.test_friction_nm)


def test_torques(hook: TorqueLoop, rollout, plant, r: int) -> dict:
    """Run r's torque figures of the test cycle that ``hook`` saw last.

    Returns ``{"metrics": {...}, "series": {...}}``: metrics (JSON-ready) as
    :meth:`TorqueLoop.metrics` plus ``warnings`` (MuJoCo ``data.warning`` counts of the
    test plant, summed over mjtWarning and over its lockstep runs, which share one
    MjData) and ``within_limits`` (commanded and applied |torque| <= limit, 1e-9
    slack) and ``limit_overshoot_rad`` (the largest joint angle past its range over the
    test cycle, rad; 0 inside the ranges); series (for recordings): ``commanded_nm``
    (T-1, n_dof) = command x limit,
    ``applied_nm`` (T-1, n_dof) ``actuator_force``, ``gravity_nm`` (T, n_dof) the bias
    torque ``qfrc_bias`` of each state, ``limit_nm`` (n_dof,).
    """
    limit = hook.controller.gains.limit
    figures = hook.metrics(rollout.commands, plant.dt)
    metrics = {k: float(v[r]) for k, v in figures.items()}
    metrics["warnings"] = int(plant.warning_count())
    metrics["within_limits"] = bool(max(metrics["max_commanded_ratio"],
                                        metrics["max_applied_ratio"]) <= 1 + 1e-9)
    metrics["limit_overshoot_rad"] = limit_overshoot_rad(rollout.angles[r], plant.body)
    series = {"commanded_nm": rollout.commands[r] * limit,
              "applied_nm": hook.applied_nm[:, r].copy(),
              "gravity_nm": hook.bias_nm[:, r].copy(), "limit_nm": limit.copy()}
    return {"metrics": metrics, "series": series}


def limit_overshoot_rad(angles: np.ndarray, which: BodyLike) -> float:
    """The largest joint angle past its range in ``angles`` (T, >= n_dof) rad, the body
    ``which``'s, in rad (0
    when every angle stays within :func:`skinny_mj.plant.body.joint_ranges`)."""
    return float(_overshoot_per_run(np.asarray(angles)[None], which)[0])


def _overshoot_per_run(angles: np.ndarray, which: BodyLike) -> np.ndarray:
    """(R,) each run's largest joint angle past its range in ``angles`` (R, T, >= n_dof)."""
    lo, hi = body_of(which).joint_ranges().T
    q = angles[..., :len(lo)]
    return np.maximum(np.maximum(lo - q, q - hi).max(axis=(1, 2)), 0.0)


def train_warnings(run) -> int | None:
    """MuJoCo warnings of ``run``'s training plant (None if it never built one)."""
    plant = run.__dict__.get("plant")  # the cached property, if it was ever used
    return None if plant is None or not hasattr(plant, "warning_count") \
        else int(plant.warning_count())


def feasibility(which: BodyLike, trajectory) -> dict[str, np.ndarray]:
    """:meth:`skinny_mj.plant.dynamics.Dynamics.feasibility` of ``trajectory`` on the torque
    twin."""
    return torque_dynamics(which).feasibility(trajectory.angles, trajectory.dt)


def feasibility_report(which: BodyLike, trajectory) -> list[str]:
    """The feasibility of ``trajectory`` as text lines (``skinny trajectory show
    --actuation torque``)."""
    return feasibility_lines(feasibility(which, trajectory), list(body_of(which).dof_names))


def readout_fitter(cfg: TrainConfig, esn, steps: int):
    """FEL's readout fit for ``method.fit`` (None: each cycle alone, ``esn.fit``): the
    normal equations with forgetting, or RLS, remembering ``method.fit.forgetting`` of the
    statistics per learning cycle of ``steps`` samples; ridge ``esn.ridge_lambda`` with a
    ridge readout, else :data:`MEMORY_RIDGE`."""
    fit = cfg.method.fit
    ridge = cfg.esn.ridge_lambda if cfg.esn.readout == "ridge" else MEMORY_RIDGE
    if fit.kind == "forgetting":
        return ForgettingReadout(esn, fit.forgetting, ridge)
    if fit.kind == "rls":
        return RLSReadout(esn, steps, fit.forgetting, ridge)
    return None


class ShareRecorder:
    """FEL's ``observe`` callback: per epoch, on its evaluation cycle (the ESN with the
    epoch's K), the feedback share mean |K u_fb| / mean |u| of the command and the
    teacher's error signal mean |u_fb| / mean |u| (each (R, E)); and over every cycle of
    the training, each run's largest joint angle past its range (``limit_overshoot_rad``
    (R,), rad: 0 for a run that never touched a joint limit)."""

    def __init__(self, gains: np.ndarray, n_runs: int, cycles: int, which: BodyLike):
        self.gains, self.eval_cycle, self.body = np.asarray(gains, float), cycles + 1, which
        self.share = np.full((n_runs, len(gains)), np.nan)
        self.error_signal = np.full((n_runs, len(gains)), np.nan)
        self.limit_overshoot_rad = np.zeros(n_runs)

    def __call__(self, epoch: int, cycle: int, ro, y_used) -> None:
        np.maximum(self.limit_overshoot_rad, _overshoot_per_run(ro.angles, self.body),
                   out=self.limit_overshoot_rad)
        if cycle != self.eval_cycle:
            return
        u = np.abs(ro.commands).mean(axis=(1, 2))
        fb = np.abs(ro.u_error[:, :-1]).mean(axis=(1, 2))
        self.error_signal[:, epoch] = fb / np.maximum(u, 1e-12)
        self.share[:, epoch] = self.gains[epoch] * self.error_signal[:, epoch]

    def metrics(self, r: int) -> dict:
        """Run r's figures (JSON-ready): ``feedback_share`` and ``error_signal_share`` per
        epoch, ``limit_overshoot_rad``."""
        return {"feedback_share": [float(v) for v in self.share[r]],
                "error_signal_share": [float(v) for v in self.error_signal[r]],
                "limit_overshoot_rad": float(self.limit_overshoot_rad[r])}


def joint_nrmse(outcome, label: str = "") -> float:
    """Test joint-angle NRMSE (each angle normalized to [-1, 1] over its range) of a
    :class:`skinny_mj.training.result.RunResult` against its movement's angles: its
    standard test (``label`` ""), or its test ``label``."""
    skinny = body_of(outcome.config.plant.body)
    test = outcome.tests[label]
    angles = test.rollout.angles[:, :, :skinny.dof]
    return float(position_nrmse(skinny.normalize_angles(angles),
                                skinny.normalize_angles(test.trajectory.angles))[0])
