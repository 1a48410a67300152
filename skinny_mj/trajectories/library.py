"""Named movements (SPEC §2, paper C) and one entry point for any movement source.

``get("ymca", "2d")``, ``get("y-pure@0.5", "3d", reps=5)``; ``names()`` lists them.
``load_movement(name_or_path, body)`` also reads trajectory files (.npz/.csv) and motion
capture (.amc with its .asf, .bvh), and returns the trajectory with a report of how
much had to be clipped into the body's joint ranges.

Two generated names (not in :func:`names`, which lists the fixed movements):

- motor babbling, ``babble`` or ``babble:seed=3,duration=20`` (also ``vmin=``,
  ``vmax=``: the segments' peak speeds, rad/s; see
  :mod:`skinny_mj.trajectories.babble`), with the usual ``@SPEED`` suffix;
- a training set of several movements, ``set:ymca+babble:seed=1+md_03.amc``: the pieces
  (any names or files, excerpts included) joined by slow minimum-jerk bridges (peak
  2 rad/s, >= 0.5 s) that carry the arms from one piece's last pose to the next one's
  first, so the set is one smooth movement (:func:`training_set`; ``load_movement``
  only, as pieces may be files; an ``.amc`` piece takes the ``asf`` given).
"""

from __future__ import annotations

import dataclasses
import logging
import numbers
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from skinny_mj.errors import SkinnyInputError
from skinny_mj.plant.body import CONTROL_DT_S, Body, BodyLike, body_of
from skinny_mj.trajectories import patterns
from skinny_mj.trajectories.asf_amc import load_asf_amc
from skinny_mj.trajectories.babble import babble, bridge, parse_babble_name
from skinny_mj.trajectories.bvh import load_bvh
from skinny_mj.trajectories.human import ymca_recorded
from skinny_mj.trajectories.retarget import RetargetReport, clip_report, range_excess
from skinny_mj.trajectories.retarget import retarget as retarget_clip
from skinny_mj.trajectories.samples import (
    SAMPLE_ASF,
    SAMPLE_CLIPS,
    SUBJECT_SKELETONS,
    sample_clip,
)
from skinny_mj.trajectories.trajectory import Trajectory, excerpt
from skinny_mj.trajectories.ymca import letter_end_steps, ymca


def _there_and_back(traj: Trajectory, end: int, name: str) -> Trajectory:
    part = traj.angles[:end]
    return Trajectory(np.concatenate([part, part[::-1]]), traj.dt, name, body=traj.body)


def _y(skinny: Body) -> Trajectory:
    """Y, then back to the start by playing the Y part in reverse."""
    return _there_and_back(ymca(skinny), letter_end_steps()["Y"], "y")


def _y_pure(skinny: Body) -> Trajectory:
    """``y`` with every elbow held at its starting angle (no elbow motion at all)."""
    angles = _y(skinny).angles.copy()
    elbows = [i for i, n in enumerate(skinny.dof_names) if n.endswith("elbow_flexion")]
    angles[:, elbows] = angles[0, elbows]
    return Trajectory(angles, _y(skinny).dt, "y-pure", body=skinny.name)


def _ym(skinny: Body) -> Trajectory:
    """Y, M, then back by playing that part in reverse."""
    return _there_and_back(ymca(skinny), letter_end_steps()["M"], "ym")


def _mirror(side: str) -> Callable[[Body], Trajectory]:
    def make(skinny: Body) -> Trajectory:
        """Both arms do one arm's YMCA part; equal angles are mirror images (body.py)."""
        angles = ymca(skinny).angles.copy()
        n_arm = skinny.dof // 2
        src = slice(0, n_arm) if side == "right" else slice(n_arm, skinny.dof)
        angles[:, :n_arm] = angles[:, src]
        angles[:, n_arm:] = angles[:, src]
        return Trajectory(angles, ymca(skinny).dt, f"mirror-{side}", body=skinny.name)

    return make


def _recorded(unit_2d: bool) -> Callable[[Body], Trajectory]:
    def make(skinny: Body) -> Trajectory:
        """The recorded-like YMCA (``skinny_mj.trajectories.human``), default seed."""
        return ymca_recorded(skinny, unit_2d=unit_2d)

    return make


_MOVEMENTS: dict[str, Callable[[Body], Trajectory]] = {
    "ymca": ymca,
    "ymca-smooth": lambda skinny: ymca(skinny).with_name("ymca-smooth"),  # ymca, by name
    "ymca-recorded": _recorded(False),
    "ymca-recorded-unit2d": _recorded(True),
    "y": _y,
    "y-pure": _y_pure,
    "ym": _ym,
    "mirror-right": _mirror("right"),
    "mirror-left": _mirror("left"),
}


def names() -> tuple[str, ...]:
    """Names accepted by :func:`get` (each may carry a speed suffix such as ``@0.5``):
    the YMCA family, then paper B's bimanual patterns."""
    return tuple(_MOVEMENTS) + patterns.names()


def get(name: str, body: BodyLike = "2d", *, speed: float = 1.0, reps: int = 1
        ) -> Trajectory:
    """A named movement for the body (its name, :data:`skinny_mj.plant.body.BODIES`),
    played at ``speed`` and repeated ``reps`` times.

    ``name`` may end in ``@SPEED`` (``"ymca@1.5"``); giving both a suffix and a
    ``speed`` other than 1 is an error. The speed change comes before the repetitions.
    """
    skinny = body_of(body)
    base, at, suffix = str(name).strip().lower().partition("@")
    babbling = parse_babble_name(base)
    if base not in names() and babbling is None:
        raise SkinnyInputError(f"unknown movement {name!r}; valid names: {', '.join(names())}")
    if at and not suffix:
        raise SkinnyInputError(f"{name!r} has no speed after '@' (use e.g. 'ymca@0.5')")
    if suffix:
        if speed != 1.0:
            raise SkinnyInputError(f"{name!r} has a speed suffix; do not also pass speed={speed}")
        try:
            speed = float(suffix)
        except ValueError:
            raise SkinnyInputError(f"bad speed suffix in {name!r} (use e.g. 'ymca@0.5')") from None
    if babbling is not None:
        traj = babble(skinny, seed=int(babbling["seed"]), duration_s=babbling["duration"],
                      v_min=babbling["vmin"], v_max=babbling["vmax"],
                      limits=babbling["limits"], holds=babbling["holds"]
                      ).resample(speed).repeat(reps)
    elif base in _MOVEMENTS:
        traj = _MOVEMENTS[base](skinny).resample(speed).repeat(reps)
    else:  # a rhythmic pattern is a function of the leader's phase: made at that speed
        traj = patterns.pattern_trajectory(base, skinny, speed).repeat(reps)
    label = base + (f"@{speed:g}" if speed != 1.0 else "") + (f"x{reps}" if reps != 1 else "")
    return traj.with_name(label)


_log = logging.getLogger(__name__)
_SKELETONS_SAID: set[tuple[str, str]] = set()  # (clip, skeleton) pairs already logged


def find_asf(amc: Path) -> Path:
    """The skeleton of the CMU clip ``amc``, beside it and named by its subject, the
    clip's name up to the first "_" (``86_02.amc``: ``86.asf``; the shipped clips:
    :data:`~skinny_mj.trajectories.samples.SUBJECT_SKELETONS`). Without one (another
    subject's skeleton is never taken), a :class:`SkinnyInputError` asking for ``--asf``."""
    subject = amc.stem.split("_")[0].lower()
    wanted = {subject, SUBJECT_SKELETONS.get(subject, subject)}
    skeletons = sorted(p for p in amc.parent.glob("*") if p.suffix.lower() == ".asf")
    found = [p for p in skeletons if p.stem.lower() in wanted]
    if len(found) == 1:
        return found[0]
    if found:
        what = f"{len(found)} skeletons of subject {subject!r} ({', '.join(p.name for p in found)})"
    else:
        others = f"; beside it: {', '.join(p.name for p in skeletons)}" if skeletons else ""
        what = f"no skeleton {subject}.asf of its subject{others}"
    raise SkinnyInputError(f"{what}: pass the clip's skeleton with --asf (asf= in Python)",
                           path=amc)


def _say_skeleton(amc: Path, asf: Path, given: bool) -> None:
    """Log which skeleton an .amc was read with, once per pair: a warning (shown on
    stderr by default) when it was found beside a clip of the user's, info when it was
    given or is the shipped clips' own."""
    if (str(amc), str(asf)) in _SKELETONS_SAID:
        return
    _SKELETONS_SAID.add((str(amc), str(asf)))
    if given:
        _log.info("%s: skeleton %s (given)", amc.name, asf)
    elif asf.resolve() == SAMPLE_ASF.resolve():
        _log.info("%s: skeleton %s (the shipped clips')", amc.name, asf)
    else:
        _log.warning("%s: skeleton %s (beside it, by the clip's subject)", amc.name, asf)


_FILE_SUFFIXES = (".npz", ".csv", ".amc", ".bvh")
_EXCERPT_KEYS = ("start", "duration")


def split_excerpt(text: str) -> tuple[str, tuple[float, float | None] | None]:
    """``"PATH@start=S,duration=D"`` -> ``(PATH, (S, D))`` in seconds.

    The excerpt syntax for movement files: ``@`` after a ``.npz``/``.csv``/``.amc``/
    ``.bvh`` path, then comma-separated ``start=`` (default 0) and ``duration=``
    (default: to the end), e.g. ``md_02.amc@start=3,duration=6.26``. Anything else
    (a library name such as ``ymca@1.5``, a plain path) comes back unchanged with None.
    """
    base, at, spec = str(text).rpartition("@")
    if not at or Path(base).suffix.lower() not in _FILE_SUFFIXES or Path(text).exists():
        return str(text), None
    if "=" not in spec:
        raise SkinnyInputError(f"bad excerpt {spec!r} in {text!r}: use "
                               "PATH@start=SECONDS,duration=SECONDS")
    values: dict[str, float] = {}
    for item in spec.split(","):
        key, eq, value = (part.strip() for part in item.partition("="))
        if not eq or key not in _EXCERPT_KEYS or key in values:
            raise SkinnyInputError(f"bad excerpt {spec!r} in {text!r}: use "
                                   "PATH@start=SECONDS,duration=SECONDS")
        try:
            values[key] = float(value)
        except ValueError:
            raise SkinnyInputError(f"excerpt {key}={value!r} is not a number of seconds "
                                   f"in {text!r}") from None
    start, duration = values.get("start", 0.0), values.get("duration")
    if not (np.isfinite(start) and start >= 0) or (
            duration is not None and not (np.isfinite(duration) and duration > 0)):
        raise SkinnyInputError(f"excerpt in {text!r} needs start >= 0 and duration > 0 s")
    return base, (start, duration)


def load_movement(
    name_or_path: str | Path,
    body: BodyLike = "2d",
    *,
    asf: str | Path | None = None,
    speed: float = 1.0,
    reps: int = 1,
    fps: float | None = None,
    cutoff_hz: float = 6.0,
    retarget: str = "angles",
) -> tuple[Trajectory, RetargetReport]:
    """Any movement for the body: a library name, a ``.npz``/``.csv`` trajectory, ``.amc``
    (+ ``asf``, or its subject's skeleton beside it, :func:`find_asf`) or ``.bvh`` motion
    capture.

    Returns the trajectory (clipped into the joint ranges, at ``speed``, ``reps`` times)
    and a :class:`RetargetReport` saying how much was clipped (zero for library names).
    ``fps`` overrides the capture rate of an .amc (default 120 Hz, CMU's) or a .bvh.
    A file may carry an excerpt, ``PATH@start=S,duration=D`` (see :func:`split_excerpt`);
    the report then covers the excerpt only. ``retarget="positions"``: motion capture's
    desired signals are the subject's normalized segment vectors (see ``retarget``).
    """
    if retarget not in ("angles", "positions"):
        raise SkinnyInputError(f"retarget must be 'angles' or 'positions', got {retarget!r}")
    for name, value in (("fps", fps), ("cutoff_hz", cutoff_hz)):
        if value is not None and (isinstance(value, bool) or not isinstance(value, numbers.Real)
                                  or not (np.isfinite(value) and value > 0)):
            raise SkinnyInputError(f"{name} must be a number > 0, got {value!r}")
    skinny = body_of(body)
    if not str(name_or_path).strip():
        raise SkinnyInputError("empty movement name: give a name (`skinny trajectory "
                               "list`) or a file")
    if str(name_or_path).strip().lower().startswith(SET_PREFIX):
        traj, report = training_set(str(name_or_path), skinny, asf=asf, fps=fps,
                                    cutoff_hz=cutoff_hz, retarget=retarget)
        return traj.resample(speed).repeat(reps), report
    text, window = split_excerpt(str(name_or_path))
    suffix = Path(text).suffix.lower()
    if suffix not in _FILE_SUFFIXES:
        base = text.strip().lower().partition("@")[0]
        if base in names() or parse_babble_name(base) is not None or not Path(text).exists():
            traj = get(text, skinny, speed=speed, reps=reps)
            excess = range_excess(traj.angles, skinny)
            return traj, clip_report(excess, skinny, source=text, source_fps=1.0 / traj.dt)
        if Path(text).is_dir():
            raise SkinnyInputError("a folder, not a movement file", path=text)
        raise SkinnyInputError(
            "unknown movement file type (use .npz, .csv, .amc with .asf, or .bvh)", path=text
        )
    path = Path(text)
    if not path.is_file() and str(path.parent) == "." and path.stem in SAMPLE_CLIPS \
            and suffix == ".amc":
        path = sample_clip(path.stem)  # a bare shipped clip name: md_02.amc, md_03.amc
    if path.is_dir():
        raise SkinnyInputError("a folder, not a movement file", path=path)
    if not path.is_file():
        raise SkinnyInputError("no such file", path=path)
    if suffix in (".npz", ".csv"):
        raw = Trajectory.load(path, skinny.dof).on(skinny)
        if len(raw) < 2 or abs(raw.dt - CONTROL_DT_S) > 1e-9:
            raise SkinnyInputError(f"{len(raw)} step(s) every {raw.dt:g} s: a movement is at "
                                   f"least 2 steps every {CONTROL_DT_S:g} s (50 Hz)",
                                   path=path)
        if window is not None:
            raw = excerpt(raw, *window)
        clipped, _ = raw.clip_to_range()
        excess = range_excess(raw.angles, skinny)
        report = clip_report(excess, skinny, source=str(path), source_fps=1.0 / raw.dt)
        traj = clipped
    else:
        if suffix == ".amc":
            skeleton = Path(asf) if asf is not None else find_asf(path)
            clip = load_asf_amc(skeleton, path, fps=fps)
        else:
            clip = load_bvh(path, fps=fps)
        traj, report = retarget_clip(clip, skinny, cutoff_hz=cutoff_hz, window_s=window,
                                     targets=retarget)
        if suffix == ".amc":
            _say_skeleton(path, skeleton, asf is not None)
    traj = traj.resample(speed).repeat(reps)
    return traj, report


def resolve_trajectory(trajectory: object, body: BodyLike) -> object:
    """The movement a ``trajectory`` argument (of :func:`skinny_mj.load`, the gym envs)
    names: None (the synthesized YMCA), any name or file the command line's
    ``--trajectory`` takes (``"ymca@0.5"``, ``"babble:seed=3"``, ``"set:ymca+md_03.amc"``,
    ``"clip.csv@start=2"``; :func:`load_movement`), a (T, n_dof) array of angles in rad,
    or an object with ``.angles`` (T, n_dof) rad, ``.dt`` and ``.dof`` (a
    :class:`Trajectory`), returned as it is. Anything else is a :class:`SkinnyInputError`."""
    if trajectory is None:
        return get("ymca", body)
    if isinstance(trajectory, str | os.PathLike):
        return load_movement(trajectory, body)[0]
    if isinstance(trajectory, np.ndarray):
        return Trajectory(trajectory, body=body_of(body).name)
    if not hasattr(trajectory, "angles"):
        raise SkinnyInputError(f"trajectory must be a movement name or file, (T, n_dof) "
                               f"angles or a Trajectory, got {type(trajectory).__name__}")
    return trajectory


SET_PREFIX = "set:"


def set_pieces(name: str) -> list[str]:
    """``"set:ymca+babble:seed=1+md_03.amc"`` -> ``["ymca", "babble:seed=1", "md_03.amc"]``."""
    text = str(name).strip()
    if not text.lower().startswith(SET_PREFIX):
        raise SkinnyInputError(f"a training set is named set:A+B+..., got {name!r}")
    pieces = [p.strip() for p in text[len(SET_PREFIX):].split("+")]
    if not pieces or any(not p for p in pieces) or any(
            p.lower().startswith(SET_PREFIX) for p in pieces):
        raise SkinnyInputError(f"bad training set {name!r}: use set:A+B+... with no empty "
                               "or nested pieces")
    return pieces


def check_asf(movement: str | Path | None, asf: str | Path | None,
              retarget: str = "angles") -> None:
    """Refuse a skeleton (``--asf``) given for a movement with no ``.amc`` clip in it, or
    ``retarget="positions"`` for one with no motion capture: either would silently go
    unused."""
    text = "" if movement is None else str(movement)
    if asf is not None and not text.strip():
        raise SkinnyInputError(f"--asf {asf} is the skeleton of an .amc clip: give the clip "
                               "as the movement too")
    if asf is None and retarget == "angles":
        return
    pieces = set_pieces(text) if text.strip().lower().startswith(SET_PREFIX) else [text]
    suffixes = {Path(split_excerpt(p)[0].strip()).suffix.lower() for p in pieces}
    if asf is not None and ".amc" not in suffixes:
        raise SkinnyInputError(f"--asf {asf} is the skeleton of an .amc clip, and the "
                               f"movement {text!r} has none: leave --asf out")
    if retarget == "positions" and not suffixes & {".amc", ".bvh"}:
        raise SkinnyInputError(f"--retarget positions reads motion capture (.amc, .bvh), and "
                               f"the movement {text!r} has none: leave it out")


def training_set(name: str, body: BodyLike, *, asf: str | Path | None = None,
                 fps: float | None = None, cutoff_hz: float = 6.0, retarget: str = "angles"
                 ) -> tuple[Trajectory, RetargetReport]:
    """The pieces of ``set:A+B+...`` (each through :func:`load_movement`) joined by
    minimum-jerk bridges (:func:`skinny_mj.trajectories.babble.bridge`).

    Returns the joined trajectory (named by ``name``) and a report whose counts add up
    over the pieces (largest excess over all; rate and cutoff of the first piece)."""
    parts: list[np.ndarray] = []
    reports: list[RetargetReport] = []
    dt = None
    for piece in set_pieces(name):
        is_amc = split_excerpt(piece)[0].lower().endswith(".amc")
        traj, report = load_movement(piece, body, asf=asf if is_amc else None, fps=fps,
                                     cutoff_hz=cutoff_hz, retarget=retarget)
        if dt is not None and abs(traj.dt - dt) > 1e-12:
            raise SkinnyInputError(f"training set {name!r}: pieces at different time steps")
        dt = traj.dt
        if parts:
            parts.append(bridge(parts[-1][-1], traj.angles[0], dt))
        parts.append(traj.angles)
        reports.append(report)
    joined = Trajectory(np.concatenate(parts), dt, str(name).strip(), body=traj.body)
    first = reports[0]
    per_dof = {k: sum(int(r.clipped_per_dof.get(k, 0)) for r in reports)
               for k in first.clipped_per_dof}
    excess = {k: max(float(r.max_excess_deg_per_dof.get(k, 0.0)) for r in reports)
              for k in first.max_excess_deg_per_dof}
    return joined, dataclasses.replace(
        first, source=str(name).strip(), steps=len(joined),
        source_frames=sum(int(r.source_frames) for r in reports),
        clipped_samples=sum(int(r.clipped_samples) for r in reports),
        clipped_steps=sum(int(r.clipped_steps) for r in reports), clipped_per_dof=per_dof,
        max_excess_deg=max(float(r.max_excess_deg) for r in reports),
        max_excess_deg_per_dof=excess,
        interpolated_samples=sum(int(r.interpolated_samples) for r in reports))
