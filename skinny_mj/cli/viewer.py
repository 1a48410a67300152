"""``skinny view``: open recordings in the rerun viewer (native, or the web viewer).

The viewer is rerun's own ``rerun`` executable (shipped in the ``rerun-sdk`` wheel); this
module only finds the recordings, builds its command line and decides whether it can be
shown here. Without a display (no ``DISPLAY`` / ``WAYLAND_DISPLAY`` on Linux) the native
viewer cannot open, so the command is printed for the user to run where there is one.
The native viewer's gRPC server, and the web viewer with its gRPC data server, are bound
to 127.0.0.1 (rerun's own default is 0.0.0.0, every interface): only this machine can
connect unless the user tunnels a port or asks for another address (``--bind``).

:func:`screenshot` (``skinny view --screenshot``) drives a headless viewer (rerun's own
offscreen mode: no window, no display, no pointer) through rerun's viewer-control API: it
waits until the recording has loaded, pauses the time cursor at a given time and saves the
first frame that no longer changes.
"""

from __future__ import annotations

import ipaddress
import math
import os
import shlex
import shutil
import signal
import socket
import struct
import subprocess
import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

from skinny_mj.errors import SkinnyEnvironmentError, SkinnyInputError
from skinny_mj.io import atomic_write_bytes
from skinny_mj.preflight import check_writable_file

__all__ = ["find_recordings", "has_display", "viewer_command", "view", "cmd_view",
           "screenshot", "vulkan_drivers"]

#: Address the viewers and their gRPC servers listen on unless ``bind`` says otherwise.
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
        check_rrd(path)
        return [path]
    if not path.is_dir():
        raise SkinnyInputError("no such recording or results folder", path=path)
    found = sorted(p for p in path.rglob("*.rrd")
                   if p.is_file() and not any(part.startswith(".")
                                              for part in p.relative_to(path).parts))
    if not found:
        raise SkinnyInputError("holds no .rrd recording", path=path)
    for rrd in found:
        check_rrd(rrd)
    return found


#: An .rrd stream's header: magic (``RRF`` and a format digit), the writer's version, and
#: options (compression, serializer); then, with the protobuf serializer (2), messages of a
#: (kind, length) u64 header and their bytes, up to an End message (kind 0).
_RRD_HEADER = 12
_PROTOBUF = 2


def check_rrd(path: Path) -> None:
    """Refuse a file the viewer would fail on later, in its own window or log: an empty
    or truncated ``.rrd``, or one that is no rerun recording at all. Only what the file's
    framing shows is checked (no decoding); a stream of another serializer passes."""
    try:
        with path.open("rb") as fh:
            head = fh.read(_RRD_HEADER)
            if len(head) < _RRD_HEADER or not head.startswith(b"RRF"):
                what = "empty" if not head else "not a rerun recording (no RRF header)"
                raise SkinnyInputError(f"{what}; write one with skinny train, test, track "
                                       "or experiment", path=path)
            if head[9] != _PROTOBUF:
                return
            size, offset = path.stat().st_size, _RRD_HEADER
            while offset + 16 <= size:
                fh.seek(offset)
                kind, length = struct.unpack("<QQ", fh.read(16))
                offset += 16 + length
                if kind == 0:  # End
                    return
            if offset > size:
                raise SkinnyInputError(f"truncated recording: a message runs past the end of "
                                       f"the file ({size} bytes)", path=path)
    except OSError as err:
        raise SkinnyInputError(f"cannot read the recording ({err.strerror or err})",
                               path=path) from None


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


def check_bind(address: str) -> str:
    """``address`` if it is an IPv4 or IPv6 address, else :class:`SkinnyInputError`."""
    try:
        return str(ipaddress.ip_address(address))
    except ValueError:
        raise SkinnyInputError(f"--bind must be an IP address such as 127.0.0.1 or 0.0.0.0, "
                               f"got {address!r}") from None


def viewer_command(recordings: Sequence[Path], *, web: bool = False,
                   web_port: int = DEFAULT_WEB_PORT, grpc_port: int = DEFAULT_GRPC_PORT,
                   bind: str = BIND_ADDRESS,
                   executable: Sequence[str] | None = None) -> list[str]:
    """The ``rerun`` command line that opens ``recordings``.

    Parameters
    ----------
    recordings : the ``.rrd`` files to open.
    web : serve the web viewer (HTTP on ``web_port``, data over gRPC on ``grpc_port``)
        instead of opening a native window.
    web_port : HTTP port for ``web``.
    grpc_port : the viewer's gRPC server (native or web); a native viewer already
        listening there is handed the recordings instead (rerun's own behaviour).
    bind : address the servers listen on.
    executable : the viewer program (default: ``rerun`` on PATH, else ``python -m rerun``).
    """
    cmd = list(executable) if executable is not None else _rerun_executable()
    cmd += ["--bind", check_bind(bind), "--port", str(grpc_port)]
    if web:
        cmd += ["--web-viewer", "--web-viewer-port", str(web_port)]
    return cmd + [str(p) for p in recordings]


def view(path: str | Path, *, web: bool = False, web_port: int = DEFAULT_WEB_PORT,
         grpc_port: int = DEFAULT_GRPC_PORT, bind: str = BIND_ADDRESS,
         dry_run: bool = False) -> int:
    """Open the recordings under ``path`` (see :func:`find_recordings`) and wait for the
    viewer to close; headless (and not ``web``) or with ``dry_run``, print the command
    instead. Returns the exit code for ``skinny view``."""
    if web and web_port == grpc_port:  # else rerun's own error, several lines, exit 1
        raise SkinnyInputError(f"--web-port {web_port} and --grpc-port {grpc_port} are one "
                               "port: the web page and its data need two")
    recordings = find_recordings(path)
    cmd = viewer_command(recordings, web=web, web_port=web_port, grpc_port=grpc_port,
                         bind=bind)
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
        ip = ipaddress.ip_address(bind)
        host = BIND_ADDRESS if ip.is_unspecified else f"[{ip}]" if ip.version == 6 else bind
        scope = "this machine only" if ip.is_loopback else "other machines can connect"
        print(f"serving {len(recordings)} recording(s) at http://{host}:{web_port} "
              f"({scope}; Ctrl-C stops)", file=sys.stderr)
    try:
        return subprocess.run(cmd, stdin=subprocess.DEVNULL).returncode
    except OSError as err:  # the wheel's viewer binary is missing: an environment fault
        print(f"skinny view: error: cannot start the rerun viewer ({err})", file=sys.stderr)
        return 1


def _free_port() -> int:
    with socket.socket() as s:
        s.bind((BIND_ADDRESS, 0))
        return s.getsockname()[1]


def _until(deadline: float, what: str, proc: subprocess.Popen, probe):
    """Call ``probe()`` until it returns something other than None (its failures and
    rerun's 15 s control timeouts retried) or ``deadline``; the viewer must keep running."""
    last: Exception | None = None
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise SkinnyEnvironmentError(f"the rerun viewer exited ({proc.returncode}) "
                                         f"while {what}")
        try:
            found = probe()
        except (OSError, RuntimeError, ValueError) as exc:  # not up yet / busy: retry
            found, last = None, exc
        if found is not None:
            return found
        time.sleep(0.5)
    raise SkinnyEnvironmentError(f"timed out {what}" + (f" ({last})" if last else ""))


#: Why a screenshot cannot be taken here, and what to install (Debian/Ubuntu package names).
NO_VULKAN = ("no Vulkan driver found, which the headless rerun viewer draws with: install "
             "your GPU's Vulkan driver, or Mesa's software one (Debian/Ubuntu package "
             "mesa-vulkan-drivers)")


def vulkan_drivers(environ: Mapping[str, str] | None = None) -> list[Path]:
    """The Vulkan driver manifests (ICD ``*.json``) the Vulkan loader finds on Linux:
    those ``VK_DRIVER_FILES`` / ``VK_ICD_FILENAMES`` name, else the ``vulkan/icd.d``
    folders of ``XDG_CONFIG_DIRS``, ``/etc``, ``XDG_DATA_DIRS``, ``/usr/local/share`` and
    ``/usr/share``. Elsewhere (macOS, Windows: drivers come with the system) ``[]``."""
    env = os.environ if environ is None else environ
    if not sys.platform.startswith("linux"):
        return []
    named = env.get("VK_DRIVER_FILES") or env.get("VK_ICD_FILENAMES")
    if named:
        return [Path(p) for p in named.split(os.pathsep) if Path(p).exists()]
    roots = [*env.get("XDG_CONFIG_DIRS", "/etc/xdg").split(os.pathsep), "/etc",
             *env.get("XDG_DATA_DIRS", "/usr/local/share:/usr/share").split(os.pathsep),
             "/usr/local/share", "/usr/share"]
    return sorted({p for root in roots if root
                   for p in Path(root, "vulkan", "icd.d").glob("*.json")})


def screenshot(recording: str | Path, png: str | Path, *, at_s: float,
               views: Sequence[str] = (), window: str = "1600x1000",
               timeout_s: float = 300.0) -> dict[str, Path]:
    """Save a screenshot of the viewer showing ``recording`` at ``at_s`` seconds (and one
    of each view named in ``views``), as the native viewer draws it in a ``window``
    (width x height) window.

    ``rerun --screenshot-to`` takes its picture ten frames after start, whatever has
    loaded by then, with the time cursor wherever playback (or following the data still
    arriving) has put it. Here a fresh headless viewer (``rerun --headless`` on a free
    port of 127.0.0.1: no window, so no pointer hovering over a plot and no window
    manager) is driven through rerun's viewer-control API: open the file, wait until
    nothing is loading and the ``time`` timeline is known, pause the cursor at ``at_s``,
    then take screenshots until two in a row are identical (every chunk the views need
    has arrived and been drawn). The viewer logs errors only (``RUST_LOG=error``), so its
    warnings (software rasterizer, Docker) raise no notification over the views; the one
    it always shows, its gRPC address, is gone from the headless viewer within 2 s.

    Returns ``{"window": png, view name: png's name + "-<i>" for the i-th of views}``.

    Raises
    ------
    SkinnyEnvironmentError
        No Vulkan driver (Linux), or the viewer failed or timed out.
    SkinnyInputError
        A name in ``views`` is no view of the recording.
    """
    recording, png = Path(recording).resolve(), Path(png)
    if sys.platform.startswith("linux") and not vulkan_drivers():
        raise SkinnyEnvironmentError(NO_VULKAN)
    port = _free_port()
    cmd = _rerun_executable() + ["--bind", BIND_ADDRESS, "--port", str(port),
                                 "--window-size", window, "--hide-welcome-screen",
                                 "--headless"]
    proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True,
                            env={**os.environ, "RUST_LOG": "error"})
    deadline = time.monotonic() + timeout_s
    try:
        client = _until(deadline, "starting the viewer", proc, lambda: _connected(port))
        client.open(str(recording))

        def loaded():
            state = client.get_state()
            recs = [r for r in state.recordings if r.store_id == state.active_recording]
            ends = [t.end for r in recs for t in r.timelines if t.name == "time"]
            return ends[0] if not state.loading and ends and ends[0] is not None else None

        end_ns = _until(deadline, f"loading {recording}", proc, loaded)
        at_ns, shots = round(at_s * 1e9), []
        if not 0 <= at_ns <= end_ns:
            raise SkinnyInputError(f"the time {at_s:g} s is outside the recording "
                                   f"(0 .. {end_ns / 1e9:g} s)", path=recording)
        client.set_time("time", duration=at_s, play_state="paused")

        def stable():
            state = client.get_state()
            cursor = [r.current_time for r in state.recordings
                      if r.store_id == state.active_recording]
            if cursor != [at_ns]:
                raise RuntimeError(f"time cursor at {cursor} ns, not {at_ns}")
            scratch = png.with_name(f".{png.stem}.{len(shots)}.png")
            shots.append(_saved_screenshot(client, scratch, deadline, proc))
            return shots[-1] if len(shots) > 1 and shots[-1] == shots[-2] else None

        images = {"window": _until(deadline, "waiting for a frame that stops changing",
                                   proc, stable)}
        ids = {v.name: v.view_id for v in client.get_state().views}
        for name in views:
            if name not in ids:
                raise SkinnyInputError(f"no view {name!r} (views: {sorted(ids)})")
            images[name] = _saved_screenshot(client, png.with_name(f".{png.stem}.v.png"),
                                             deadline, proc, ids[name])
    except SkinnyEnvironmentError as err:
        if proc.poll() is not None:  # crashed: most often no working graphics adapter
            raise SkinnyEnvironmentError(f"{err}; it needs a working Vulkan driver, such as "
                                         "Mesa's (Debian/Ubuntu package mesa-vulkan-drivers)"
                                         ) from None
        raise
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGTERM)
        proc.wait(timeout=30)
    png.parent.mkdir(parents=True, exist_ok=True)
    names = {"window": png} | {v: png.with_name(f"{png.stem}-{i}{png.suffix}")
                               for i, v in enumerate(views)}
    return {k: atomic_write_bytes(names[k], image) for k, image in images.items()}


def _saved_screenshot(client, path: Path, deadline: float, proc: subprocess.Popen,
                      view_id: str | None = None) -> bytes:
    """One screenshot through ``path`` (then removed). On a slow software renderer a frame
    can take longer than the 15 s rerun's control calls wait for; the viewer still saves
    it, so a timed-out request is followed by waiting for the file."""
    from PIL import Image

    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        client.save_screenshot(str(path.resolve()), view_id=view_id)
    except TimeoutError:
        pass

    def whole():
        with Image.open(path) as img:  # raises until the viewer has written all of it
            img.load()
        return path.read_bytes()

    try:
        return _until(deadline, "waiting for the screenshot file", proc, whole)
    finally:
        path.unlink(missing_ok=True)


def _connected(port: int):
    from rerun.experimental import ViewerClient

    client = ViewerClient.connect(f"rerun+http://{BIND_ADDRESS}:{port}/proxy")
    client.get_state()  # raises until the viewer answers
    return client


def cmd_view(args) -> int:
    """The ``skinny view`` handler (:mod:`skinny_mj.cli.parser` parses its arguments)."""
    if getattr(args, "screenshot", None) is not None:
        return _cmd_screenshot(args)
    return view(args.path, web=args.web, web_port=args.web_port, grpc_port=args.grpc_port,
                bind=getattr(args, "bind", BIND_ADDRESS), dry_run=args.dry_run)


def _cmd_screenshot(args) -> int:
    """``skinny view --screenshot OUT.png RUN``: the viewer's picture of one recording."""
    out = Path(args.screenshot)
    if not math.isfinite(args.at) or args.at < 0:
        raise SkinnyInputError(f"--at must be a time >= 0 s, got {args.at:g}")
    if args.web or args.dry_run:
        raise SkinnyInputError("--screenshot takes neither --web nor --dry-run")
    if out.suffix.lower() != ".png":
        raise SkinnyInputError(f"--screenshot writes a PNG: give a name ending in .png, "
                               f"got {out}")
    recordings = find_recordings(args.path)
    if len(recordings) > 1:
        raise SkinnyInputError(f"holds {len(recordings)} recordings; --screenshot takes "
                               f"one: name its .rrd", path=args.path)
    check_writable_file(out, "--screenshot")
    path = screenshot(recordings[0], out, at_s=args.at)["window"]
    print(f"wrote {path}")
    return 0
