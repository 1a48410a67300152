"""The :class:`Trajectory` value: joint angles over time, and its file formats.

A trajectory is what Skinny is asked to imitate: ``angles`` (T, n_dof) in radians at a
fixed step ``dt`` (0.02 s = 50 Hz), columns in its body's
:attr:`~skinny_mj.plant.body.Body.dof_names` order (``body``: a body's name; None: Skinny's
2D or 3D by the number of columns). It is immutable; every operation returns a new one.

Optional explicit desired signals: ``desired = {"cartesian": (T, n_sig)}``,
a recorded position signal that is NOT Skinny's own kinematics of ``angles`` (a human's
normalized segment vectors, reachable or not); ``angles`` are then its inverse
kinematics (the true commands). :meth:`Trajectory.position_signals` returns them when
present; every time operation carries them along; ``.npz`` stores them.

Files: ``.npz`` (arrays ``angles`` and ``meta``, a JSON string; loaded with
``allow_pickle=False``) and ``.csv`` (a ``# dt=...`` comment line, a header with the
DOF names, one row per step, floats written with 17 significant digits so that the
round trip is exact). Every malformed file raises :class:`SkinnyInputError` naming
the file and, for CSV, the line.
"""

from __future__ import annotations

import io
import json
import math
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from skinny_mj.errors import SkinnyInputError
from skinny_mj.io import atomic_path, atomic_write_text
from skinny_mj.plant import body
from skinny_mj.plant.body import Body, BodyLike, body_of
from skinny_mj.preflight import Estimate, check, check_path_name

DEFAULT_DT_S = body.CONTROL_DT_S  # movements are sampled at the control rate
#: Largest |angle| a movement may hold, rad (joint ranges are within +-pi; a larger
#: finite value is clipped, but one near the float limit overflows in speeds and degrees).
MAX_ABS_ANGLE_RAD = 1000.0
MIN_SPEED, MAX_SPEED = 0.0, 10.0  # resample(speed) accepts MIN_SPEED < speed <= MAX_SPEED
_FORMAT_VERSION = 1


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Joint angles over time for a body.

    Parameters
    ----------
    angles : (T, n_dof) joint angles, rad, columns in the body's ``dof_names`` order.
    dt : time step, s (default 0.02 = 50 Hz).
    name : a label (used in file metadata and recordings).
    desired : {signals: (T, n_signals)} explicit desired signals, or None.
    body : the name of the body the angles are for (a :data:`~skinny_mj.plant.body.
        BodyLike`, kept as its name); None: Skinny's 2D (4 columns) or 3D (8).
    """

    angles: np.ndarray
    dt: float = DEFAULT_DT_S
    name: str = "trajectory"
    desired: dict | None = None  # {signals: (T, n_signals)} explicit desired signals
    body: str | None = None

    def __post_init__(self) -> None:
        if np.iscomplexobj(self.angles):  # float() would drop the imaginary part, warning
            raise SkinnyInputError(f"trajectory {self.name!r}: angles must be real numbers, "
                                   f"got {np.asarray(self.angles).dtype}")
        try:
            a = np.array(self.angles, dtype=float)
        except (TypeError, ValueError) as exc:
            raise SkinnyInputError(
                f"trajectory {self.name!r}: angles are not numbers ({exc})"
            ) from None
        if a.ndim != 2 or a.shape[0] < 1:
            raise SkinnyInputError(
                f"trajectory {self.name!r}: angles must be (T>=1, n_dof), got shape {a.shape}"
            )
        if self.body is None and a.shape[1] not in body.DOF_ALIASES:
            raise SkinnyInputError(
                f"trajectory {self.name!r}: {a.shape[1]} columns, expected 4 (2D) or 8 (3D) "
                "DOFs, or the name of the body they are for"
            )
        if self.body is not None:
            skinny = body_of(self.body)
            if a.shape[1] != skinny.dof:
                raise SkinnyInputError(f"trajectory {self.name!r}: {a.shape[1]} columns, the "
                                       f"{skinny.name} body has {skinny.dof} DOFs")
            object.__setattr__(self, "body", skinny.name)
        if not np.all(np.isfinite(a)):
            t, j = np.argwhere(~np.isfinite(a))[0]
            raise SkinnyInputError(
                f"trajectory {self.name!r}: non-finite angle at step {t}, DOF {j}"
            )
        if np.any(np.abs(a) > MAX_ABS_ANGLE_RAD):  # finite, but its speeds and degrees
            t, j = np.argwhere(np.abs(a) > MAX_ABS_ANGLE_RAD)[0]  # would overflow to inf
            raise SkinnyInputError(
                f"trajectory {self.name!r}: angle {a[t, j]:g} rad at step {t}, DOF {j} is not "
                f"a joint angle (|angle| <= {MAX_ABS_ANGLE_RAD:g} rad)"
            )
        try:
            dt = float(self.dt)
        except (TypeError, ValueError):
            dt = math.nan
        if isinstance(self.dt, bool) or not (math.isfinite(dt) and dt > 0):
            raise SkinnyInputError(f"trajectory {self.name!r}: dt must be a finite number > 0 "
                                   f"s, got {self.dt!r}")
        a.setflags(write=False)
        object.__setattr__(self, "angles", a)
        object.__setattr__(self, "dt", dt)
        object.__setattr__(self, "name", str(self.name))
        object.__setattr__(self, "desired", _check_desired(self.desired, a, self.name,
                                                           self.skinny))

    # -- basic properties -------------------------------------------------------------
    @property
    def dof(self) -> int:
        """The number of columns: the body's hinges."""
        return int(self.angles.shape[1])

    @property
    def skinny(self) -> Body:
        """The :class:`~skinny_mj.plant.body.Body` the angles are for."""
        return body_of(self.dof if self.body is None else self.body)

    @property
    def dof_names(self) -> tuple[str, ...]:
        return self.skinny.dof_names

    def __len__(self) -> int:
        return int(self.angles.shape[0])

    @property
    def duration_s(self) -> float:
        """Number of steps times dt (313 steps at 0.02 s = 6.26 s)."""
        return len(self) * self.dt

    def __repr__(self) -> str:
        return f"Trajectory(name={self.name!r}, steps={len(self)}, dof={self.dof}, dt={self.dt})"

    # -- signals ----------------------------------------------------------------------
    def position_signals(self, signals: str = "joint", on: BodyLike | None = None
                         ) -> np.ndarray:
        """Normalized position signals (T, n_signals): the explicit ones if it has them,
        else the kinematics of the body ``on`` (default its own,
        :meth:`~skinny_mj.plant.body.Body.position_signals`)."""
        body.check_signals(signals)
        if self.desired and signals in self.desired:
            return np.array(self.desired[signals])
        return body_of(self.skinny if on is None else on).position_signals(self.angles,
                                                                             signals)

    def _map(self, angles: np.ndarray, name: str, fn) -> Trajectory:
        """A new trajectory of ``angles`` whose explicit signals are ``fn(signals)``."""
        desired = None if not self.desired else {k: fn(v) for k, v in self.desired.items()}
        return Trajectory(angles, self.dt, name, desired, self.body)

    def velocities(self) -> np.ndarray:
        """Joint velocities (T-1, n_dof), rad/s: forward differences / dt."""
        return np.diff(self.angles, axis=0) / self.dt

    def max_speed_rad_s(self) -> np.ndarray:
        """Fastest absolute speed per DOF, (n_dof,) rad/s (zeros for a single step)."""
        v = self.velocities()
        return np.abs(v).max(axis=0) if len(v) else np.zeros(self.dof)

    # -- transformations --------------------------------------------------------------
    def resample(self, speed: float) -> Trajectory:
        """Play the movement ``speed`` times as fast: ``round(T / speed)`` steps, same dt.

        Shape-preserving cubic (PCHIP) interpolation in time, end poses kept, so a
        trajectory inside the joint ranges stays inside them. speed 0.5 doubles the steps.
        """
        try:
            speed = float(speed)
        except (TypeError, ValueError):
            raise SkinnyInputError(f"speed must be a number, got {speed!r}") from None
        if not (math.isfinite(speed) and MIN_SPEED < speed <= MAX_SPEED):
            raise SkinnyInputError(
                f"speed must be in ({MIN_SPEED:g}, {MAX_SPEED:g}], got {speed:g}"
            )
        if speed == 1.0 or len(self) < 2:
            return self
        from scipy.interpolate import PchipInterpolator

        n = max(2, int(round(len(self) / speed)))
        steps = str(n) if n < 10**15 else f"{n:.3g}"  # not 290 digits for speed 1e-300
        check_size(n, self.dof, f"speed {speed:g}: {steps} steps of {self.name}")
        src = np.arange(len(self), dtype=float)
        dst = np.linspace(0.0, len(self) - 1.0, n)
        angles = PchipInterpolator(src, self.angles, axis=0)(dst)
        return self._map(angles, f"{self.name}@{speed:g}",
                         lambda v: PchipInterpolator(src, v, axis=0)(dst))

    def repeat(self, n: int) -> Trajectory:
        """The movement ``n`` times in a row ((n*T, n_dof))."""
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
            raise SkinnyInputError(f"repetitions must be an integer >= 1, got {n!r}")
        if n == 1:
            return self
        check_size(int(n) * len(self), self.dof, f"{n} repetitions of {self.name}")
        return self._map(np.tile(self.angles, (int(n), 1)), f"{self.name}x{n}",
                         lambda v: np.tile(v, (int(n), 1)))

    def reversed(self) -> Trajectory:
        """The movement played backwards."""
        return self._map(self.angles[::-1], f"{self.name}-reversed", lambda v: v[::-1])

    def concat(self, other: Trajectory) -> Trajectory:
        """This movement followed by ``other`` (same dof and dt)."""
        if not isinstance(other, Trajectory):
            return NotImplemented
        if other.dof != self.dof or other.body != self.body:
            raise SkinnyInputError(f"cannot join a trajectory for {self.body or self.dof} and "
                                   f"one for {other.body or other.dof}")
        if not math.isclose(other.dt, self.dt, rel_tol=1e-9):
            raise SkinnyInputError(f"cannot join dt={self.dt} s and dt={other.dt} s trajectories")
        keys = set(self.desired or {}) & set(other.desired or {})  # signals both carry
        desired = {k: np.concatenate([self.desired[k], other.desired[k]]) for k in keys}
        return Trajectory(np.concatenate([self.angles, other.angles]), self.dt,
                          f"{self.name}+{other.name}", desired or None, self.body)

    __add__ = concat

    def with_name(self, name: str) -> Trajectory:
        return Trajectory(self.angles, self.dt, name, self.desired, self.body)

    def on(self, which: BodyLike) -> Trajectory:
        """The same angles for the body ``which`` (with as many hinges)."""
        return Trajectory(self.angles, self.dt, self.name, self.desired, body_of(which).name)

    def clip_to_range(self) -> tuple[Trajectory, int]:
        """Clip every angle into the body's joint ranges; returns the clipped trajectory
        and the number of (step, DOF) samples that were outside."""
        lo, hi = self.skinny.joint_ranges().T
        outside = int(np.count_nonzero((self.angles < lo) | (self.angles > hi)))
        if outside == 0:
            return self, 0
        return Trajectory(np.clip(self.angles, lo, hi), self.dt, self.name,
                          self.desired, self.body), outside

    # -- files ------------------------------------------------------------------------
    def save(self, path: str | Path) -> Path:
        """Write ``.npz`` or ``.csv`` (chosen by the suffix) atomically."""
        path = check_path_name(path, "trajectory file")  # a NUL byte, a name too long
        suffix = path.suffix.lower()
        if suffix == ".npz":
            meta = {
                "format_version": _FORMAT_VERSION,
                "name": self.name,
                "dt": self.dt,
                "dof": self.dof,
                "dof_names": list(self.dof_names),
                **({} if self.body is None else {"body": self.body}),
            }
            extra = {f"desired_{k}": v for k, v in (self.desired or {}).items()}
            with atomic_path(path) as tmp, open(tmp, "wb") as fh:
                np.savez(fh, angles=self.angles, meta=np.array(json.dumps(meta)), **extra)
            return path
        if suffix == ".csv" and self.desired:
            raise SkinnyInputError("explicit desired signals are stored in .npz only", path=path)
        if suffix == ".csv":
            buf = io.StringIO()
            buf.write(f"# skinny-mj trajectory; name={self.name}; dt={self.dt!r}; dof={self.dof}"
                      + ("" if self.body is None else f"; body={self.body}") + "\n")
            buf.write(",".join(self.dof_names) + "\n")
            np.savetxt(buf, self.angles, fmt="%.17g", delimiter=",")
            atomic_write_text(path, buf.getvalue())
            return path
        raise SkinnyInputError("trajectory files must end in .npz or .csv", path=path)

    @classmethod
    def load(cls, path: str | Path, n_dof: int | None = None) -> Trajectory:
        """Read a ``.npz`` or ``.csv`` trajectory; ``n_dof`` (if given) must match the
        file."""
        path = Path(path)
        if path.is_dir():
            raise SkinnyInputError("a folder, not a trajectory file", path=path)
        if not path.is_file():
            raise SkinnyInputError("no such trajectory file", path=path)
        suffix = path.suffix.lower()
        if suffix == ".npz":
            traj = _load_npz(path)
        elif suffix == ".csv":
            traj = _load_csv(path)
        else:
            raise SkinnyInputError("trajectory files must end in .npz or .csv", path=path)
        if n_dof is not None and traj.dof != n_dof:
            raise SkinnyInputError(
                f"DOF mismatch: file has {traj.dof} DOFs, {n_dof} were asked for", path=path
            )
        return traj


def _load_npz(path: Path) -> Trajectory:
    if path.is_file() and path.stat().st_size and not zipfile.is_zipfile(path):
        raise SkinnyInputError("not a readable trajectory npz (not an .npz archive)", path=path)
    try:
        with np.load(path, allow_pickle=False) as data:
            if "angles" not in data.files or "meta" not in data.files:
                raise SkinnyInputError("npz needs arrays 'angles' and 'meta'", path=path)
            angles = np.asarray(data["angles"])
            meta = json.loads(str(data["meta"]))
            desired = {k[len("desired_"):]: np.asarray(data[k])
                       for k in data.files if k.startswith("desired_")} or None
    except SkinnyInputError:
        raise
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, NotImplementedError) as exc:
        # zip errors, pickled objects, bad JSON (BadZipFile: a zip header with no zip after
        # it; NotImplementedError: a zip version or compression zipfile cannot read)
        text = str(exc)
        if "allow_pickle" in text:  # numpy's advice to load it unsafely: not ours to give
            text = "it holds pickled Python objects, which are not loaded: they can run code"
        raise SkinnyInputError(f"not a readable trajectory npz ({text})", path=path) from None
    if not isinstance(meta, dict):
        raise SkinnyInputError("'meta' must be a JSON object", path=path)
    which = meta.get("body")
    if which is not None and not isinstance(which, str):
        raise SkinnyInputError(f"meta body must be a body's name, got {which!r}", path=path)
    if angles.ndim != 2 or (which is None and angles.shape[1] not in body.DOF_ALIASES):
        raise SkinnyInputError(f"angles must be (T, 4 or 8), or meta must name the body, got "
                               f"shape {angles.shape}", path=path)
    names = meta.get("dof_names")
    if names is not None and (not isinstance(names, list) or tuple(names) != body_of(
            angles.shape[1] if which is None else which).dof_names):
        raise SkinnyInputError(f"DOF names {names} are not the {which or angles.shape[1]} "
                               "body's", path=path)
    dof = meta.get("dof", angles.shape[1])
    if isinstance(dof, bool) or not isinstance(dof, int):
        raise SkinnyInputError(f"meta dof must be a whole number, got {dof!r}", path=path)
    if dof != angles.shape[1]:
        raise SkinnyInputError(
            f"meta says dof={meta['dof']} but angles have {angles.shape[1]} columns", path=path
        )
    if not np.issubdtype(angles.dtype, np.number) or np.issubdtype(angles.dtype,
                                                                    np.complexfloating):
        raise SkinnyInputError(f"angles must be real numbers, got dtype {angles.dtype}",
                               path=path)
    bad = np.argwhere(~np.isfinite(angles))
    if len(bad):
        raise SkinnyInputError(f"non-finite angle at step {bad[0][0]}, DOF {bad[0][1]}", path=path)
    try:
        return Trajectory(angles, meta.get("dt", DEFAULT_DT_S), meta.get("name", path.stem),
                          desired, which)
    except (SkinnyInputError, TypeError, ValueError) as exc:  # e.g. "dt": "x" in meta
        raise SkinnyInputError(str(exc), path=path) from None


def _parse_comment(text: str) -> dict[str, str]:
    out = {}
    for part in text.lstrip("#").split(";"):
        if "=" in part:
            key, value = part.split("=", 1)
            out[key.strip()] = value.strip()
    return out


def _load_csv(path: Path) -> Trajectory:
    try:
        lines = path.read_text(encoding="utf-8-sig").splitlines()  # a spreadsheet's BOM
    except (OSError, UnicodeDecodeError) as exc:
        raise SkinnyInputError(f"cannot read ({exc})", path=path) from None
    meta: dict[str, str] = {}
    header: list[str] | None = None
    rows: list[list[float]] = []
    for lineno, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            meta.update(_parse_comment(line))
            continue
        cells = [c.strip() for c in line.split(",")]
        if header is None:
            header = cells
            which = meta.get("body") or (len(header) if len(header) in body.DOF_ALIASES
                                         else None)
            if which is None or tuple(header) != body_of(which).dof_names:
                raise SkinnyInputError(
                    f"header must be the DOF names of the body (2D: "
                    f"{list(body_of('2d').dof_names)}; or name it: # body=NAME), got {header}",
                    path=path,
                    line=lineno,
                )
            continue
        if len(cells) != len(header):
            raise SkinnyInputError(
                f"{len(cells)} columns, expected {len(header)}", path=path, line=lineno
            )
        try:
            values = [float(c) for c in cells]
        except ValueError:
            bad = next(c for c in cells if not _is_float(c))
            raise SkinnyInputError(f"not a number: {bad!r}", path=path, line=lineno) from None
        if not all(math.isfinite(v) for v in values):
            raise SkinnyInputError("NaN or infinite angle", path=path, line=lineno)
        rows.append(values)
    if header is None or not rows:
        raise SkinnyInputError("no header or no data rows", path=path)
    try:
        return Trajectory(np.array(rows), meta.get("dt", DEFAULT_DT_S), meta.get("name", path.stem),
                          body=meta.get("body"))
    except (SkinnyInputError, ValueError) as exc:
        raise SkinnyInputError(str(exc), path=path) from None


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def excerpt(traj: Trajectory, start_s: float, duration_s: float | None) -> Trajectory:
    """Steps of ``traj`` from ``start_s`` for ``duration_s`` seconds (both >= 0, inside;
    ``duration_s`` None: to the end)."""
    first = float(start_s) / traj.dt  # 1e308 s: inf steps, which int() cannot take
    steps = None if duration_s is None else float(duration_s) / traj.dt
    inside = math.isfinite(first) and (steps is None or math.isfinite(steps))
    start = int(round(first)) if inside else -1
    n = len(traj) - start if steps is None else int(round(steps)) if inside else 0
    if start < 0 or n < 1 or start + n > len(traj):
        what = "to the end" if duration_s is None else f"+ {duration_s:g} s"
        raise SkinnyInputError(
            f"excerpt {start_s:g} s {what} is outside {traj.name!r} "
            f"(0-{traj.duration_s:g} s)"
        )
    label = f"{start_s:g}s" if duration_s is None else f"{start_s:g}s+{duration_s:g}s"
    return traj._map(traj.angles[start : start + n], f"{traj.name}[{label}]",
                     lambda v: v[start : start + n])


def check_size(steps: int, n_dof: int, cause: str) -> None:
    """Refuse (one line) a movement of ``steps`` steps of ``n_dof`` angles the memory
    cannot hold: its angles, the interpolation's or tiling's copies, explicit desired
    signals (about 6 arrays)."""
    check(Estimate({"movement": steps * (n_dof + 1) * 8 * 6}, {"movement": cause}),
          "the movement")


def _check_desired(desired: dict | None, angles: np.ndarray, name: str,
                   skinny: Body) -> dict | None:
    """Explicit desired signals as read-only float arrays, or a SkinnyInputError."""
    if not desired:
        return None
    out = {}
    for key, value in dict(desired).items():
        if key not in body.SIGNALS:
            raise SkinnyInputError(f"trajectory {name!r}: unknown desired signals {key!r}")
        v = np.array(value, dtype=float)
        shape = (angles.shape[0], skinny.n_signals(key))
        if v.shape != shape or not np.all(np.isfinite(v)) \
                or np.any(np.abs(v) > MAX_ABS_ANGLE_RAD):
            raise SkinnyInputError(f"trajectory {name!r}: desired {key!r} signals must be "
                                   f"finite, at most {MAX_ABS_ANGLE_RAD:g} in magnitude, "
                                   f"shape {shape}; got shape {v.shape}")
        v.setflags(write=False)
        out[key] = v
    return out
