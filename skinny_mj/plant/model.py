"""Loading a body's MJCF (:class:`skinny_mj.plant.body.Body`): the scene, the robot alone,
a batch of copies, and the check that its MJCF is what the analytic kinematics assumes.

Every body, velocity servo or torque twin, is its own MJCF file. The torque twins'
(``models/skinny/skinny_{2d,3d}_torque.xml``) are made from the velocity bodies' XML by
:func:`torque_spec` with :class:`mujoco.MjSpec` edits (written out by
:mod:`skinny_mj.plant.torque_files`): the velocity actuators become ``<motor>``
actuators of the same names, and the arm becomes a physical one: gravity acts (no
gravity compensation), segment masses, centres of mass and inertias come from de Leva's
(1996) anthropometric table scaled to Skinny's segment lengths
(:func:`segment_inertias`), torques are limited to conservative human strength
(:data:`TORQUE_GEAR_NM`), and the physics step and integrator are the ones
``benchmarks/torque_step_check.py`` measured. The numbers and their sources are in
``models/skinny/README.md``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np

from skinny_mj.errors import SkinnyInputError
from skinny_mj.mjcf import compile_spec, read_model, read_spec
from skinny_mj.plant import body
from skinny_mj.plant.body import Body, BodyLike, body_of

# -- the torque twin: a physical arm (sources and measurements: models/skinny/README.md)
# Peak joint torque (N m): the motor's gear (ctrl in [-1, 1] times gear) and the joint's
# actuatorfrcrange. Conservative adult-male strength: set by the weaker direction of each
# pair (abduction < adduction, flexion < extension, external < internal rotation, elbow
# extension < flexion) and below its peak mean, e.g. shoulder flexion 89.9 N m isometric
# at 0 deg, 68.6 at 45 deg; elbow 0.67 (extension) / 0.78 (flexion) N m per kg body mass
# concentric, 47 / 55 N m at 70 kg. Sources per DOF: models/skinny/README.md.
TORQUE_GEAR_NM = {
    "shoulder_abduction": 50.0,
    "shoulder_flexion": 60.0,
    "shoulder_rotation": 30.0,
    "elbow_flexion": 45.0,
}
# Physics step and integrator, chosen by benchmarks/torque_step_check.py (its table is
# in the model card): the cheapest candidate within 1e-4 rad of a 0.1 ms RK4 reference
# over a 2 s free swing, 1e-3 rad over 1 s of random torques, 1e-3 relative energy drift
# over 5 s undamped, and stable under 2 s of full random torques, on both arms. RK4 at
# 5 ms (4 substeps per 20 ms control step; swing error 6e-8 rad) is; Euler and
# implicitfast are first order (5e-3 rad at 2 ms, and the undamped 3D arm's energy
# grows 60 % at 2 ms, diverges at 4 ms), RK4 at 10 ms misses the random-torque bound
# on the 3D arm (4e-3 rad) and RK4 at 20 ms diverges there.
TORQUE_TIMESTEP_S = 0.005
TORQUE_INTEGRATOR = mujoco.mjtIntegrator.mjINT_RK4
# Passive joint viscosity (N m s/rad), the shared default of skinny_defaults.xml kept:
# between passive tissue damping in arm models (0.05) and the viscosity of intentional
# elbow movement (~8 N m s/rad); a free-swinging forearm's damping ratio is ~0.56. The
# controllers add the active impedance.
TORQUE_JOINT_DAMPING = 0.5
# Rotor inertia (kg m^2): a human joint has none; the 2D arm and the elbows need none.
TORQUE_ARMATURE = 0.0
# ... except the 3D arm's three shoulder hinges (benchmarks/torque_stability_check.py):
# flexion pressed past its soft limit toward 90 deg aligns the abduction and rotation
# axes, M turns singular and RK4 diverges (MuJoCo's BADQACC/BADQVEL) under saturated
# torques at any step (1 ms too); 5e-4 still fails 12-18 of 20 bang-bang runs, 1e-3 none of 40.
# The value is the reflected inertia of a humanoid-arm motor at these torques: Unitree
# G1's 5020 (25 N m), rotor J (0.139, 0.017, 0.169)e-4 kg m^2 through a 16:1 two-stage
# planetary gear, J1 (N1 N2)^2 + J2 N2^2 + J3 = 0.00361 kg m^2.
TORQUE_ARMATURE_3D_SHOULDER = 0.0036
# Joint limits of the torque twin: a critically damped limit constraint with a time
# constant of one 5 ms physics step (MuJoCo's default, 20 ms, let a saturated arm pass
# 0.5-0.6 rad beyond a limit when driven into it from the far end, and 0.9-1.1 rad under
# bang-bang torques; benchmarks/torque_limits_check.py). MuJoCo raises a positive
# time constant below two physics steps to two steps (its "refsafe"), so the limit is
# given in MuJoCo's direct form (-stiffness, -damping) = (-1/tau^2, -2/tau): the same
# constraint as solref (tau, 1), unclamped. One step is the stiffest that stays stable
# with RK4 at 5 ms under full random torques (2.5 ms diverged in 3D).
TORQUE_LIMIT_TIMECONST_S = 0.005
TORQUE_LIMIT_SOLREF = (-1.0 / TORQUE_LIMIT_TIMECONST_S ** 2, -2.0 / TORQUE_LIMIT_TIMECONST_S)
# ... and its impedance (solimp: d0, dmax, width rad, midpoint, power) ramps from 0.3 at
# the limit to MuJoCo's 0.95 over the first 0.05 rad past it (MuJoCo's default: 0.9 to
# 0.95 over 0.001): a learning arm that grazes a limit meets a soft stop, one driven
# into it a stiff one. Stiff from the first touch, the limit's impulses entered FEL's
# targets and the 3D YMCA learned 5x worse (docs/results/dynamic.md). Measured: a joint
# driven into a limit from the far end at full torque (40-80 rad/s) passes it by at most
# 0.09 rad (2D) / 0.13 rad (3D), about one physics step of motion, and pushed on rests
# within 0.03 rad of it.
TORQUE_LIMIT_SOLIMP = (0.3, 0.95, 0.05, 0.5, 2.0)
BODY_MASS_KG = 70.0  # the stated body whose arm the twin is (ICRP reference man)
# de Leva (1996, J Biomech 29:1223, Table 4), males: mass / body mass, CoM distance from
# the proximal end / segment length, radii of gyration / length about the sagittal
# (antero-posterior, y), transverse (medio-lateral, x) and longitudinal (z) axes.
# Segments: shoulder-elbow joint centres, elbow-wrist joint centres, wrist joint centre
# to the tip of the middle finger (Skinny's hand reaches the fingertip).
DE_LEVA_MALE = {
    "upper_arm": (0.0271, 0.5772, 0.285, 0.269, 0.158),
    "forearm": (0.0162, 0.4574, 0.276, 0.265, 0.121),
    "hand": (0.0061, 0.3624, 0.288, 0.235, 0.184),
}
#: The hand's length, m: the wrist's joint centre to the tip of the middle finger (the
#: hand capsule of Skinny's MJCF; the arms' kinematics ends at the wrist).
HAND_LENGTH_M = 0.18


def load_spec(which: BodyLike, scene: bool = True) -> mujoco.MjSpec:
    """The body's scene (``scene=False``: the robot alone) as an editable
    :class:`mujoco.MjSpec`, its MJCF checked first (:func:`check_on_load`)."""
    skinny = body_of(which)
    check_on_load(skinny)
    return read_spec(skinny.path(scene))


def torque_spec(which: BodyLike, scene: bool = True) -> mujoco.MjSpec:
    """The torque twin of a velocity body, made with MjSpec edits of its scene
    (``scene=False``: of the robot alone): every velocity actuator becomes a motor of the
    same name and joint, gear = peak torque (:data:`TORQUE_GEAR_NM`, N m; ctrlrange and
    forcerange [-1, 1], the joint's actuatorfrcrange +-gear), gravity compensation off,
    the arm bodies' inertials from :func:`segment_inertias`, joint damping
    :data:`TORQUE_JOINT_DAMPING` and armature :data:`TORQUE_ARMATURE` (the 3D shoulder
    hinges :data:`TORQUE_ARMATURE_3D_SHOULDER`), :data:`TORQUE_INTEGRATOR` at
    :data:`TORQUE_TIMESTEP_S`. The joints keep their limits (soft MuJoCo constraints).
    What :mod:`skinny_mj.plant.torque_files` writes as the torque bodies' MJCF."""
    velocity = body_of(which)
    if velocity.actuation != "velocity":
        raise SkinnyInputError(f"the torque twin is made from a velocity body; {velocity.name}"
                               f" is driven by {velocity.actuation}")
    spec = load_spec(velocity, scene)
    _make_physical(spec, velocity)
    return spec


@dataclass(frozen=True)
class SegmentInertia:
    """One rigid segment: mass (kg), CoM distance from its proximal joint along the
    segment (m), and principal moments of inertia about the CoM (3,) kg m^2 about the
    body's x (medio-lateral), y (antero-posterior) and z (long) axes."""

    mass_kg: float
    com_m: float
    inertia_kg_m2: tuple[float, float, float]


def segment_lengths_m(which: BodyLike = "2d") -> dict[str, float]:
    """The body's upper arm and forearm (as its MJCF has them) and :data:`HAND_LENGTH_M`,
    m, by segment."""
    upper, fore = body_of(which).arms.lengths_m
    return {"upper_arm": upper, "forearm": fore, "hand": HAND_LENGTH_M}


def segment_inertias(body_mass_kg: float = BODY_MASS_KG, which: BodyLike = "2d"
                     ) -> dict[str, SegmentInertia]:
    """de Leva's male table (:data:`DE_LEVA_MALE`) scaled to the body's segment lengths
    (:func:`segment_lengths_m`): masses are fractions of ``body_mass_kg``, CoM positions
    and radii of gyration fractions of each segment's length. Keys "upper_arm",
    "forearm", "hand"."""
    out, lengths = {}, segment_lengths_m(which)
    for name, (m_frac, com_frac, r_ap, r_ml, r_long) in DE_LEVA_MALE.items():
        length, mass = lengths[name], m_frac * body_mass_kg
        inertia = tuple(mass * (r * length) ** 2 for r in (r_ml, r_ap, r_long))
        out[name] = SegmentInertia(mass, com_frac * length, inertia)
    return out


def forearm_hand_inertia(body_mass_kg: float = BODY_MASS_KG, which: BodyLike = "2d"
                         ) -> SegmentInertia:
    """Forearm and hand as the one rigid body they are (no wrist joint): total mass, CoM
    distance from the elbow, and inertia about the combined CoM (parallel-axis theorem:
    each part's own inertia plus m d^2 about the two axes across the segment)."""
    seg = segment_inertias(body_mass_kg, which)
    fore, hand = seg["forearm"], seg["hand"]
    d_fore = fore.com_m  # from the elbow
    d_hand = segment_lengths_m(which)["forearm"] + hand.com_m
    mass = fore.mass_kg + hand.mass_kg
    com = (fore.mass_kg * d_fore + hand.mass_kg * d_hand) / mass
    shift = fore.mass_kg * (d_fore - com) ** 2 + hand.mass_kg * (d_hand - com) ** 2
    own = np.add(fore.inertia_kg_m2, hand.inertia_kg_m2)
    return SegmentInertia(mass, com, (float(own[0] + shift), float(own[1] + shift),
                                      float(own[2])))


def _make_physical(spec: mujoco.MjSpec, velocity: Body) -> None:
    """Edit Skinny's spec into the torque twin (see the module docstring)."""
    spec.option.timestep = TORQUE_TIMESTEP_S
    spec.option.integrator = TORQUE_INTEGRATOR
    # No solver warm start: warm-started, the constraint solver's iterations at a joint
    # limit depend on every copy of a lockstep batch (1e-13 rad apart after 6 s); cold,
    # each copy is bit for bit one robot alone (tests/test_dynamic.py)
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_WARMSTART)
    for side in body.SIDES:
        for name, seg in segment_inertias(which=velocity).items():
            b = spec.body(f"{side}_{name}")
            b.gravcomp = 0.0
            b.explicitinertial = True  # these numbers, not the capsules' volumes
            b.mass = seg.mass_kg
            b.ipos = [0.0, 0.0, -seg.com_m]  # every segment points down its -z at q = 0
            b.iquat = [1.0, 0.0, 0.0, 0.0]
            b.inertia = list(seg.inertia_kg_m2)
    for name in velocity.dof_names:
        limit = TORQUE_GEAR_NM.get(name.split("_", 1)[1])
        if limit is None:
            raise SkinnyInputError(f"the torque body has no peak torque for {name!r} "
                                   f"(skinny_mj.plant.model.TORQUE_GEAR_NM knows "
                                   f"{', '.join(TORQUE_GEAR_NM)})")
        joint = spec.joint(name)
        joint.damping[0] = TORQUE_JOINT_DAMPING
        joint.armature = TORQUE_ARMATURE_3D_SHOULDER if not velocity.planar \
            and "shoulder" in name else TORQUE_ARMATURE
        joint.solref_limit = list(TORQUE_LIMIT_SOLREF)
        joint.solimp_limit = list(TORQUE_LIMIT_SOLIMP)
        joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_TRUE
        joint.actfrcrange = [-limit, limit]
        act = spec.actuator(name)
        act.set_to_motor()
        act.gear[0] = limit
        act.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.ctrlrange = [-1.0, 1.0]
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE  # actuator units: gain 1
        act.forcerange = [-1.0, 1.0]


def load_model(which: BodyLike) -> mujoco.MjModel:
    """Compile the body's scene (velocity servo or torque twin, as its MJCF says), its
    MJCF checked first (:func:`check_on_load`)."""
    skinny = body_of(which)
    check_on_load(skinny)
    return read_model(skinny.path())


BATCH_PREFIX = "r{}/"  # names of copy r in :func:`load_batch_model`


def load_batch_model(which: BodyLike, copies: int,
                     edit: Callable[[mujoco.MjSpec], None] | None = None) -> mujoco.MjModel:
    """``copies`` independent Skinnies (no scene) in one model, for stepping many runs
    with one ``mj_step``; ``edit`` (optional) changes each copy's spec before it is
    attached (a variant of the body, e.g. :func:`skinny_mj.plant.perturb.lengthen_forearm`).

    Copy r's elements are named ``r{r}/<name>`` and laid out as contiguous blocks in
    copy order (bodies after the world body, joints, dofs, qpos, sites, actuators), so
    ``data.qpos.reshape(copies, -1)`` etc. are per-copy views. Skinny's geoms never
    collide and the copies share nothing, so each copy computes bit for bit what a
    one-robot model computes (``tests/test_plant.py`` checks it).
    """
    skinny = body_of(which)
    if copies < 1:
        raise SkinnyInputError(f"copies must be >= 1, got {copies}")
    parent = mujoco.MjSpec()
    one = load_spec(skinny, scene=False)
    for name in dir(one.option):  # the robot's physics options, field by field
        if not name.startswith("_"):
            setattr(parent.option, name, getattr(one.option, name))
    # jacobian="auto" is dense below nv = 60 (one robot) and sparse from there on (a batch
    # of 8 3D or 15 2D robots), whose constraint solver rounds otherwise at a joint
    # limit: dense, each copy is bit for bit the robot alone whatever the batch size
    if parent.option.jacobian == mujoco.mjtJacobian.mjJAC_AUTO:
        parent.option.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    parent.compiler.degree = one.compiler.degree
    parent.compiler.autolimits = one.compiler.autolimits
    for r in range(copies):
        robot = load_spec(skinny, scene=False)
        if edit is not None:
            edit(robot)
        parent.attach(robot, prefix=BATCH_PREFIX.format(r), frame=parent.worldbody.add_frame())
    return compile_spec(parent, skinny.path(scene=False))


def check_body(which: BodyLike, poses: int = 20, seed: int = 0) -> list[str]:
    """What in a body's MJCF the analytic kinematics cannot take (empty: nothing): its
    arms read afresh (:meth:`~skinny_mj.plant.body.Body.read_arms`: hinges, actuators and
    sites named and ordered as two arms), the left arm's hinge axes the mirror images of
    the right's, and the sites' positions at ``poses`` random poses equal to
    :meth:`~skinny_mj.plant.kinematics.Kinematics.arm_points` (1e-9 m)."""
    skinny = body_of(which)
    try:
        skinny.read_arms()
    except SkinnyInputError as err:
        return [str(err)]
    model = read_model(skinny.path(scene=False))
    problems = []
    for i, joint in enumerate(skinny.arms.joints):
        got = model.joint(f"left_{joint}").axis
        if not np.allclose(got, skinny.joint_axis(i, "left"), atol=1e-12):
            problems.append(f"left_{joint} axis {got}: not the mirror image of right_{joint}'s, "
                            f"{skinny.joint_axis(i, 'left')}")
    if problems:
        return problems
    data = mujoco.MjData(model)
    sites = [model.site(f"{s}_{p}").id for s in body.SIDES for p in ("shoulder", "elbow", "wrist")]
    lo, hi = skinny.joint_ranges().T
    rng = np.random.default_rng(seed)
    for _ in range(poses):
        q = rng.uniform(lo, hi)
        data.qpos[model.jnt_qposadr] = q
        mujoco.mj_kinematics(model, data)
        got = data.site_xpos[sites].reshape(2, 3, 3)
        if not np.allclose(got, skinny.arm_points(q), atol=1e-9):
            problems.append(f"the sites' positions at q = {np.round(q, 3).tolist()} are not "
                            "the analytic kinematics' (a hinge off its body's origin, or a "
                            "site off its joint's centre)")
            break
    return problems


_CHECKED: set[tuple] = set()


def check_on_load(which: BodyLike) -> None:
    """:func:`check_body` of the body's MJCF, once per body and file version: an MJCF
    the analytic kinematics cannot take (an actuator taken out, a hinge renamed) is a
    :class:`SkinnyInputError` naming the file and what is wrong, not a ``KeyError``
    from deep inside the plant."""
    skinny = body_of(which)
    robot, scene = skinny.path(scene=False), skinny.path()
    key = (skinny, *((str(f), f.stat().st_mtime_ns) for f in (robot, scene)))
    if key in _CHECKED:
        return
    skinny.read_arms()  # what it cannot read is refused naming the file (and line)
    problems = check_body(skinny)
    if problems:
        raise SkinnyInputError(f"the {skinny.label} body's MJCF: {'; '.join(problems)}",
                               path=robot)
    _CHECKED.add(key)
