"""Checks a command makes before any long work: can it write its output, can it render,
does the machine have the memory it needs.

Each failure is a :class:`~skinny_mj.errors.SkinnyEnvironmentError` (the CLI prints one
line and exits 1), raised before the training or the sweep starts rather than after it;
memory too small for a run is a :class:`~skinny_mj.errors.SkinnyInputError` naming the
parameter that makes it big (exit 2; :func:`check` against an :class:`Estimate`, which the
training, the engine and the command line make from the shapes they allocate).
Nothing here imports mujoco: :func:`check_gl` must run before the first import.
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from skinny_mj.errors import SkinnyEnvironmentError, SkinnyInputError
from skinny_mj.io import atomic_write_bytes

__all__ = ["GL_BACKENDS", "MIN_FREE_BYTES", "check_gl", "check_writable", "check_writable_file",
           "check_free_space", "cleaned_on_failure", "Estimate", "available_bytes", "check",
           "fmt_bytes"]

#: MUJOCO_GL values mujoco accepts on Linux (mujoco/rendering/classic/gl_context.py);
#: any other value makes ``import mujoco`` itself raise.
GL_BACKENDS = ("disable", "disabled", "off", "false", "0", "enable", "enabled", "on",
               "true", "1", "glfw", "", "glx", "egl", "osmesa")
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
    SkinnyEnvironmentError
        If an ancestor is a file (ENOTDIR), the file system is read-only, the folder is
        not writable, or the disk is full; the message names the folder and the reason.
    """
    folder = Path(folder)
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
        raise SkinnyEnvironmentError(
            f"cannot write the output folder {folder} ({reason}: {existing}); "
            "choose another --out") from None
    return folder


def check_writable_file(path: str | Path, option: str = "--out") -> Path:
    """Check that the file ``path`` can be written (its folder as :func:`check_writable`
    checks one, and ``path`` itself not a folder), before the work that makes it."""
    path = Path(path)
    if path.is_dir():
        raise SkinnyEnvironmentError(f"{option} {path} is a folder; give a file name")
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


# -- memory ------------------------------------------------------------------------------
def fmt_bytes(n: float) -> str:
    """``n`` bytes in the largest binary unit that keeps it >= 1 (``1.5 GiB``)."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(n) < 1024 or unit == "PiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
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
