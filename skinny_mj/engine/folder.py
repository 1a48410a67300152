"""A sweep's output folder: which folder a sweep may write, and one sweep at a time in it.

- :func:`choose_out_dir`: ``--resume`` needs ``--out`` naming an existing sweep folder
  (one with a ``config.json``); a new sweep needs an empty or new folder, or
  ``--overwrite`` to replace an old sweep's (never a folder that holds no sweep);
- :func:`sweep_lock`: the file ``sweep.lock`` (JSON: pid, host, start time) held while a
  sweep runs; a second sweep into the same folder is refused naming the holder. A lock
  whose process is gone (same host, pid not running, or running since another time: the
  pid was reused) is stale: it is taken over with a warning saying so.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import json
import logging
import os
import shutil
import socket
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from skinny_mj.engine.stats import to_jsonable
from skinny_mj.engine.sweep import SEEDING
from skinny_mj.errors import SkinnyInputError
from skinny_mj.io import atomic_write_json

__all__ = ["LOCK_NAME", "config_dict", "prepare_out_dir", "choose_out_dir",
           "clear_sweep", "check_unlocked", "sweep_lock", "read_lock"]

LOCK_NAME = "sweep.lock"
_log = logging.getLogger(__name__)


def config_dict(experiment: Any, runs: int) -> dict[str, Any]:
    """What ``config.json`` records of ``experiment`` (see :mod:`skinny_mj.engine.experiment`)."""
    return to_jsonable({
        "experiment": experiment.name,
        "config": experiment.to_dict(),
        "rows": [{"row": r.id, "params": r.settings, "paper": dict(r.paper),
                  **{k: getattr(r, k) for k in ("runs", "seeds_of") if getattr(r, k) is not None}}
                 for r in experiment.rows],
        "groups": {g: list(m) for g, m in experiment.groups.items()},
        "runs": runs,
        "base_seed": experiment.base_seed,
        "seeding": SEEDING,
    })


def prepare_out_dir(experiment: Any, out_dir: Path, runs: int, resume: bool,
                    invocation: dict[str, Any]) -> None:
    """Write ``out_dir/config.json``, or on ``resume`` check it holds the same sweep and
    add this resume to its ``resumes``."""
    config = config_dict(experiment, runs)
    config_path = out_dir / "config.json"
    now = _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")
    if resume and config_path.is_file():
        try:
            old = json.loads(config_path.read_text())
            same = {k: old.get(k) for k in ("experiment", "config", "rows", "base_seed",
                                             "seeding")}
        except (ValueError, AttributeError) as exc:
            raise SkinnyInputError(f"not a sweep's config.json ({exc})",
                                   path=config_path) from exc
        if same != {k: config[k] for k in same}:
            raise SkinnyInputError(_difference(same, config), path=config_path)
        old["resumes"] = [*old.get("resumes", []), {"at": now, **invocation}]
        atomic_write_json(config_path, to_jsonable(old))
        return
    config.update(invocation, started_at=now, python=sys.version.split()[0],
                  numpy=np.__version__, resumes=[])
    atomic_write_json(config_path, to_jsonable(config))


#: What each recorded key of a sweep's config.json is, in a refusal to resume it.
_WHAT = {"config": "config (--quick, --movement, --body, --signals, --protocol)",
         "rows": "rows (--rows, --quick)", "base_seed": "seed",
         "seeding": "seeding (this version seeds a run by its row's id, not its position)"}


def _difference(old: dict[str, Any], new: dict[str, Any]) -> str:
    """Why ``--resume`` refuses a folder: the study it holds, or what of its sweep differs."""
    if old["experiment"] != new["experiment"]:
        how = ("skinny sweep KEY=V1,V2 --resume" if old["experiment"] == "sweep"
               else f"skinny experiment {old['experiment']} --resume")
        return (f"holds a sweep of experiment {old['experiment']!r}, not "
                f"{new['experiment']!r}; resume it with `{how}`, or use a new --out")
    differ = [_WHAT[k] for k in _WHAT if old[k] != new[k]]
    return (f"holds a different sweep of {new['experiment']!r}: its {' and '.join(differ)} "
            "differ; resume it with the options it was started with, or use a new --out")


def _entries(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name != LOCK_NAME)


def choose_out_dir(out: str | Path | None, default: Path | None, *, resume: bool,
                   overwrite: bool) -> Path | None:
    """The folder a ``skinny experiment`` writes, refused (:class:`SkinnyInputError`)
    before any run when it would lose results in silence; see the module docstring.
    Without ``out``: ``default`` (None: the caller makes a new folder when the sweep
    starts, :func:`skinny_mj.engine.experiment.default_out_dir`)."""
    if resume and overwrite:
        raise SkinnyInputError("give --resume (continue the sweep in --out) or --overwrite "
                               "(replace it), not both")
    if out is None:
        if resume:
            raise SkinnyInputError("--resume needs --out, the folder of the sweep to resume")
        return default
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise SkinnyInputError("--out is a file, not a folder", path=out)
    if out.is_dir():  # a running sweep is named before anything else is said of its folder
        check_unlocked(out)
    is_sweep = (out / "config.json").is_file()
    if resume:
        if not is_sweep:
            raise SkinnyInputError("--resume: not a sweep's folder (no config.json); give "
                                   "the --out of the sweep to continue", path=out)
        return out
    if out.is_dir() and _entries(out):
        if not is_sweep:
            raise SkinnyInputError("--out is a folder that holds other files and no sweep; "
                                   "choose a new or empty folder", path=out)
        if not overwrite:
            raise SkinnyInputError("--out already holds a sweep; continue it with --resume, "
                                   "replace it with --overwrite, or choose a new folder",
                                   path=out)
    return out


def clear_sweep(out: Path) -> None:
    """Remove everything in the sweep folder ``out`` but its lock (``--overwrite``)."""
    for entry in out.iterdir():
        if entry.name == LOCK_NAME:
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry)
        else:
            entry.unlink()


def _start_ticks(pid: int) -> str | None:
    """A process's start time in clock ticks since boot (``/proc/PID/stat`` field 22),
    None where unknown: with the pid it tells a reused pid from the lock's holder."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
        return stat.rsplit(")", 1)[1].split()[19]
    except (OSError, IndexError):
        return None


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process: it exists
        return True
    except (OverflowError, ValueError):
        return False
    return True


def read_lock(path: Path) -> dict[str, Any] | None:
    """The lock file's holder, or None if it cannot be read (being written, damaged)."""
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def _holder_line(holder: dict[str, Any] | None) -> str:
    if holder is None:
        return "a sweep whose lock file cannot be read"
    return (f"pid {holder.get('pid')} on {holder.get('host')}, started "
            f"{holder.get('started_at')}")


def _stale(holder: dict[str, Any] | None) -> bool:
    """True when the holder ran on this host and is gone (or its pid was reused)."""
    if holder is None or holder.get("host") != socket.gethostname():
        return False
    pid = holder.get("pid")
    if not isinstance(pid, int) or isinstance(pid, bool):
        return False
    if not _alive(pid):
        return True
    ticks = holder.get("start_ticks")
    return ticks is not None and _start_ticks(pid) not in (None, ticks)


def check_unlocked(out: Path) -> None:
    """Refuse now (before any estimate or run) a folder another live sweep holds."""
    path = Path(out) / LOCK_NAME
    if path.exists():
        holder = read_lock(path)
        if not _stale(holder) and not _mine(holder):
            raise _held(path, holder)


def _mine(holder: dict[str, Any] | None) -> bool:
    return holder is not None and holder.get("pid") == os.getpid() \
        and holder.get("host") == socket.gethostname()


def _held(path: Path, holder: dict[str, Any] | None) -> SkinnyInputError:
    return SkinnyInputError(
        f"another sweep is running in this folder ({_holder_line(holder)}); wait for it, "
        f"or delete {path.name} if that sweep is gone", path=path)


def _acquire(path: Path) -> bool:
    """Create the lock ``path`` (True), or find it this process's own (False); a stale
    lock is replaced with a warning (logging), a live one refused."""
    me = {"pid": os.getpid(), "host": socket.gethostname(),
          "started_at": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
          "start_ticks": _start_ticks(os.getpid())}
    for _attempt in range(2):
        try:
            fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            holder = read_lock(path)
            if _mine(holder):
                return False
            if not _stale(holder):
                raise _held(path, holder) from None
            _log.warning("removed a stale lock (%s; that process is no longer running): %s",
                         _holder_line(holder), path)
            path.unlink(missing_ok=True)
            continue
        with os.fdopen(fd, "w") as f:
            json.dump(me, f)
        return True
    raise _held(path, read_lock(path))  # another sweep took the stale lock first


@contextlib.contextmanager
def sweep_lock(out: str | Path) -> Iterator[Path]:
    """Hold ``out/sweep.lock`` while the block runs (creating ``out``); a lock this
    process already holds is kept (nested use); a stale one is replaced, with a
    warning (logging)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / LOCK_NAME
    acquired = _acquire(path)
    try:
        yield out
    finally:
        if acquired and _mine(read_lock(path)):
            path.unlink(missing_ok=True)
