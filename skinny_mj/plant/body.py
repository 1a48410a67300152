"""Skinny's body as numbers: DOF names, joint axes and ranges, segment lengths, and
analytic kinematics. Pure NumPy (no mujoco import): this is the contract that the
MJCF files in ``models/skinny/``, the trajectories and the feedback controller share.
A test checks that MuJoCo's forward kinematics and site Jacobians agree with it.

Frame: z up, Skinny faces -y, so his right arm hangs on the -x side and the frontal
plane is x-z. Every arm rotation is intrinsic (MuJoCo composes a body's hinges in
the order they are declared): R = R(a1, q1) R(a2, q2) ... with axes in the local frame.
The arm hangs straight down at q = 0.

2D (4 DOF), per arm: shoulder abduction theta (0 = arm down, pi/2 = horizontal,
pi = straight up) and elbow flexion phi in the same frontal plane (0 = straight,
positive continues the abduction direction, so with the arm raised the forearm folds
over towards the head, as in the M of YMCA).
3D (8 DOF), per arm: shoulder abduction, shoulder flexion (forward swing about the
abducted arm's x axis), shoulder rotation (about the upper arm's long axis), elbow
flexion. Flexion is the middle of the three shoulder hinges; its range stays well
inside +-90 deg, where the first and third axes would align (gimbal lock).
The left arm is the mirror image of the right across x = 0: its axes are -M a with
M = diag(-1, 1, 1), so equal joint angles give mirror-image poses.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from skinny_mj import plugins
from skinny_mj.errors import SkinnyInputError

SIDES = ("right", "left")
SHOULDER_HEIGHT_M = 1.42
SHOULDER_HALF_WIDTH_M = 0.19
UPPER_ARM_LENGTH_M = 0.30
FOREARM_LENGTH_M = 0.27
HAND_LENGTH_M = 0.18
_MIRROR = np.diag([-1.0, 1.0, 1.0])
_DOWN = np.array([0.0, 0.0, -1.0])


@dataclass(frozen=True)
class JointSpec:
    """One hinge of the right arm; the left arm's twin is derived by mirroring."""

    name: str  # without the side prefix, e.g. "shoulder_abduction"
    segment: str  # "upper_arm" or "forearm": the body the hinge moves
    axis_right: tuple[float, float, float]  # local axis for the right arm
    range_rad: tuple[float, float]


_ABDUCTION = JointSpec("shoulder_abduction", "upper_arm", (0.0, 1.0, 0.0), (0.0, np.pi))
_FLEXION = JointSpec(
    "shoulder_flexion", "upper_arm", (-1.0, 0.0, 0.0), (-np.pi / 4, 5 * np.pi / 12)
)
_ROTATION = JointSpec(
    "shoulder_rotation", "upper_arm", (0.0, 0.0, 1.0), (-np.pi / 2, np.pi / 2)
)
_ELBOW_2D = JointSpec("elbow_flexion", "forearm", (0.0, 1.0, 0.0), (0.0, np.pi))
_ELBOW_3D = JointSpec("elbow_flexion", "forearm", (0.0, 1.0, 0.0), (0.0, 5 * np.pi / 6))

ACTUATIONS = ("velocity", "torque")
#: The control step, s (50 Hz: the thesis's 200 Hz capture, every 4th sample kept).
CONTROL_DT_S = 0.02
#: Largest sensor noise std (normalized units): 10x the signals' whole range [-1, 1] is
#: noise only; far larger finite values overflow to inf in the noise and the errors.
MAX_SENSOR_NOISE = 10.0
#: Entry-point group through which another package adds a body (a :class:`Body`).
BODY_GROUP = "skinny_mj.bodies"


@dataclass(frozen=True)
class Body:
    """A body Skinny-MJ trains on: two mirrored arms with these hinges, and its MJCF.

    ``dof``: the number of joints of both arms, the key a user chooses the body by
    (``--dof``, ``plant.dof``). ``arm_joints``: the right arm's hinges from the shoulder
    out, each moving the upper arm or the forearm (the left arm mirrors them).
    ``planar``: every hinge turns in the frontal plane, so the Cartesian signals are the
    segments' x and z only. ``label``: how a message names it ("2D"). ``folder``: the
    folder of its MJCF (None: Skinny's own, :func:`skinny_mj.plant.model.models_dir`),
    holding ``robot`` (the arms and their actuators; joint, actuator and site names as
    :func:`dof_names` and ``{side}_{shoulder,elbow,wrist}``) and ``scene`` (the robot
    with floor, light and camera). The segment lengths are Skinny's
    (:data:`UPPER_ARM_LENGTH_M`, :data:`FOREARM_LENGTH_M`); a test of the MJCF against
    this spec is :func:`skinny_mj.plant.model.check_body`.
    """

    dof: int
    arm_joints: tuple[JointSpec, ...]
    planar: bool
    label: str
    robot: str
    scene: str
    folder: Path | None = None

    def __post_init__(self) -> None:
        if isinstance(self.dof, bool) or not isinstance(self.dof, int) or \
                self.dof != 2 * len(self.arm_joints):
            raise SkinnyInputError(f"a body's dof is twice its arm's joints "
                                   f"({2 * len(self.arm_joints)}), got {self.dof!r}")
        names = [j.name for j in self.arm_joints]
        if len(set(names)) != len(names):
            raise SkinnyInputError(f"a body's joints need distinct names, got {names}")
        segments = [j.segment for j in self.arm_joints]
        if set(segments) - {"upper_arm", "forearm"} or segments != sorted(
                segments, key=("upper_arm", "forearm").index) or "forearm" not in segments:
            raise SkinnyInputError("a body's hinges move the upper arm first, then the "
                                   f"forearm (at least one), got {segments}")


#: The bodies, by dof: Skinny's 2D and 3D, and any :func:`register_body` added.
BODIES: dict[int, Body] = {
    4: Body(4, (_ABDUCTION, _ELBOW_2D), planar=True, label="2D", robot="skinny_2d.xml",
            scene="scene_2d.xml"),
    8: Body(8, (_ABDUCTION, _FLEXION, _ROTATION, _ELBOW_3D), planar=False, label="3D",
            robot="skinny_3d.xml", scene="scene_3d.xml"),
}


def register_body(new: Body) -> Body:
    """Add a body, chosen from then on by its ``dof`` (``--dof``, ``plant.dof``). The same
    body again is a no-op; another body under a taken dof is a :class:`SkinnyInputError`.

    In this process only: for the command line and a sweep's worker processes, register
    it through the entry-point group :data:`BODY_GROUP` instead (``docs/adding-a-body.md``).
    """
    old = BODIES.get(new.dof)
    if old is not None and old != new:
        raise SkinnyInputError(f"dof {new.dof} is taken by the {old.label} body")
    BODIES[new.dof] = new
    return new


def body_of(dof: object) -> Body:
    """The :class:`Body` chosen by ``dof``; an unknown dof is a :class:`SkinnyInputError`
    naming the known ones."""
    found = _lookup(dof)
    if found is None and not isinstance(dof, bool):  # another package's (read once)
        for _, new in plugins.load_group(BODY_GROUP, Body, "skinny_mj.plant.body.Body"):
            register_body(new)
        found = _lookup(dof)
    if found is None:
        known = " or ".join(f"{d} ({b.label})" for d, b in sorted(BODIES.items()))
        raise SkinnyInputError(f"dof must be {known}, got {dof!r}")
    return found


def _lookup(dof: object) -> Body | None:
    if isinstance(dof, bool):
        return None
    try:
        return BODIES.get(dof)  # type: ignore[call-overload]
    except TypeError:  # unhashable
        return None


def check_dof(dof: object) -> int:
    """``dof`` if it names a body (4 = 2D, 8 = 3D, or one :func:`register_body` added),
    else a :class:`SkinnyInputError` (a ValueError)."""
    return body_of(dof).dof


def check_signals(signals: object) -> str:
    """``signals`` if it names a :data:`SIGNAL_SETS` entry, else a :class:`SkinnyInputError`."""
    signal_set(signals)
    return str(signals)


def signal_set(signals: object) -> SignalSet:
    """The :class:`SignalSet` named ``signals``, else a :class:`SkinnyInputError`."""
    if not isinstance(signals, str) or signals not in SIGNAL_SETS:
        raise SkinnyInputError(f"signals must be one of {tuple(SIGNAL_SETS)}, got {signals!r}")
    return SIGNAL_SETS[signals]


def check_actuation(actuation: object) -> str:
    """``actuation`` if it is "velocity" or "torque", else a :class:`SkinnyInputError`."""
    if actuation not in ACTUATIONS:
        raise SkinnyInputError(f"actuation must be one of {ACTUATIONS}, got {actuation!r}")
    return str(actuation)


_check_dof = check_dof


def joint_axis(spec: JointSpec, side: str) -> np.ndarray:
    """Local hinge axis (3,) of ``spec`` on arm ``side`` ("right" or "left")."""
    axis = np.asarray(spec.axis_right, dtype=float)
    return axis if side == "right" else -_MIRROR @ axis


def dof_names(dof: int) -> tuple[str, ...]:
    """Ordered DOF (joint and actuator) names: right arm first, then left."""
    return tuple(f"{side}_{j.name}" for side in SIDES for j in body_of(dof).arm_joints)


def joint_ranges(dof: int) -> np.ndarray:
    """Joint ranges, (n_dof, 2) radians, in :func:`dof_names` order."""
    specs = body_of(dof).arm_joints
    return np.array([j.range_rad for _ in SIDES for j in specs], dtype=float)


def signal_names(dof: int, signals: str) -> tuple[str, ...]:
    """Names of the position signals: joint angles, or Cartesian components of the
    elbow relative to the shoulder and the wrist relative to the elbow
    (x, z in 2D; x, y, z in 3D), right arm first; then the appended hinges' names."""
    sig = signal_set(signals)
    if sig.base == "joint":
        names = dof_names(dof)
    else:
        axes = "xz" if body_of(dof).planar else "xyz"
        names = tuple(f"{side}_{point}_{a}" for side in SIDES for point in ("elbow", "wrist")
                      for a in axes)
    return names + tuple(dof_names(dof)[i] for i in sig.appended_dofs(dof))


def elbow_dofs(dof: int) -> np.ndarray:
    """Indices (in :func:`dof_names` order) of the hinges that move only the forearm,
    right arm first: the extra signals of "cartesian-elbow"."""
    n_arm = dof // 2
    own = [i for i, j in enumerate(body_of(dof).arm_joints) if j.segment == "forearm"]
    return np.array([a * n_arm + i for a in range(2) for i in own])


@dataclass(frozen=True)
class SignalSet:
    """How a set of position signals is built (an entry of :data:`SIGNAL_SETS`).

    base : "joint" (normalized joint angles) or "cartesian" (segment directions,
        :func:`cartesian_signals`), which each plant builds its own way. appended : dof
        -> indices (:func:`dof_names` order) of the hinges whose normalized angles (and
        Jacobian rows, 2 / range) follow the base's, or None.
    """

    base: str
    appended: Callable[[int], np.ndarray] | None = None

    def appended_dofs(self, dof: int) -> np.ndarray:
        return np.zeros(0, int) if self.appended is None else self.appended(dof)

    def extend(self, values: np.ndarray, q: np.ndarray, dof: int) -> np.ndarray:
        """(..., n_signals): the base signals ``values`` (..., n_base) with the appended
        hinges' normalized angles of q (..., n_dof) rad after them."""
        if self.appended is None:
            return values
        extra = normalize_angles(q, dof)[..., self.appended(dof)]
        return np.concatenate([values, extra], axis=-1)

    def extend_jacobian(self, jac: np.ndarray, dof: int) -> np.ndarray:
        """(..., n_signals, n_dof): the base's Jacobian ``jac`` (..., n_base, n_dof) per
        rad with each appended hinge's row, 2 / range, below."""
        if self.appended is None:
            return jac
        idx = self.appended(dof)
        lo, hi = joint_ranges(dof)[idx].T
        rows = np.zeros((len(idx), jac.shape[-1]))
        rows[np.arange(len(idx)), idx] = 2.0 / (hi - lo)
        return np.concatenate([jac, np.broadcast_to(rows, jac.shape[:-2] + rows.shape)],
                              axis=-2)


#: The signal sets by name; a new one is one entry. "cartesian-elbow": the Cartesian
#: signals, then each arm's forearm hinge angles (normalized as joint signals): the
#: elbow's bend, which the segment directions leave ambiguous where the arm is straight
#: (see :func:`elbow_dofs`).
SIGNAL_SETS: dict[str, SignalSet] = {
    "joint": SignalSet("joint"),
    "cartesian": SignalSet("cartesian"),
    "cartesian-elbow": SignalSet("cartesian", elbow_dofs),
}
SIGNALS = tuple(SIGNAL_SETS)


def n_signals(dof: int, signals: str) -> int:
    return len(signal_names(dof, signals))


def normalize_angles(q: np.ndarray, dof: int) -> np.ndarray:
    """Joint angles (..., n_dof) rad -> normalized (-1 at the lower limit, +1 at the upper)."""
    lo, hi = joint_ranges(dof).T
    return 2.0 * (np.asarray(q) - lo) / (hi - lo) - 1.0


def denormalize_angles(q_norm: np.ndarray, dof: int) -> np.ndarray:
    """Inverse of :func:`normalize_angles`: normalized (..., n_dof) -> radians."""
    lo, hi = joint_ranges(dof).T
    return lo + (np.asarray(q_norm) + 1.0) * (hi - lo) / 2.0


def _axis_angle(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) about a unit ``axis`` (3,) by ``angle`` (...) rad."""
    c, s = np.cos(angle)[..., None, None], np.sin(angle)[..., None, None]
    k = np.array(
        [[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]]
    )
    return np.eye(3) + s * k + (1.0 - c) * (k @ k)


def _arm_frames(q_arm: np.ndarray, dof: int, side: str):
    """World axes of each hinge and the upper-arm / forearm rotations for one arm.

    q_arm: (T, n_arm) radians. Returns axes (T, n_arm, 3), R_upper (T, 3, 3),
    R_forearm (T, 3, 3).
    """
    specs = body_of(dof).arm_joints
    rot = np.broadcast_to(np.eye(3), (q_arm.shape[0], 3, 3)).copy()
    axes = np.empty((q_arm.shape[0], len(specs), 3))
    r_upper = rot
    for i, spec in enumerate(specs):
        if spec.segment == "forearm" and (i == 0 or specs[i - 1].segment == "upper_arm"):
            r_upper = rot.copy()
        a = joint_axis(spec, side)
        axes[:, i] = rot @ a
        rot = rot @ _axis_angle(a, q_arm[:, i])
    return axes, r_upper, rot


def segment_vectors(q: np.ndarray, dof: int) -> np.ndarray:
    """Elbow-relative-to-shoulder and wrist-relative-to-elbow vectors in metres.

    q: (..., n_dof) joint angles, rad. Returns (..., 2 arms, 2 segments, 3);
    arms right, left; segments upper arm, forearm.
    """
    q = np.asarray(q, dtype=float)
    n_arm = len(body_of(dof).arm_joints)
    if q.shape[-1] != 2 * n_arm:
        raise ValueError(f"expected {2 * n_arm} joint angles for dof={dof}, got {q.shape[-1]}")
    q2 = q.reshape(-1, 2 * n_arm)
    out = np.empty((q2.shape[0], 2, 2, 3))
    for k, side in enumerate(SIDES):
        _, r_upper, r_fore = _arm_frames(q2[:, k * n_arm : (k + 1) * n_arm], dof, side)
        out[:, k, 0] = UPPER_ARM_LENGTH_M * (r_upper @ _DOWN)
        out[:, k, 1] = FOREARM_LENGTH_M * (r_fore @ _DOWN)
    return out.reshape(q.shape[:-1] + (2, 2, 3))


def shoulder_positions() -> np.ndarray:
    """World positions (2 arms, 3) of the right and left shoulder joint centres, m."""
    half, height = SHOULDER_HALF_WIDTH_M, SHOULDER_HEIGHT_M
    return np.array([[-half, 0.0, height], [half, 0.0, height]])


def arm_points(q: np.ndarray, dof: int) -> np.ndarray:
    """World positions (..., 2 arms, 3 points: shoulder, elbow, wrist, 3) in metres."""
    seg = segment_vectors(q, dof)
    shoulder = np.broadcast_to(shoulder_positions(), seg.shape[:-2] + (3,))
    elbow = shoulder + seg[..., 0, :]
    wrist = elbow + seg[..., 1, :]
    return np.stack([shoulder, elbow, wrist], axis=-2)


def _cartesian_components(dof: int) -> list[int]:
    return [0, 2] if body_of(dof).planar else [0, 1, 2]


def cartesian_signals(q: np.ndarray, dof: int) -> np.ndarray:
    """Normalized Cartesian signals (..., n_signals) in [-1, 1]: each segment vector
    divided by its length, components as in :func:`signal_names`."""
    seg = segment_vectors(q, dof)
    seg = seg / np.array([UPPER_ARM_LENGTH_M, FOREARM_LENGTH_M])[:, None]
    seg = seg[..., _cartesian_components(dof)]
    return seg.reshape(seg.shape[:-3] + (-1,))


def position_signals(q: np.ndarray, dof: int, signals: str) -> np.ndarray:
    """Normalized position signals (..., n_signals) for joint angles q (..., n_dof) rad."""
    sig = signal_set(signals)
    base = normalize_angles(q, dof) if sig.base == "joint" else cartesian_signals(q, dof)
    return sig.extend(base, q, dof)


def signal_jacobian(q: np.ndarray, dof: int, signals: str) -> np.ndarray:
    """d(normalized signal)/d(joint angle), (..., n_signals, n_dof) per radian, for
    q (..., n_dof) rad.

    Joint signals: a constant diagonal 2 / (hi - lo). Cartesian: each column is the
    hinge's world axis crossed with the normalized segment vector it moves.
    """
    q = np.asarray(q, dtype=float)
    n_dof = _check_dof(dof)
    if q.shape[-1] != n_dof:
        raise ValueError(f"expected {n_dof} joint angles for dof={dof}, got {q.shape[-1]}")
    lead = q.shape[:-1]
    q2 = q.reshape(-1, n_dof)
    sig = signal_set(signals)
    if sig.base == "joint":
        lo, hi = joint_ranges(dof).T
        jac = np.broadcast_to(np.diag(2.0 / (hi - lo)), lead + (n_dof, n_dof)).copy()
        return sig.extend_jacobian(jac, dof)
    comps = _cartesian_components(dof)
    nc = len(comps)
    n_arm = n_dof // 2
    jac = np.zeros((q2.shape[0], 2 * 2 * nc, n_dof))
    for k, side in enumerate(SIDES):
        qa = q2[:, k * n_arm : (k + 1) * n_arm]
        axes, r_upper, r_fore = _arm_frames(qa, dof, side)
        upper = r_upper @ _DOWN
        fore = r_fore @ _DOWN
        for i, spec in enumerate(body_of(dof).arm_joints):
            col = k * n_arm + i
            if spec.segment == "upper_arm":
                jac[:, k * 2 * nc : k * 2 * nc + nc, col] = np.cross(axes[:, i], upper)[:, comps]
            jac[:, k * 2 * nc + nc : (k + 1) * 2 * nc, col] = np.cross(axes[:, i], fore)[:, comps]
    jac = sig.extend_jacobian(jac, dof)
    return jac.reshape(lead + jac.shape[1:])
