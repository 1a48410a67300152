"""Where Skinny's MJCF files live and how to load them (velocity servo or torque twin).

The XML in ``models/skinny/`` is the single body description; it ships inside the wheel
as the package data ``skinny_mj.models``. The torque twin is
made from the same XML with :class:`mujoco.MjSpec` (:func:`load_spec`): the velocity
actuators become ``<motor>`` actuators of the same names, and the arm becomes a physical
one: gravity acts (no gravity compensation), segment masses, centres of mass and
inertias come from de Leva's (1996) anthropometric table scaled to Skinny's segment
lengths (:func:`segment_inertias`), torques are limited to conservative human strength
(:data:`TORQUE_GEAR_NM`), and the physics step and integrator are the ones
``benchmarks/torque_step_check.py`` measured. The numbers and their sources are in
``models/skinny/README.md``.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from importlib.resources import files
from pathlib import Path

import mujoco
import numpy as np

from skinny_mj.errors import SkinnyEnvironmentError, SkinnyInputError
from skinny_mj.plant import body
from skinny_mj.plant.mjcf import compile_spec, read_model, read_spec

MODELS_ENV_VAR = "SKINNY_MJ_MODELS"
ACTUATIONS = ("velocity", "torque")
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
SEGMENT_LENGTH_M = {"upper_arm": body.UPPER_ARM_LENGTH_M, "forearm": body.FOREARM_LENGTH_M,
                    "hand": body.HAND_LENGTH_M}


def models_dir() -> Path:
    """The folder holding Skinny's XML: ``$SKINNY_MJ_MODELS``, else the installed package
    data ``skinny_mj.models`` (the repo's top-level ``models/``, mapped in pyproject):
    ``<repo>/models/skinny`` in an editable install, inside site-packages otherwise."""
    override = os.environ.get(MODELS_ENV_VAR)
    if override:
        return Path(override)
    try:
        return Path(str(files("skinny_mj.models").joinpath("skinny")))
    except ModuleNotFoundError:  # an install from before the models were package data
        raise SkinnyEnvironmentError(f"skinny_mj.models is not installed: reinstall the "
                                     f"package (pip install -e .) or set {MODELS_ENV_VAR}"
                                     ) from None


def _check(dof: int, actuation: str = "velocity") -> None:
    body.check_dof(dof)
    if actuation not in ACTUATIONS:
        raise SkinnyInputError(f"actuation must be one of {ACTUATIONS}, got {actuation!r}")


def xml_path(dof: int, scene: bool = True) -> Path:
    """Path of the body's scene (``scene_{2d,3d}.xml``: floor, light, camera) or, with
    ``scene=False``, of the robot alone (``skinny_{2d,3d}.xml``); a body another package
    registered (:class:`skinny_mj.plant.body.Body`) names its own folder and files."""
    spec = body.body_of(dof)
    path = (spec.folder or models_dir()) / (spec.scene if scene else spec.robot)
    if not path.is_file():
        # a missing model is the installation's fault (or $SKINNY_MJ_MODELS'), not the
        # user's input: an environment error, exit 1
        raise SkinnyEnvironmentError(
            f"{path}: model file not found (set {MODELS_ENV_VAR} to the models/skinny folder)")
    return path


def load_spec(dof: int, actuation: str = "velocity", scene: bool = True) -> mujoco.MjSpec:
    """The scene (``scene=False``: the robot alone) as an editable
    :class:`mujoco.MjSpec`; ``actuation="torque"`` makes the torque twin: every
    velocity actuator becomes a motor of the same name and joint, gear = peak torque
    (:data:`TORQUE_GEAR_NM`, N m; ctrlrange and forcerange [-1, 1], the joint's
    actuatorfrcrange +-gear), gravity compensation off, the arm bodies' inertials from
    :func:`segment_inertias`, joint damping :data:`TORQUE_JOINT_DAMPING` and armature
    :data:`TORQUE_ARMATURE` (the 3D shoulder hinges :data:`TORQUE_ARMATURE_3D_SHOULDER`),
    :data:`TORQUE_INTEGRATOR` at :data:`TORQUE_TIMESTEP_S`. The
    joints keep their limits (soft MuJoCo constraints). The velocity servo is the XML
    as it is."""
    _check(dof, actuation)
    check_on_load(dof)
    spec = read_spec(xml_path(dof, scene))
    if actuation == "torque":
        _make_physical(spec, dof)
    return spec


@dataclass(frozen=True)
class SegmentInertia:
    """One rigid segment: mass (kg), CoM distance from its proximal joint along the
    segment (m), and principal moments of inertia about the CoM (3,) kg m^2 about the
    body's x (medio-lateral), y (antero-posterior) and z (long) axes."""

    mass_kg: float
    com_m: float
    inertia_kg_m2: tuple[float, float, float]


def segment_inertias(body_mass_kg: float = BODY_MASS_KG) -> dict[str, SegmentInertia]:
    """de Leva's male table (:data:`DE_LEVA_MALE`) scaled to Skinny's segment lengths:
    masses are fractions of ``body_mass_kg``, CoM positions and radii of gyration
    fractions of each segment's length. Keys "upper_arm", "forearm", "hand"."""
    out = {}
    for name, (m_frac, com_frac, r_ap, r_ml, r_long) in DE_LEVA_MALE.items():
        length, mass = SEGMENT_LENGTH_M[name], m_frac * body_mass_kg
        inertia = tuple(mass * (r * length) ** 2 for r in (r_ml, r_ap, r_long))
        out[name] = SegmentInertia(mass, com_frac * length, inertia)
    return out


def forearm_hand_inertia(body_mass_kg: float = BODY_MASS_KG) -> SegmentInertia:
    """Forearm and hand as the one rigid body they are (no wrist joint): total mass, CoM
    distance from the elbow, and inertia about the combined CoM (parallel-axis theorem:
    each part's own inertia plus m d^2 about the two axes across the segment)."""
    seg = segment_inertias(body_mass_kg)
    fore, hand = seg["forearm"], seg["hand"]
    d_fore, d_hand = fore.com_m, body.FOREARM_LENGTH_M + hand.com_m  # from the elbow
    mass = fore.mass_kg + hand.mass_kg
    com = (fore.mass_kg * d_fore + hand.mass_kg * d_hand) / mass
    shift = fore.mass_kg * (d_fore - com) ** 2 + hand.mass_kg * (d_hand - com) ** 2
    own = np.add(fore.inertia_kg_m2, hand.inertia_kg_m2)
    return SegmentInertia(mass, com, (float(own[0] + shift), float(own[1] + shift),
                                      float(own[2])))


def _make_physical(spec: mujoco.MjSpec, dof: int) -> None:
    """Edit Skinny's spec into the torque twin (see the module docstring)."""
    spec.option.timestep = TORQUE_TIMESTEP_S
    spec.option.integrator = TORQUE_INTEGRATOR
    # No solver warm start: warm-started, the constraint solver's iterations at a joint
    # limit depend on every copy of a lockstep batch (1e-13 rad apart after 6 s); cold,
    # each copy is bit for bit one robot alone (tests/test_dynamic.py)
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_WARMSTART)
    for side in body.SIDES:
        for name, seg in segment_inertias().items():
            b = spec.body(f"{side}_{name}")
            b.gravcomp = 0.0
            b.explicitinertial = True  # these numbers, not the capsules' volumes
            b.mass = seg.mass_kg
            b.ipos = [0.0, 0.0, -seg.com_m]  # every segment points down its -z at q = 0
            b.iquat = [1.0, 0.0, 0.0, 0.0]
            b.inertia = list(seg.inertia_kg_m2)
    for name in body.dof_names(dof):
        limit = TORQUE_GEAR_NM.get(name.split("_", 1)[1])
        if limit is None:
            raise SkinnyInputError(f"the torque body has no peak torque for {name!r} "
                                   f"(skinny_mj.plant.model.TORQUE_GEAR_NM knows "
                                   f"{', '.join(TORQUE_GEAR_NM)})")
        joint = spec.joint(name)
        joint.damping[0] = TORQUE_JOINT_DAMPING
        joint.armature = TORQUE_ARMATURE_3D_SHOULDER if not body.body_of(dof).planar \
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


def load_model(dof: int, actuation: str = "velocity") -> mujoco.MjModel:
    """Compile Skinny's scene: ``dof`` 4 (2D) or 8 (3D), velocity servo or torque twin."""
    _check(dof, actuation)
    if actuation == "velocity":
        check_on_load(dof)
        return read_model(xml_path(dof))
    return compile_spec(load_spec(dof, actuation), xml_path(dof))


BATCH_PREFIX = "r{}/"  # names of copy r in :func:`load_batch_model`


def load_batch_model(dof: int, copies: int, actuation: str = "velocity",
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
    _check(dof, actuation)
    if copies < 1:
        raise SkinnyInputError(f"copies must be >= 1, got {copies}")
    parent = mujoco.MjSpec()
    one = load_spec(dof, actuation, scene=False)
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
        robot = load_spec(dof, actuation, scene=False)
        if edit is not None:
            edit(robot)
        parent.attach(robot, prefix=BATCH_PREFIX.format(r), frame=parent.worldbody.add_frame())
    return compile_spec(parent, xml_path(dof, scene=False))


def check_body(dof: int, poses: int = 20, seed: int = 0) -> list[str]:
    """What in a body's MJCF disagrees with its :class:`~skinny_mj.plant.body.Body` spec
    (empty: they agree): every joint and actuator named and ordered as
    :func:`~skinny_mj.plant.body.dof_names`, each hinge on its segment with the spec's
    axis and limited to its range, the sites ``{side}_{shoulder,elbow,wrist}``, and the
    sites' positions at ``poses`` random poses equal to
    :func:`~skinny_mj.plant.body.arm_points` (1e-9 m)."""
    _check(dof)
    model = read_model(xml_path(dof))
    problems = []
    names = list(body.dof_names(dof))
    joints = [model.joint(i).name for i in range(model.njnt)]
    actuators = [model.actuator(i).name for i in range(model.nu)]
    for kind, found in (("joint", joints), ("actuator", actuators)):
        missing = [n for n in names if n not in found]
        if missing:
            problems.append(f"no {kind} {', '.join(map(repr, missing))}")
        elif found != names:
            problems.append(f"{kind}s {found}, the spec says {names}")
    sites = [f"{s}_{p}" for s in body.SIDES for p in ("shoulder", "elbow", "wrist")]
    missing = [s for s in sites if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, s) < 0]
    problems += [f"no site {s!r}" for s in missing]
    if problems:
        return problems
    for side in body.SIDES:
        for spec in body.body_of(dof).arm_joints:
            joint = model.joint(f"{side}_{spec.name}")
            where = model.body(joint.bodyid[0]).name
            if where != f"{side}_{spec.segment}":
                problems.append(f"{joint.name} moves {where}, the spec says "
                                f"{side}_{spec.segment}")
            if not np.allclose(joint.axis, body.joint_axis(spec, side), atol=1e-12):
                problems.append(f"{joint.name} axis {joint.axis}, the spec says "
                                f"{body.joint_axis(spec, side)}")
            if not model.jnt_limited[joint.id] or not np.allclose(
                    joint.range, spec.range_rad, atol=1e-12):
                problems.append(f"{joint.name} range {joint.range}, the spec says "
                                f"{spec.range_rad} (limited)")
    if problems:
        return problems
    data = mujoco.MjData(model)
    site_ids = [model.site(s).id for s in sites]
    lo, hi = body.joint_ranges(dof).T
    rng = np.random.default_rng(seed)
    for _ in range(poses):
        q = rng.uniform(lo, hi)
        data.qpos[model.jnt_qposadr] = q
        mujoco.mj_kinematics(model, data)
        got = data.site_xpos[site_ids].reshape(2, 3, 3)
        if not np.allclose(got, body.arm_points(q, dof), atol=1e-9):
            problems.append(f"the sites' positions at q = {np.round(q, 3).tolist()} are not "
                            "the spec's (segment lengths, shoulder positions or axes)")
            break
    return problems


_CHECKED: set[tuple] = set()


def check_on_load(dof: int) -> None:
    """:func:`check_body` of the body's MJCF, once per body and file version: an MJCF
    that disagrees with its spec (an actuator taken out, a hinge renamed) is a
    :class:`SkinnyInputError` naming the file and what is wrong, not a ``KeyError``
    from deep inside the plant."""
    spec, path = body.body_of(dof), xml_path(dof, scene=False)
    key = (spec, *((str(f), f.stat().st_mtime_ns) for f in (path, xml_path(dof))))
    if key in _CHECKED:
        return
    problems = check_body(dof)
    if problems:
        raise SkinnyInputError(f"the MJCF does not match the {spec.label} body's spec "
                               f"(skinny_mj.plant.body): {'; '.join(problems)}", path=path)
    _CHECKED.add(key)
