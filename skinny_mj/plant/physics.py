"""Skinny's physics: named queries on a MuJoCo model of ``models/skinny``.

:class:`Layout` reads joint angles, position signals and their Jacobians from a raw
``(MjModel, MjData)`` pair by name; :class:`SkinnyPhysics` (the dm_control ``Physics``)
and :class:`skinny_mj.plant.adapters.BatchPlant` both use it, so the two paths compute the
same numbers with the same operations. :func:`servo_ctrl` turns a normalized
velocity command into the velocity actuators' ctrl (rad/s), clipped so the joint
stays inside its range.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

import mujoco
import numpy as np
from dm_control import mujoco as dm_mujoco

from skinny_mj.plant import body
from skinny_mj.plant.body import Body, BodyLike, body_of
from skinny_mj.plant.model import load_model

# A command never targets a joint closer than this to its range limit (rad): MuJoCo's
# limit constraint stays inactive, so the stiff servo never gets kicked off a limit.
LIMIT_MARGIN_RAD = 1e-3
_POINTS = ("shoulder", "elbow", "wrist")


def servo_ctrl(
    command: np.ndarray,
    q: np.ndarray,
    max_speed_rad_s: np.ndarray,
    range_rad: np.ndarray,
    dt: float,
    margin_rad: float = LIMIT_MARGIN_RAD,
) -> np.ndarray:
    """Velocity ctrl (rad/s) for a normalized command, clipped at the joint limits.

    Parameters
    ----------
    command : (..., n_dof) normalized velocity command; clipped to [-1, 1].
    q : (..., n_dof) current joint angles, rad.
    max_speed_rad_s : (n_dof,) full-scale speed, rad/s.
    range_rad : (n_dof, 2) joint ranges, rad.
    dt : control step, s.
    margin_rad : the commanded target q + ctrl * dt stays this far inside the range;
        the excess of a command is dropped (no wind-up).

    Returns
    -------
    (..., n_dof) joint velocity command, rad/s.
    """
    return servo_velocity(command, q, max_speed_rad_s, *servo_targets(range_rad, margin_rad),
                          dt)


def servo_targets(range_rad: np.ndarray, margin_rad: float = LIMIT_MARGIN_RAD
                  ) -> tuple[np.ndarray, np.ndarray]:
    """The lowest and highest angle (n_dof,) rad a servo command may target: each joint's
    range less ``margin_rad`` at both ends (:func:`servo_ctrl`)."""
    return range_rad[:, 0] + margin_rad, range_rad[:, 1] - margin_rad


def servo_velocity(command: np.ndarray, q: np.ndarray, max_speed_rad_s: np.ndarray,
                   low_rad: np.ndarray, high_rad: np.ndarray, dt: float) -> np.ndarray:
    """:func:`servo_ctrl` with the targets' bounds (:func:`servo_targets`) given."""
    vel = np.maximum(np.asarray(command, float), -1.0)  # clip to [-1, 1], in place
    np.minimum(vel, 1.0, out=vel)
    vel *= max_speed_rad_s
    np.maximum(vel, (low_rad - q) / dt, out=vel)
    return np.minimum(vel, (high_rad - q) / dt, out=vel)


def segment_signals(points: np.ndarray, lengths: np.ndarray, comps) -> np.ndarray:
    """(R, 4 * n_comps) Cartesian signals: the ``comps`` components of each segment's unit
    direction (shoulder to elbow, elbow to wrist, arm-major), from ``points`` (R, 2 arms,
    3, 3). :class:`Layout` and :class:`skinny_mj.plant.adapters.BatchPlant` both call it."""
    seg = (points[:, :, 1:] - points[:, :, :-1])[..., comps]  # (R, arm, segment, comp)
    return (seg / lengths.reshape(2, 1)).reshape(points.shape[0], -1)


def segment_jacobian(
    axes: np.ndarray, points: np.ndarray, pairs: tuple[np.ndarray, np.ndarray],
    lengths: np.ndarray, comps: list[int],
) -> np.ndarray:
    """d(Cartesian signal)/d(joint angle), per rad, for R runs at once.

    A segment's signals are the components of its unit direction e = v / L,
    v = p_b - p_a (shoulder to elbow, elbow to wrist). A hinge upstream of p_a turns v
    about its axis: d e / d q = axis x e; a hinge between p_a and p_b turns p_b about
    an axis through p_b itself: 0. So this is ``mj_jacSite(b) - mj_jacSite(a)`` over L
    up to rounding (~1e-16), at a fraction of its cost. It is :func:`segment_jacobian_of`
    on gathered axes and points, which :class:`Layout` (the dm_control path) and
    :class:`skinny_mj.plant.adapters.BatchPlant` call: all get the same bits.

    Parameters
    ----------
    axes : (R, n_dof, 3) world joint axes (``cdof``'s angular part), in DOF order.
    points : (R, 2 arms, 3, 3) shoulder, elbow, wrist positions, m.
    pairs : (segment indices, DOF indices) of the (segment, DOF) pairs where the DOF
        turns the segment (segments arm-major: upper arm, forearm).
    lengths : (4,) segment lengths, m.
    comps : components of each segment in the signals ([0, 2]: x, z in 2D).

    Returns
    -------
    (R, 4 * len(comps), n_dof), rows in :meth:`Body.signal_names` order.
    """
    n, n_dof = axes.shape[0], axes.shape[1]
    jacobian = _identity_jacobian(tuple(comps), pairs[0].tobytes(), pairs[1].tobytes(),
                                  np.asarray(lengths, float).tobytes(), n_dof)
    return jacobian(axes.reshape(n, -1), points.reshape(n, -1))


@functools.lru_cache(maxsize=32)
def _identity_jacobian(comps: tuple[int, ...], seg: bytes, dof: bytes, lengths: bytes,
                       n_dof: int) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    pairs = (np.frombuffer(seg, np.intp), np.frombuffer(dof, np.intp))
    return segment_jacobian_of(pairs, np.frombuffer(lengths), list(comps), np.arange(n_dof),
                               np.arange(6), axis_columns=3)


def segment_jacobian_of(
    pairs: tuple[np.ndarray, np.ndarray], lengths: np.ndarray, comps: list[int],
    dof_adr: np.ndarray, site_ids: np.ndarray, axis_columns: int = 6,
) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """:func:`segment_jacobian` built once for a model's indices: a callable of ``cdof``
    (R, nv * ``axis_columns``) and ``site_xpos`` (R, n_sites * 3), each robot's rows of
    ``MjData`` flattened, that reads the joint axes (the first 3 columns) at ``dof_adr``
    (n_dof,) and the points at ``site_ids`` (2 arms, 3 points) itself. Per call, only the
    turning pairs' components i then j of each signal component k (i = k + 1, j = k + 2,
    mod 3) are gathered, (R, P, 2 comp), each once and by ``take``: on tiny arrays NumPy
    pays per call and per innermost run."""
    seg, dof = (np.asarray(i, np.intp) for i in pairs)
    k, n_dof = np.asarray(comps), len(dof_adr)
    c = len(k)
    ij = np.concatenate([(k + 1) % 3, (k + 2) % 3])[None, :]
    points = np.asarray(site_ids).reshape(2, 3)
    start = (points[:, :-1].reshape(-1)[seg][:, None] * 3 + ij).reshape(-1)  # arm-major
    end = (points[:, 1:].reshape(-1)[seg][:, None] * 3 + ij).reshape(-1)
    axis = (np.asarray(dof_adr)[dof][:, None] * axis_columns + ij).reshape(-1)
    length = np.repeat(np.asarray(lengths, float)[seg], 2 * c)
    flat = ((seg[:, None] * c + np.arange(c)) * n_dof + dof[:, None]).reshape(-1)
    shape = (-1, len(seg), 2 * c)

    def jacobian(cdof: np.ndarray, sites: np.ndarray) -> np.ndarray:
        a = cdof.take(axis, axis=1).reshape(shape)
        e = ((sites.take(end, axis=1) - sites.take(start, axis=1)) / length).reshape(shape)
        # mju_cross, every component at once: (a x e)_k = a_i e_j - a_j e_i, (R, P, comp)
        cross = (a[..., :c] * e[..., c:] - a[..., c:] * e[..., :c]).reshape(len(a), -1)
        out = np.zeros((len(a), 4 * c, n_dof))  # each (pair, comp) to its (segment, comp, DOF)
        out.reshape(len(a), -1)[:, flat] = cross
        return out

    return jacobian


def _segment_pairs(model: mujoco.MjModel, site_ids: np.ndarray,
                   dof_adr: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(segment indices, DOF indices) of the pairs where a DOF is on the kinematic chain
    of the segment's first site (the chain ``mj_jac`` walks): the DOFs that turn it."""
    starts = site_ids[:, :2].reshape(-1)  # shoulder, elbow of each arm
    turns = np.zeros((starts.size, model.nv), bool)
    for k, site in enumerate(starts):
        b = int(model.site_bodyid[site])
        while b and not model.body_dofnum[b]:
            b = int(model.body_parentid[b])
        if b:
            i = int(model.body_dofadr[b] + model.body_dofnum[b] - 1)
            while i >= 0:
                turns[k, i] = True
                i = int(model.dof_parentid[i])
    return np.nonzero(turns[:, dof_adr])


class Layout:
    """Name-resolved indices of a body's joints, actuators and sites in one MjModel.

    Parameters
    ----------
    model : a compiled model of ``skinny`` (its scene or robot).
    skinny : the :class:`Body` it is.
    """

    def __init__(self, model: mujoco.MjModel, skinny: Body):
        self.body = skinny
        self.dof = skinny.dof
        names = skinny.dof_names
        jnt = [model.joint(n).id for n in names]
        self.qpos_adr = np.array([model.jnt_qposadr[j] for j in jnt])
        self.dof_adr = np.array([model.jnt_dofadr[j] for j in jnt])
        self.actuator_ids = np.array([model.actuator(n).id for n in names])
        # site ids (2 arms, 3 points: shoulder, elbow, wrist)
        self.site_ids = np.array(
            [[model.site(f"{s}_{p}").id for p in _POINTS] for s in body.SIDES]
        )
        self.range_rad = model.jnt_range[jnt].copy()
        self.arm_lengths = skinny.lengths_m()
        self.components = skinny.cartesian_components()
        self.segment_pairs = _segment_pairs(model, self.site_ids, self.dof_adr)
        self.segment_lengths = np.tile(self.arm_lengths, 2)
        self._jacp = np.zeros((3, model.nv))

    def joint_angles(self, data: mujoco.MjData) -> np.ndarray:
        """(n_dof,) joint angles, rad, in :attr:`Body.dof_names` order."""
        return data.qpos[self.qpos_adr].copy()

    def set_joint_angles(self, data: mujoco.MjData, q: np.ndarray) -> None:
        """Write (n_dof,) angles (rad) to qpos and zero the joint velocities."""
        data.qpos[self.qpos_adr] = q
        data.qvel[self.dof_adr] = 0.0

    def segment_vectors(self, data: mujoco.MjData) -> np.ndarray:
        """(2 arms, 2 segments, 3) elbow-shoulder and wrist-elbow vectors, m (world frame)."""
        pts = data.site_xpos[self.site_ids]  # (2, 3, 3)
        return pts[:, 1:] - pts[:, :-1]

    def position_signals(self, data: mujoco.MjData, signals: str) -> np.ndarray:
        """(n_signals,) normalized noise-free signals (see :meth:`Body.signal_names`)."""
        sig, q = body.signal_set(signals), self.joint_angles(data)
        if sig.base == "joint":
            return sig.extend(self.body.normalize_angles(q), q, self.body)
        out = segment_signals(data.site_xpos[self.site_ids][None], self.arm_lengths,
                              self.components)[0]
        return sig.extend(out, q, self.body)

    def site_jacobian(self, model: mujoco.MjModel, data: mujoco.MjData, site_id: int):
        """(3, nv) translational Jacobian of a site, m/rad (``mj_jacSite``)."""
        jacp = np.zeros((3, model.nv))
        mujoco.mj_jacSite(model, data, jacp, None, int(site_id))
        return jacp

    def signal_jacobian(
        self, model: mujoco.MjModel, data: mujoco.MjData, signals: str
    ) -> np.ndarray:
        """(n_signals, n_dof) d(normalized signal)/d(joint angle), per rad."""
        sig = body.signal_set(signals)
        if sig.base == "joint":
            lo, hi = self.range_rad.T
            return sig.extend_jacobian(np.diag(2.0 / (hi - lo)), self.body)
        axes = data.cdof[self.dof_adr, :3][None]
        points = data.site_xpos[self.site_ids][None]
        jac = segment_jacobian(axes, points, self.segment_pairs, self.segment_lengths,
                               self.components)[0]
        return sig.extend_jacobian(jac, self.body)


class SkinnyPhysics(dm_mujoco.Physics):
    """dm_control Physics for Skinny with named queries (angles in rad, lengths in m)."""

    @classmethod
    def load(cls, which: BodyLike = "2d") -> SkinnyPhysics:
        """The body's scene (see :func:`skinny_mj.plant.model.load_model`) as a Physics."""
        from dm_control.mujoco import wrapper

        physics = cls.from_model(wrapper.MjModel(load_model(which)))
        physics.skinny_body = body_of(which)
        return physics

    @property
    def layout(self) -> Layout:
        """Name-resolved indices, built on first use."""
        layout = getattr(self, "_skinny_layout", None)
        if layout is None:
            if getattr(self, "skinny_body", None) is None:
                raise AttributeError("a SkinnyPhysics knows its body when made by "
                                     "SkinnyPhysics.load(body)")
            layout = Layout(self.model.ptr, self.skinny_body)
            self._skinny_layout = layout
        return layout

    @property
    def dof(self) -> int:
        """The body's number of hinges."""
        return self.layout.dof

    def joint_angles(self) -> np.ndarray:
        """(n_dof,) joint angles, rad, in :attr:`Body.dof_names` order."""
        return self.layout.joint_angles(self.data.ptr)

    def joint_velocities(self) -> np.ndarray:
        """(n_dof,) joint velocities, rad/s."""
        return self.data.qvel[self.layout.dof_adr].copy()

    def set_joint_angles(self, q: np.ndarray) -> None:
        """Put the arms in pose q (n_dof,) rad at rest and recompute kinematics."""
        self.layout.set_joint_angles(self.data.ptr, np.asarray(q, dtype=float))
        self.forward()

    def segment_vectors(self) -> np.ndarray:
        """(2 arms, 2 segments, 3) elbow-shoulder and wrist-elbow vectors, m."""
        return self.layout.segment_vectors(self.data.ptr)

    def position_signals(self, signals: str) -> np.ndarray:
        """(n_signals,) normalized noise-free position signals (one of ``body.SIGNALS``)."""
        return self.layout.position_signals(self.data.ptr, signals)

    def site_jacobian(self, name: str) -> np.ndarray:
        """(3, nv) translational Jacobian of site ``name`` (e.g. "right_wrist"), m/rad."""
        return self.layout.site_jacobian(self.model.ptr, self.data.ptr, self.model.site(name).id)

    def signal_jacobian(self, signals: str) -> np.ndarray:
        """(n_signals, n_dof) d(normalized signal)/d(joint angle), per rad (see
        :func:`segment_jacobian`)."""
        return self.layout.signal_jacobian(self.model.ptr, self.data.ptr, signals)
