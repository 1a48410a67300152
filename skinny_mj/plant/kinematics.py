"""A body's arms as numbers, read from its MJCF (:class:`skinny_mj.mjcf.Arms`): DOF
names, ranges, the position signals and the analytic forward kinematics and its
Jacobian, pure NumPy. :class:`Kinematics` is what :class:`skinny_mj.plant.body.Body`
computes with; the conventions (frames, mirrored arms) are in that module's docstring.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from skinny_mj.errors import SkinnyInputError

if TYPE_CHECKING:
    from skinny_mj.mjcf import Arms

SIDES = ("right", "left")
_MIRROR = np.diag([-1.0, 1.0, 1.0])
_DOWN = np.array([0.0, 0.0, -1.0])


class Kinematics:
    """The kinematics and signals of two mirrored arms described by :attr:`arms`."""

    name: str

    @property
    def arms(self) -> Arms:
        raise NotImplementedError

    @property
    def dof(self) -> int:
        """The number of hinges of both arms."""
        return 2 * len(self.arms.joints)

    @property
    def actuation(self) -> str:
        """"velocity" (velocity servos) or "torque" (motors), as its MJCF's actuators."""
        return self.arms.actuation

    @property
    def planar(self) -> bool:
        """Every hinge turns in the frontal plane (its axis is y): the Cartesian signals
        are the segments' x and z only."""
        return all(a[0] == 0 and a[2] == 0 for a in self.arms.axes_right)

    @property
    def dof_names(self) -> tuple[str, ...]:
        """Ordered DOF (joint and actuator) names: right arm first, then left."""
        return tuple(f"{side}_{j}" for side in SIDES for j in self.arms.joints)

    def joint_axis(self, joint: int, side: str) -> np.ndarray:
        """Local hinge axis (3,) of the arm's ``joint``-th hinge on arm ``side``."""
        axis = np.asarray(self.arms.axes_right[joint], dtype=float)
        return axis if side == "right" else -_MIRROR @ axis

    def joint_ranges(self) -> np.ndarray:
        """Joint ranges, (n_dof, 2) radians, in :attr:`dof_names` order."""
        return np.array(self.arms.ranges_rad, dtype=float)

    def lengths_m(self) -> np.ndarray:
        """(2,) the upper arm's and the forearm's length (shoulder to elbow, elbow to
        wrist), m."""
        return np.array(self.arms.lengths_m)

    def shoulder_positions(self) -> np.ndarray:
        """World positions (2 arms, 3) of the right and left shoulder joint centres, m."""
        return np.array(self.arms.shoulders_m)

    # -- signals ---------------------------------------------------------------------
    def signal_names(self, signals: str) -> tuple[str, ...]:
        """Names of the position signals: joint angles, or Cartesian components of the
        elbow relative to the shoulder and the wrist relative to the elbow
        (x, z in 2D; x, y, z in 3D), right arm first; then the appended hinges' names."""
        sig = signal_set(signals)
        if sig.base == "joint":
            names = self.dof_names
        else:
            axes = "xz" if self.planar else "xyz"
            names = tuple(f"{side}_{point}_{a}" for side in SIDES
                          for point in ("elbow", "wrist") for a in axes)
        return names + tuple(self.dof_names[i] for i in sig.appended_dofs(self))

    def n_signals(self, signals: str) -> int:
        return len(self.signal_names(signals))

    def elbow_dofs(self) -> np.ndarray:
        """Indices (in :attr:`dof_names` order) of the hinges that move only the forearm,
        right arm first: the extra signals of "cartesian-elbow"."""
        segments = self.arms.segments
        own = [i for i, s in enumerate(segments) if s == "forearm"]
        return np.array([a * len(segments) + i for a in range(2) for i in own])

    def normalize_angles(self, q: np.ndarray) -> np.ndarray:
        """Joint angles (..., n_dof) rad -> normalized (-1 at the lower limit, +1 at the
        upper)."""
        lo, hi = self.joint_ranges().T
        return 2.0 * (np.asarray(q) - lo) / (hi - lo) - 1.0

    def denormalize_angles(self, q_norm: np.ndarray) -> np.ndarray:
        """Inverse of :meth:`normalize_angles`: normalized (..., n_dof) -> radians."""
        lo, hi = self.joint_ranges().T
        return lo + (np.asarray(q_norm) + 1.0) * (hi - lo) / 2.0

    # -- kinematics ------------------------------------------------------------------
    def _arm_frames(self, q_arm: np.ndarray, side: str):
        """World axes of each hinge and the upper-arm / forearm rotations for one arm.

        q_arm: (T, n_arm) radians. Returns axes (T, n_arm, 3), R_upper (T, 3, 3),
        R_forearm (T, 3, 3).
        """
        segments = self.arms.segments
        rot = np.broadcast_to(np.eye(3), (q_arm.shape[0], 3, 3)).copy()
        axes = np.empty((q_arm.shape[0], len(segments), 3))
        r_upper = rot
        for i, segment in enumerate(segments):
            if segment == "forearm" and (i == 0 or segments[i - 1] == "upper_arm"):
                r_upper = rot.copy()
            a = self.joint_axis(i, side)
            axes[:, i] = rot @ a
            rot = rot @ _axis_angle(a, q_arm[:, i])
        return axes, r_upper, rot

    def _check_angles(self, q: np.ndarray) -> int:
        n_dof = self.dof
        if q.shape[-1] != n_dof:
            raise ValueError(f"expected {n_dof} joint angles for the {self.name} body, got "
                             f"{q.shape[-1]}")
        return n_dof

    def segment_vectors(self, q: np.ndarray) -> np.ndarray:
        """Elbow-relative-to-shoulder and wrist-relative-to-elbow vectors in metres.

        q: (..., n_dof) joint angles, rad. Returns (..., 2 arms, 2 segments, 3);
        arms right, left; segments upper arm, forearm.
        """
        q = np.asarray(q, dtype=float)
        n_dof = self._check_angles(q)
        n_arm = n_dof // 2
        upper, fore = self.arms.lengths_m
        q2 = q.reshape(-1, n_dof)
        out = np.empty((q2.shape[0], 2, 2, 3))
        for k, side in enumerate(SIDES):
            _, r_upper, r_fore = self._arm_frames(q2[:, k * n_arm : (k + 1) * n_arm], side)
            out[:, k, 0] = upper * (r_upper @ _DOWN)
            out[:, k, 1] = fore * (r_fore @ _DOWN)
        return out.reshape(q.shape[:-1] + (2, 2, 3))

    def arm_points(self, q: np.ndarray) -> np.ndarray:
        """World positions (..., 2 arms, 3 points: shoulder, elbow, wrist, 3) in metres."""
        seg = self.segment_vectors(q)
        shoulder = np.broadcast_to(self.shoulder_positions(), seg.shape[:-2] + (3,))
        elbow = shoulder + seg[..., 0, :]
        wrist = elbow + seg[..., 1, :]
        return np.stack([shoulder, elbow, wrist], axis=-2)

    def cartesian_components(self) -> list[int]:
        """The components of each segment vector in the Cartesian signals: x, z ([0, 2])
        for a planar body, else x, y, z."""
        return [0, 2] if self.planar else [0, 1, 2]

    def cartesian_signals(self, q: np.ndarray) -> np.ndarray:
        """Normalized Cartesian signals (..., n_signals) in [-1, 1]: each segment vector
        divided by its length, components as in :meth:`signal_names`."""
        seg = self.segment_vectors(q)
        seg = seg / self.lengths_m()[:, None]
        seg = seg[..., self.cartesian_components()]
        return seg.reshape(seg.shape[:-3] + (-1,))

    def position_signals(self, q: np.ndarray, signals: str) -> np.ndarray:
        """Normalized position signals (..., n_signals) for joint angles q (..., n_dof) rad."""
        sig = signal_set(signals)
        base = self.normalize_angles(q) if sig.base == "joint" else self.cartesian_signals(q)
        return sig.extend(base, q, self)

    def signal_jacobian(self, q: np.ndarray, signals: str) -> np.ndarray:
        """d(normalized signal)/d(joint angle), (..., n_signals, n_dof) per radian, for
        q (..., n_dof) rad.

        Joint signals: a constant diagonal 2 / (hi - lo). Cartesian: each column is the
        hinge's world axis crossed with the normalized segment vector it moves.
        """
        q = np.asarray(q, dtype=float)
        n_dof = self._check_angles(q)
        lead = q.shape[:-1]
        q2 = q.reshape(-1, n_dof)
        sig = signal_set(signals)
        if sig.base == "joint":
            lo, hi = self.joint_ranges().T
            jac = np.broadcast_to(np.diag(2.0 / (hi - lo)), lead + (n_dof, n_dof)).copy()
            return sig.extend_jacobian(jac, self)
        comps = self.cartesian_components()
        nc = len(comps)
        n_arm = n_dof // 2
        jac = np.zeros((q2.shape[0], 2 * 2 * nc, n_dof))
        for k, side in enumerate(SIDES):
            qa = q2[:, k * n_arm : (k + 1) * n_arm]
            axes, r_upper, r_fore = self._arm_frames(qa, side)
            upper = r_upper @ _DOWN
            fore = r_fore @ _DOWN
            for i, segment in enumerate(self.arms.segments):
                col = k * n_arm + i
                if segment == "upper_arm":
                    jac[:, k * 2 * nc : k * 2 * nc + nc, col] = \
                        np.cross(axes[:, i], upper)[:, comps]
                jac[:, k * 2 * nc + nc : (k + 1) * 2 * nc, col] = \
                    np.cross(axes[:, i], fore)[:, comps]
        jac = sig.extend_jacobian(jac, self)
        return jac.reshape(lead + jac.shape[1:])



def check_signals(signals: object) -> str:
    """``signals`` if it names a :data:`SIGNAL_SETS` entry, else a :class:`SkinnyInputError`."""
    signal_set(signals)
    return str(signals)


def signal_set(signals: object) -> SignalSet:
    """The :class:`SignalSet` named ``signals``, else a :class:`SkinnyInputError`."""
    if not isinstance(signals, str) or signals not in SIGNAL_SETS:
        raise SkinnyInputError(f"signals must be one of {tuple(SIGNAL_SETS)}, got {signals!r}")
    return SIGNAL_SETS[signals]


@dataclass(frozen=True)
class SignalSet:
    """How a set of position signals is built (an entry of :data:`SIGNAL_SETS`).

    base : "joint" (normalized joint angles) or "cartesian" (segment directions,
        :meth:`Kinematics.cartesian_signals`), which each plant builds its own way. appended :
        body -> indices (:attr:`Kinematics.dof_names` order) of the hinges whose normalized
        angles (and Jacobian rows, 2 / range) follow the base's, or None.
    """

    base: str
    appended: Callable[[Kinematics], np.ndarray] | None = None

    def appended_dofs(self, body: Kinematics) -> np.ndarray:
        return np.zeros(0, int) if self.appended is None else self.appended(body)

    def extend(self, values: np.ndarray, q: np.ndarray, body: Kinematics) -> np.ndarray:
        """(..., n_signals): the base signals ``values`` (..., n_base) with the appended
        hinges' normalized angles of q (..., n_dof) rad after them."""
        if self.appended is None:
            return values
        extra = body.normalize_angles(q)[..., self.appended(body)]
        return np.concatenate([values, extra], axis=-1)

    def extend_jacobian(self, jac: np.ndarray, body: Kinematics) -> np.ndarray:
        """(..., n_signals, n_dof): the base's Jacobian ``jac`` (..., n_base, n_dof) per
        rad with each appended hinge's row, 2 / range, below."""
        if self.appended is None:
            return jac
        idx = self.appended(body)
        lo, hi = body.joint_ranges()[idx].T
        rows = np.zeros((len(idx), jac.shape[-1]))
        rows[np.arange(len(idx)), idx] = 2.0 / (hi - lo)
        return np.concatenate([jac, np.broadcast_to(rows, jac.shape[:-2] + rows.shape)],
                              axis=-2)


#: The signal sets by name; a new one is one entry. "cartesian-elbow": the Cartesian
#: signals, then each arm's forearm hinge angles (normalized as joint signals): the
#: elbow's bend, which the segment directions leave ambiguous where the arm is straight
#: (see :meth:`Kinematics.elbow_dofs`).
SIGNAL_SETS: dict[str, SignalSet] = {
    "joint": SignalSet("joint"),
    "cartesian": SignalSet("cartesian"),
    "cartesian-elbow": SignalSet("cartesian", Kinematics.elbow_dofs),
}
SIGNALS = tuple(SIGNAL_SETS)


def _axis_angle(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) about a unit ``axis`` (3,) by ``angle`` (...) rad."""
    c, s = np.cos(angle)[..., None, None], np.sin(angle)[..., None, None]
    k = np.array(
        [[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]]
    )
    return np.eye(3) + s * k + (1.0 - c) * (k @ k)
