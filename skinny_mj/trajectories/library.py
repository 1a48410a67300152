"""Named movements (SPEC §2, paper C) and one entry point for any movement source.

``get("ymca", dof=4)``, ``get("y-pure@0.5", dof=8, reps=5)``; ``names()`` lists them.
``load_movement(name_or_path, dof)`` also reads trajectory files (.npz/.csv) and motion
capture (.amc with its .asf, .bvh), and returns the trajectory with a report of how
much had to be clipped into Skinny's joint ranges.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from skinny_mj import body
from skinny_mj.errors import SkinnyInputError
from skinny_mj.trajectories import patterns
from skinny_mj.trajectories.retarget import RetargetReport, clip_report, range_excess
from skinny_mj.trajectories.trajectory import Trajectory, excerpt
from skinny_mj.trajectories.ymca import letter_end_steps, ymca


def _there_and_back(traj: Trajectory, end: int, name: str) -> Trajectory:
    part = Trajectory(traj.angles[:end], traj.dt, name)
    return Trajectory(np.concatenate([part.angles, part.angles[::-1]]), traj.dt, name)


def _y(dof: int) -> Trajectory:
    """Y, then back to the start by playing the Y part in reverse."""
    return _there_and_back(ymca(dof), letter_end_steps()["Y"], "y")


def _y_pure(dof: int) -> Trajectory:
    """``y`` with every elbow held at its starting angle (no elbow motion at all)."""
    angles = _y(dof).angles.copy()
    elbows = [i for i, n in enumerate(body.dof_names(dof)) if n.endswith("elbow_flexion")]
    angles[:, elbows] = angles[0, elbows]
    return Trajectory(angles, _y(dof).dt, "y-pure")


def _ym(dof: int) -> Trajectory:
    """Y, M, then back by playing that part in reverse."""
    return _there_and_back(ymca(dof), letter_end_steps()["M"], "ym")


def _mirror(side: str) -> Callable[[int], Trajectory]:
    def make(dof: int) -> Trajectory:
        """Both arms do one arm's YMCA part; equal angles are mirror images (body.py)."""
        angles = ymca(dof).angles.copy()
        n_arm = dof // 2
        src = slice(0, n_arm) if side == "right" else slice(n_arm, dof)
        angles[:, :n_arm] = angles[:, src]
        angles[:, n_arm:] = angles[:, src]
        return Trajectory(angles, ymca(dof).dt, f"mirror-{side}")

    return make


_MOVEMENTS: dict[str, Callable[[int], Trajectory]] = {
    "ymca": ymca,
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


_check_dof = body.check_dof


def get(name: str, dof: int = 4, *, speed: float = 1.0, reps: int = 1) -> Trajectory:
    """A named movement for ``dof`` (4 or 8), played at ``speed`` and repeated ``reps`` times.

    ``name`` may end in ``@SPEED`` (``"ymca@1.5"``); giving both a suffix and a
    ``speed`` other than 1 is an error. The speed change comes before the repetitions.
    """
    _check_dof(dof)
    base, _, suffix = str(name).strip().lower().partition("@")
    if base not in names():
        raise SkinnyInputError(f"unknown movement {name!r}; valid names: {', '.join(names())}")
    if suffix:
        if speed != 1.0:
            raise SkinnyInputError(f"{name!r} has a speed suffix; do not also pass speed={speed}")
        try:
            speed = float(suffix)
        except ValueError:
            raise SkinnyInputError(f"bad speed suffix in {name!r} (use e.g. 'ymca@0.5')") from None
    if base in _MOVEMENTS:
        traj = _MOVEMENTS[base](dof).resample(speed).repeat(reps)
    else:  # a rhythmic pattern is a function of the leader's phase: made at that speed
        traj = patterns.pattern_trajectory(base, dof, speed).repeat(reps)
    label = base + (f"@{speed:g}" if speed != 1.0 else "") + (f"x{reps}" if reps != 1 else "")
    return traj.with_name(label)


def _find_asf(amc: Path) -> Path:
    found = sorted(amc.parent.glob("*.asf")) + sorted(amc.parent.glob("*.ASF"))
    found = sorted(set(found))
    if len(found) != 1:
        what = "no .asf" if not found else f"{len(found)} .asf files"
        raise SkinnyInputError(f"{what} beside the .amc; pass the skeleton with asf=", path=amc)
    return found[0]


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
    if not at or Path(base).suffix.lower() not in _FILE_SUFFIXES or "=" not in spec:
        return str(text), None
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
    dof: int = 4,
    *,
    asf: str | Path | None = None,
    speed: float = 1.0,
    reps: int = 1,
    fps: float | None = None,
    cutoff_hz: float = 6.0,
) -> tuple[Trajectory, RetargetReport]:
    """Any movement: a library name, a ``.npz``/``.csv`` trajectory, ``.amc`` (+ ``asf``,
    or the single ``.asf`` in the same folder) or ``.bvh`` motion capture.

    Returns the trajectory (clipped into the joint ranges, at ``speed``, ``reps`` times)
    and a :class:`RetargetReport` saying how much was clipped (zero for library names).
    ``fps`` overrides the capture rate of an .amc (default 120 Hz, CMU's) or a .bvh.
    A file may carry an excerpt, ``PATH@start=S,duration=D`` (see :func:`split_excerpt`);
    the report then covers the excerpt only.
    """
    _check_dof(dof)
    text, window = split_excerpt(str(name_or_path))
    suffix = Path(text).suffix.lower()
    if suffix not in _FILE_SUFFIXES:
        base = text.strip().lower().partition("@")[0]
        if base in names() or not Path(text).exists():
            traj = get(text, dof, speed=speed, reps=reps)
            excess = range_excess(traj.angles, dof)
            return traj, clip_report(excess, dof, source=text, source_fps=1.0 / traj.dt)
        raise SkinnyInputError(
            "unknown movement file type (use .npz, .csv, .amc with .asf, or .bvh)", path=text
        )
    path = Path(text)
    if not path.is_file():
        raise SkinnyInputError("no such file", path=path)
    if suffix in (".npz", ".csv"):
        raw = Trajectory.load(path, dof=dof)
        if window is not None:
            raw = excerpt(raw, *window)
        clipped, _ = raw.clip_to_range()
        excess = range_excess(raw.angles, dof)
        report = clip_report(excess, dof, source=str(path), source_fps=1.0 / raw.dt)
        traj = clipped
    else:
        from skinny_mj.trajectories.retarget import retarget

        if suffix == ".amc":
            from skinny_mj.trajectories.asf_amc import load_asf_amc

            clip = load_asf_amc(Path(asf) if asf is not None else _find_asf(path), path, fps=fps)
        else:
            from skinny_mj.trajectories.bvh import load_bvh

            clip = load_bvh(path, fps=fps)
        traj, report = retarget(clip, dof, cutoff_hz=cutoff_hz, window_s=window)
    traj = traj.resample(speed).repeat(reps)
    return traj, report
