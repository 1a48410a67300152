"""Checks a command makes before any long work: can it write its output, can it render,
would it write over earlier results; and the new folder a run without ``--out`` writes.

Who is at fault decides the exit code. A path the user gave that cannot be used as given
(an ``--out`` that already holds results, a file where a folder is needed or the other way
round, a folder under a file) is input: :class:`~skinny_mj.errors.SkinnyInputError`, exit 2.
A machine that refuses a good path (read-only, no permission, full disk, no rendering
backend) is the environment: :class:`~skinny_mj.errors.SkinnyEnvironmentError`, exit 1.
Either is one line, raised before the training or the sweep starts rather than after it.

No run is lost in silence (:func:`check_run_folder`, :func:`check_new_file`,
:func:`new_folder`):

- an ``--out`` folder that holds files is refused unless ``--overwrite``, and even then
  unless it holds a run (:data:`RUN_FILES`): ``--overwrite`` replaces those files only, once
  the new run is computed, never a folder of other files;
- an ``--out`` file that exists is refused unless ``--overwrite``;
- without ``--out``, a run writes a folder made for it, ``results/<kind>/<UTC time>``,
  created with an exclusive ``mkdir``: a second run started in the same second gets
  ``<time>-2``, a third ``<time>-3``, and so on.

Memory: memory too small for a run is a :class:`~skinny_mj.errors.SkinnyInputError`
naming the parameter that makes it big (exit 2; :func:`check` against an :class:`Estimate`,
which the training, the engine and the command line make from the shapes they allocate).

Nothing here imports mujoco: :func:`check_gl` must run before the first import.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import errno
import itertools
import os
import shutil
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from skinny_mj.errors import SkinnyEnvironmentError, SkinnyInputError
from skinny_mj.io import atomic_write_bytes

__all__ = ["GL_BACKENDS", "GL_OFF", "MIN_FREE_BYTES", "RUN_FILES", "check_gl", "check_path_name",
           "check_writable", "check_writable_file", "check_free_space", "cleaned_on_failure",
           "check_run_folder", "check_new_file", "timestamp", "new_folder", "run_folder",
           "Estimate", "available_bytes", "check", "fmt_bytes"]

#: MUJOCO_GL values that turn rendering off (mujoco/rendering/classic/gl_context.py).
GL_OFF = ("disable", "disabled", "off", "false", "0")
#: MUJOCO_GL values mujoco accepts on Linux (the same file); any other value makes
#: ``import mujoco`` itself raise.
GL_BACKENDS = (*GL_OFF, "enable", "enabled", "on", "true", "1", "glfw", "", "glx", "egl",
               "osmesa")
#: Bytes the probe writes: enough to see a disk that is already full, not to fill one.
_PROBE_BYTES = 4096
#: Free space an output folder needs before a command starts (a run's JSON, model and
#: figures take < 1 MiB; a recording checks its own size with :func:`check_free_space`).
MIN_FREE_BYTES = 1 << 20


def check_gl() -> None:
    """Refuse a ``MUJOCO_GL`` that mujoco would refuse at import, with the valid values."""
    value = os.environ.get("MUJOCO_GL", "").lower().strip()
    if value not in GL_BACKENDS:
        raise SkinnyEnvironmentError(
            f"MUJOCO_GL={os.environ['MUJOCO_GL']!r} is not a rendering backend mujoco knows; "
            "use egl (GPU or Mesa EGL), osmesa (software) or glfw (a display), or "
            "unset it")


def check_writable(folder: str | Path) -> Path:
    """Check that ``folder`` (created later if missing) can take files, without creating it.

    Writes a small hidden probe file, through the same atomic write every result uses,
    into ``folder`` or its nearest existing ancestor, and removes it again.

    Raises
    ------
    SkinnyInputError
        If ``folder`` or an ancestor is a file (ENOTDIR): the path cannot be a folder.
    SkinnyEnvironmentError
        If the file system is read-only, the folder is not writable, or the disk is
        full; either message names the folder and the reason.
    """
    folder = check_path_name(folder)
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    try:
        if not existing.is_dir():
            raise NotADirectoryError(errno.ENOTDIR, os.strerror(errno.ENOTDIR), str(existing))
        probe = existing / f".skinny-write-probe-{os.getpid()}"
        atomic_write_bytes(probe, b"\0" * _PROBE_BYTES)
        probe.unlink()
        check_free_space(existing, MIN_FREE_BYTES)
    except SkinnyEnvironmentError:
        raise
    except OSError as exc:
        reason = exc.strerror or str(exc)
        error = SkinnyInputError if exc.errno == errno.ENOTDIR else SkinnyEnvironmentError
        raise error(f"cannot write the output folder {folder} ({reason}: {existing}); "
                    "choose another --out") from None
    return folder


def check_path_name(path: str | Path, option: str = "--out") -> Path:
    """Refuse a path no file system takes, as bad input naming ``option``: a NUL byte
    (``ValueError`` deep in ``os``), or a name longer than the file system allows
    (``ENAMETOOLONG``, which would otherwise read as a fault of the machine)."""
    text = os.fspath(path)
    if "\0" in str(text):
        raise SkinnyInputError(f"{option} {str(text)!r} holds a NUL byte; choose another name")
    path = Path(path)
    existing = path.absolute()
    while existing != existing.parent:
        try:
            if existing.exists():
                break
        except OSError:  # ENAMETOOLONG on the way up: the part names are checked below
            pass
        existing = existing.parent
    try:
        name_max = os.pathconf(existing, "PC_NAME_MAX")
    except (OSError, ValueError):
        name_max = 255
    long = [part for part in path.parts if len(os.fsencode(part)) > name_max]
    if long:
        raise SkinnyInputError(f"{option}: the name {long[0][:40]}... is "
                               f"{len(os.fsencode(long[0]))} bytes, more than the "
                               f"{name_max} the file system allows; choose a shorter name")
    return path


def check_writable_file(path: str | Path, option: str = "--out") -> Path:
    """Check that the file ``path`` can be written (its folder as :func:`check_writable`
    checks one, and ``path`` itself not a folder), before the work that makes it."""
    path = check_path_name(path, option)
    if path.is_dir():
        raise SkinnyInputError(f"{option} {path} is a folder; give a file name")
    check_writable(path.parent if str(path.parent) else Path("."))
    return path


@contextlib.contextmanager
def cleaned_on_failure(folder: str | Path) -> Iterator[Path]:
    """Write a command's files into ``folder`` inside this block: if the block raises,
    every file and folder it added to ``folder`` is removed again (and ``folder`` itself
    if the block created it), so a failed command leaves no half-written output. What
    was there before is kept."""
    folder = Path(folder)
    existed = folder.is_dir()
    before = {p.name for p in folder.iterdir()} if existed else set()
    try:
        yield folder
    except BaseException:
        if not existed:
            shutil.rmtree(folder, ignore_errors=True)
        elif folder.is_dir():
            for entry in folder.iterdir():
                if entry.name not in before:
                    if entry.is_dir() and not entry.is_symlink():
                        shutil.rmtree(entry, ignore_errors=True)
                    else:
                        entry.unlink(missing_ok=True)
        raise


def check_free_space(folder: str | Path, need_bytes: int) -> None:
    """Refuse to start a write of about ``need_bytes`` into ``folder`` (an existing
    directory) when the disk has less free: rerun's file writer can hang forever on a
    full disk (rerun 0.41: ``save`` never returns), so a recording looks first."""
    free = shutil.disk_usage(folder).free
    if free < need_bytes:
        raise SkinnyEnvironmentError(
            f"the disk holding {folder} is full: {free / 2**20:.2f} MiB free, "
            f"{need_bytes / 2**20:.2f} MiB needed; free some space or choose another --out")


#: The files a run writes (``skinny train``, ``demo``, ``test``, ``track``): a folder that
#: holds one of them holds a run, which ``--overwrite`` may replace.
RUN_FILES = ("metrics.json", "model.npz", "run.rrd", "learning_curve.png")


def _visible(folder: Path) -> list[str]:
    """The names in ``folder`` but hidden ones (``.DS_Store``, an atomic write's leftover)."""
    return sorted(p.name for p in folder.iterdir() if not p.name.startswith("."))


def check_run_folder(out: str | Path, overwrite: bool, option: str = "--out") -> Path:
    """Refuse (:class:`SkinnyInputError`) a run's output folder ``out`` that would lose
    results in silence: a file, a folder holding files (unless ``overwrite`` and they
    include a run's), see the module docstring."""
    out = check_path_name(out, option)
    if out.exists() and not out.is_dir():
        raise SkinnyInputError(f"{option} is a file, not a folder; choose a folder", path=out)
    entries = _visible(out) if out.is_dir() else []
    if not entries:
        return out
    if not set(entries) & set(RUN_FILES):
        raise SkinnyInputError(f"{option} is a folder that holds other files and no run; "
                               "choose a new or empty folder", path=out)
    if not overwrite:
        raise SkinnyInputError(f"{option} already holds a run; replace it with --overwrite, "
                               "or choose a new folder", path=out)
    return out


def check_new_file(path: str | Path, overwrite: bool, option: str = "--out") -> Path:
    """Refuse (:class:`SkinnyInputError`) an output file that exists, unless ``overwrite``;
    then check it can be written (:func:`check_writable_file`)."""
    path = check_path_name(path, option)
    if path.exists() and not path.is_dir() and not overwrite:
        raise SkinnyInputError(f"{option} already exists; replace it with --overwrite, or "
                               "choose another name", path=path)
    return check_writable_file(path, option)


def timestamp() -> str:
    """The current UTC time to the second, as a default folder's name: ``20261204-061500``."""
    return _dt.datetime.now(_dt.UTC).strftime("%Y%m%d-%H%M%S")


def new_folder(parent: str | Path, stamp: str | None = None) -> Path:
    """Make and return ``parent/<stamp>`` (default: :func:`timestamp` now), or
    ``<stamp>-2``, ``-3``, ... when another run already took it: each ``mkdir`` is
    exclusive, so two runs started in the same second (two processes, two machines on
    one shared disk) never share one."""
    parent = Path(parent)
    parent.mkdir(parents=True, exist_ok=True)
    stem = timestamp() if stamp is None else stamp
    for k in itertools.count(1):
        path = parent / (stem if k == 1 else f"{stem}-{k}")
        try:
            path.mkdir()
        except FileExistsError:
            continue
        return path
    raise AssertionError("unreachable")  # itertools.count never ends


@contextlib.contextmanager
def run_folder(out: str | Path | None, default_parent: str | Path, *,
               overwrite: bool = False, stamp: str | None = None) -> Iterator[Path]:
    """The folder a run writes its files into inside this block: ``out`` or, when None,
    a :func:`new_folder` under ``default_parent`` (named ``stamp``: the time the command
    started, or ``stamp-2``... if another run took that name since).

    Call it when the run is computed (the writes come last). ``out`` is checked again
    (:func:`check_run_folder`: another run may have written there since the command
    started); with ``overwrite`` the old run's :data:`RUN_FILES` are removed first, so a
    failed run never sits beside an older model. A block that raises leaves nothing
    (:func:`cleaned_on_failure`; a new folder is removed).
    """
    if out is None:
        path = new_folder(default_parent, stamp)
        try:
            yield path
        except BaseException:
            shutil.rmtree(path, ignore_errors=True)
            raise
        return
    out = check_run_folder(out, overwrite)
    if out.is_dir() and overwrite:
        for name in RUN_FILES:
            (out / name).unlink(missing_ok=True)
    with cleaned_on_failure(out) as path:
        yield path


# -- memory ------------------------------------------------------------------------------
def fmt_bytes(n: float) -> str:
    """``n`` bytes in the largest binary unit that keeps it >= 1 (``1.5 GiB``)."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(n) < 1024 or unit == "PiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.3g} {unit}" if n >= 1e4 \
                else f"{n:.1f} {unit}"
        n /= 1024
    raise AssertionError("unreachable")


@dataclass(frozen=True)
class Estimate:
    """Bytes a run (or a sweep) needs: ``parts`` (label -> bytes) and, per part, the
    parameter that makes it grow (``causes``: label -> e.g. ``"--reservoir 20000"``)."""

    parts: dict[str, int]
    causes: dict[str, str] = field(default_factory=dict)

    @property
    def total(self) -> int:
        return int(sum(self.parts.values()))

    @property
    def culprit(self) -> str:
        """The parameter behind the largest part."""
        label = max(self.parts, key=lambda k: self.parts[k])
        return self.causes.get(label, label)

    def scaled(self, factor: int, cause: str) -> Estimate:
        """``factor`` copies at once (e.g. parallel workers), ``cause`` added to each."""
        return Estimate({k: v * factor for k, v in self.parts.items()},
                        {k: f"{self.causes.get(k, k)}, {cause}" for k in self.parts})


def available_bytes() -> int | None:
    """Memory this process may still use: ``MemAvailable`` of ``/proc/meminfo`` (or
    psutil's ``available`` off Linux), lowered to a cgroup's headroom (``memory.max``
    less ``memory.current``, cgroup v2) where one is set; None if nothing says."""
    free: int | None = None
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                free = int(line.split()[1]) * 1024
                break
    except (OSError, ValueError, IndexError):
        free = None
    if free is None:
        try:
            import psutil

            free = int(psutil.virtual_memory().available)
        except Exception:  # no psutil, or it cannot read this system
            return None
    try:
        limit = Path("/sys/fs/cgroup/memory.max").read_text().strip()
        used = int(Path("/sys/fs/cgroup/memory.current").read_text().strip())
        if limit != "max":
            free = min(free, max(0, int(limit) - used))
    except (OSError, ValueError):
        pass
    return free


def check(estimate: Estimate, what: str, *, available: int | None = None,
          hint: str = "") -> None:
    """Refuse (:class:`SkinnyInputError`) when ``estimate`` exceeds the memory available.

    ``what`` names the run ("the training"); ``available`` defaults to
    :func:`available_bytes` (unknown: no check)."""
    free = available_bytes() if available is None else available
    if free is None or estimate.total <= free:
        return
    raise SkinnyInputError(
        f"{what} needs about {fmt_bytes(estimate.total)} of memory ({estimate.culprit}), "
        f"more than the {fmt_bytes(free)} available{'; ' + hint if hint else ''}")
