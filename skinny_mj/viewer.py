"""``skinny view``: open recordings in the rerun viewer (native, or the web viewer).

The viewer is rerun's own ``rerun`` executable (shipped in the ``rerun-sdk`` wheel); this
module only finds the recordings, builds its command line and decides whether it can be
shown here. Without a display (no ``DISPLAY`` / ``WAYLAND_DISPLAY`` on Linux) the native
viewer cannot open, so the command is printed for the user to run where there is one.
The web viewer and its gRPC data server are bound to 127.0.0.1 (rerun's own default is
0.0.0.0, every interface): only this machine can connect unless the user tunnels a port.
"""

from __future__ import annotations

import os
import shlex
import shutil
import subprocess
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path

from skinny_mj.errors import SkinnyInputError

__all__ = ["find_recordings", "has_display", "viewer_command", "view", "cmd_view"]

#: Address the web viewer and its gRPC server listen on (never every interface).
BIND_ADDRESS = "127.0.0.1"
DEFAULT_WEB_PORT = 9090
DEFAULT_GRPC_PORT = 9876


def find_recordings(path: str | Path) -> list[Path]:
    """The ``.rrd`` files ``path`` names: the file itself, or every recording under a
    folder (a run's ``run.rrd``, a sweep's ``*.rrd``), sorted, hidden files (atomic-write
    leftovers) left out.

    Raises
    ------
    SkinnyInputError
        ``path`` does not exist, is not an ``.rrd`` file, or holds no recording.
    """
    path = Path(path)
    if path.is_file():
        if path.suffix.lower() != ".rrd":
            raise SkinnyInputError("not a rerun recording (.rrd)", path=path)
        return [path]
    if not path.is_dir():
        raise SkinnyInputError("no such recording or results folder", path=path)
    found = sorted(p for p in path.rglob("*.rrd")
                   if p.is_file() and not any(part.startswith(".")
                                              for part in p.relative_to(path).parts))
    if not found:
        raise SkinnyInputError("holds no .rrd recording", path=path)
    return found


def has_display(environ: Mapping[str, str] | None = None) -> bool:
    """Whether a native window can open: always on macOS and Windows; on Linux and
    other X11/Wayland systems only with ``DISPLAY`` or ``WAYLAND_DISPLAY`` set."""
    env = os.environ if environ is None else environ
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(env.get("DISPLAY") or env.get("WAYLAND_DISPLAY"))


def _rerun_executable() -> list[str]:
    # The wheel's console script may be off PATH (a venv not activated): its module works.
    return ["rerun"] if shutil.which("rerun") else [sys.executable, "-m", "rerun"]


def viewer_command(recordings: Sequence[Path], *, web: bool = False,
                   web_port: int = DEFAULT_WEB_PORT, grpc_port: int = DEFAULT_GRPC_PORT,
                   executable: Sequence[str] | None = None) -> list[str]:
    """The ``rerun`` command line that opens ``recordings``.

    Parameters
    ----------
    recordings : the ``.rrd`` files to open.
    web : serve the web viewer (HTTP on ``web_port``, data over gRPC on ``grpc_port``),
        bound to :data:`BIND_ADDRESS`, instead of opening a native window.
    web_port, grpc_port : TCP ports for ``web``.
    executable : the viewer program (default: ``rerun`` on PATH, else ``python -m rerun``).
    """
    cmd = list(executable) if executable is not None else _rerun_executable()
    if web:
        cmd += ["--web-viewer", "--bind", BIND_ADDRESS, "--web-viewer-port", str(web_port),
                "--port", str(grpc_port)]
    return cmd + [str(p) for p in recordings]


def view(path: str | Path, *, web: bool = False, web_port: int = DEFAULT_WEB_PORT,
         grpc_port: int = DEFAULT_GRPC_PORT, dry_run: bool = False) -> int:
    """Open the recordings under ``path`` (see :func:`find_recordings`) and wait for the
    viewer to close; headless (and not ``web``) or with ``dry_run``, print the command
    instead. Returns the exit code for ``skinny view``."""
    recordings = find_recordings(path)
    cmd = viewer_command(recordings, web=web, web_port=web_port, grpc_port=grpc_port)
    line = shlex.join(cmd)
    if dry_run:
        print(line)
        return 0
    if not web and not has_display():
        print(f"no display here (DISPLAY is not set): on a machine with one, run\n  {line}\n"
              f"or serve the web viewer from here with: skinny view {shlex.quote(str(path))}"
              " --web")
        return 0
    if web:
        print(f"serving {len(recordings)} recording(s) at http://{BIND_ADDRESS}:{web_port} "
              f"(this machine only; Ctrl-C stops)", file=sys.stderr)
    try:
        return subprocess.run(cmd, stdin=subprocess.DEVNULL).returncode
    except OSError as err:  # the wheel's viewer binary is missing: an environment fault
        print(f"skinny view: error: cannot start the rerun viewer ({err})", file=sys.stderr)
        return 1


def cmd_view(args) -> int:
    """The ``skinny view`` handler (:mod:`skinny_mj.cli` parses its arguments)."""
    return view(args.path, web=args.web, web_port=args.web_port, grpc_port=args.grpc_port,
                dry_run=args.dry_run)
