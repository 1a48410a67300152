"""``skinny view`` and the saved blueprint, looked at as a person would: a screenshot of
the native rerun viewer under Xvfb (Debian ``xvfb`` + ``mesa-vulkan-drivers``; ``.ci/run``
installs them), checked from its pixels."""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from skinny_mj import recording_layout as layout
from skinny_mj import trajectories
from skinny_mj.cli import viewer
from skinny_mj.cli.parser import main
from skinny_mj.plant import body
from skinny_mj.recording import ACTUAL_RGB, DESIRED_RGB, write_recording


def _write_run(path: Path, dof: int, torque: bool = False) -> Path:
    """A run of YMCA whose actual arms lag the desired ones by 0.2 s (two arm colours);
    ``torque``: with torques as the torque body records them, each joint's applied torque
    a sine of a tenth to a quarter of its limit (small beside the limits)."""
    traj = trajectories.get("ymca", dof)
    lag = np.concatenate([np.repeat(traj.angles[:1], 10, axis=0), traj.angles[:-10]])
    desired = traj.position_signals("cartesian")
    commands = np.clip(np.diff(lag, axis=0) * 5.0, -1.0, 1.0)
    actual = desired.copy()
    actual[10:] = desired[:-10]
    torques = None
    if torque:
        t = np.arange(len(lag))[:, None] * body.CONTROL_DT_S
        k = np.arange(dof)[None, :]
        limit = np.where(k[0] % (dof // 2) == dof // 2 - 1, 40.0, 80.0)  # elbows weaker
        applied = limit * (0.1 + 0.15 * k / dof) * np.sin(2 * np.pi * t * (0.3 + 0.1 * k) + k)
        commands = applied[:-1] / limit
        torques = {"commanded_nm": applied[:-1], "applied_nm": applied[:-1],
                   "gravity_nm": 0.05 * limit * np.cos(2 * np.pi * 0.2 * t + k),
                   "limit_nm": limit}
    return write_recording(
        path, dt=body.CONTROL_DT_S, dof=dof, dof_names=list(body.dof_names(dof)),
        signal_names=list(body.signal_names(dof, "cartesian")), desired_angles=traj.angles,
        actual_angles=lag, commands=commands, desired_signals=desired, actual_signals=actual,
        title=f"viewer test, {dof} DOF" + (", torque" if torque else ""),
        curves={"train_position_nrmse": np.geomspace(1, .1, 5)}, torques=torques)


@pytest.fixture(scope="module")
def run_3d(tmp_path_factory) -> Path:
    return _write_run(tmp_path_factory.mktemp("view") / "sweep" / "row-1" / "run.rrd", 8)


def test_view_headless_prints_the_command(run_3d, monkeypatch, capsys):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    folder = run_3d.parents[1]
    (folder / ".hidden.rrd.tmp").write_bytes(b"")  # an atomic-write leftover: not a recording
    assert main(["view", str(folder)]) == 0
    out = capsys.readouterr().out
    assert "no display" in out and f"rerun --bind 127.0.0.1 --port 9876 {run_3d}" in out
    assert ".hidden" not in out


@pytest.mark.parametrize("web", [[], ["--web"]])
def test_view_command_binds_localhost(run_3d, capsys, web):
    assert main(["view", str(run_3d), *web, "--dry-run", "--web-port", "9123",
                 "--grpc-port", "9124"]) == 0
    cmd = capsys.readouterr().out.split()
    assert cmd[cmd.index("--bind") + 1] == "127.0.0.1" and "0.0.0.0" not in cmd
    assert cmd[cmd.index("--port") + 1] == "9124" and cmd[-1] == str(run_3d)
    assert ("--web-viewer" in cmd) == bool(web)
    if web:
        assert cmd[cmd.index("--web-viewer-port") + 1] == "9123"


def test_view_bind_elsewhere_only_when_asked(run_3d, capsys):
    assert main(["view", str(run_3d), "--dry-run", "--bind", "0.0.0.0"]) == 0
    cmd = capsys.readouterr().out.split()
    assert cmd[cmd.index("--bind") + 1] == "0.0.0.0"
    assert main(["view", str(run_3d), "--dry-run", "--bind", "localhost:1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--bind" in err[0] and "localhost:1" in err[0]


@pytest.mark.parametrize("make", ["missing", "empty-dir", "not-rrd"])
def test_view_bad_path_is_one_line_exit_2(make, tmp_path, capsys):
    path = tmp_path / "x.json"
    if make == "empty-dir":
        path = tmp_path
    elif make == "not-rrd":
        path.write_text("{}")
    assert main(["view", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(path) in err[0]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _listening(port: int) -> list[str]:
    """Local addresses (hex, as /proc/net/tcp{,6} writes them) listening on ``port``."""
    found = []
    for name in ("/proc/net/tcp", "/proc/net/tcp6"):
        for line in Path(name).read_text().splitlines()[1:]:
            local, state = line.split()[1], line.split()[3]
            addr, hex_port = local.split(":")
            if state == "0A" and int(hex_port, 16) == port:  # 0A = LISTEN
                found.append(addr)
    return found


def _addresses_while_viewing(cmd: list[str], ports: list[int]) -> list[str]:
    """Start ``cmd`` (``skinny view ...``), wait until every port in ``ports`` listens and
    return the local addresses listening on them."""
    env = {**os.environ, "BROWSER": "true"}  # never open a browser from a test
    proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, env=env, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and not all(_listening(p) for p in ports):
            assert proc.poll() is None, "the viewer exited"
            time.sleep(0.2)
        return [a for p in ports for a in _listening(p)]
    finally:
        os.killpg(proc.pid, signal.SIGTERM)
        proc.wait(timeout=30)


NEEDS_PROC_NET = pytest.mark.skipif(not Path("/proc/net/tcp").is_file(),
                                    reason="needs Linux /proc/net/tcp")


@NEEDS_PROC_NET
def test_web_viewer_listens_on_127_0_0_1_only(run_3d):
    web, grpc = _free_port(), _free_port()
    addresses = _addresses_while_viewing(
        [sys.executable, "-m", "skinny_mj.cli.parser", "view", str(run_3d), "--web", "--web-port",
         str(web), "--grpc-port", str(grpc)], [web, grpc])
    assert len(addresses) >= 2 and set(addresses) == {"0100007F"}  # 127.0.0.1, nothing else


NEEDS_XVFB = pytest.mark.skipif(
    shutil.which("xvfb-run") is None or shutil.which("rerun") is None,
    reason="needs Debian packages xvfb and mesa-vulkan-drivers (.ci/run installs them) and "
    "the rerun viewer")


@NEEDS_PROC_NET
@NEEDS_XVFB
def test_native_viewer_listens_on_127_0_0_1_only(run_3d):
    grpc = _free_port()  # the native viewer's own gRPC server (rerun's default: 0.0.0.0)
    addresses = _addresses_while_viewing(
        ["xvfb-run", "-a", sys.executable, "-m", "skinny_mj.cli.parser", "view", str(run_3d),
         "--grpc-port", str(grpc)], [grpc])
    assert addresses and set(addresses) == {"0100007F"}  # 127.0.0.1, nothing else


# -- the screenshot ---------------------------------------------------------------------
def _near(pixels: np.ndarray, rgb: tuple[int, int, int], tol: int = 60) -> np.ndarray:
    return np.abs(pixels - np.array(rgb)).sum(axis=2) <= tol


def _rgb(path: Path) -> np.ndarray:
    from PIL import Image

    with Image.open(path) as img:
        return np.asarray(img.convert("RGB")).astype(np.int64)


def _check_arms(pose: np.ndarray) -> None:
    """Both arms whole in the 3D view, desired (blue) and actual (orange) apart."""
    arms = _near(pose, DESIRED_RGB) | _near(pose, ACTUAL_RGB)
    ys, xs = np.nonzero(arms)
    h, w = arms.shape
    assert arms.sum() > 300, "no arm pixels in the 3D view"
    # both arms whole: clear of the view's edges, one either side of the middle
    assert xs.min() > 0.03 * w and xs.max() < 0.97 * w, (xs.min(), xs.max(), w)
    assert ys.min() > 0.05 * h and ys.max() < 0.97 * h, (ys.min(), ys.max(), h)
    assert xs.min() < 0.4 * w and xs.max() > 0.6 * w
    assert _near(pose, ACTUAL_RGB).sum() > 50, "the actual (orange) arms are not drawn"


def _check_joint_plot(img: np.ndarray, dofs: list[str], min_height: float = 0.0) -> None:
    """Per joint of ``dofs``, in its own colour: a line across the time axis, left of the
    legend, its vertical extent at least ``min_height`` of the view (not squashed), and a
    legend entry in the blank right of the data (the axis runs 30 % past the end)."""
    h, w = img.shape[:2]
    data, legend = img[:, : int(0.72 * w)], img[:, int(0.8 * w):]
    for dof in dofs:
        line = _near(data, layout.joint_rgb(dof))
        cols, rows = np.flatnonzero(line.any(axis=0)), np.flatnonzero(line.any(axis=1))
        assert line.sum() > 1000, f"no {dof} line (its colour: {layout.joint_rgb(dof)})"
        assert np.ptp(cols) > 0.55 * w, f"the {dof} line does not cross the time axis"
        assert np.ptp(rows) > min_height * h, f"the {dof} trace is squashed: {np.ptp(rows)} px"
        assert _near(legend, layout.joint_rgb(dof)).sum() > 20, f"no legend entry for {dof}"


def _arm_views(title: str) -> dict[str, str]:
    return {side: f"{side} arm: {title}" for side in body.SIDES}


@NEEDS_XVFB
def test_viewer_screenshot_frames_both_arms_and_plots_have_lines(run_3d, tmp_path):
    # 0.6 s in, the actual arms lag the desired ones by 0.2 s: both colours show
    angles = _arm_views(layout.ANGLES_TITLE)
    shots = viewer.screenshot(run_3d, tmp_path / "viewer.png", at_s=0.6,
                              views=["pose", *angles.values()])
    _check_arms(_rgb(shots["pose"]))
    for side, name in angles.items():  # one colour per joint, each with its legend entry
        _check_joint_plot(_rgb(shots[name]), [n for n in body.dof_names(8)
                                              if n.startswith(side)])
    assert _rgb(shots["window"]).shape[1] >= 1600


@NEEDS_XVFB
def test_viewer_screenshot_of_a_torque_recording(tmp_path):
    run = _write_run(tmp_path / "run.rrd", 8, torque=True)
    torques = _arm_views(layout.TORQUES_TITLE)
    shots = viewer.screenshot(run, tmp_path / "torque.png", at_s=0.6,
                              views=["pose", *torques.values()])
    _check_arms(_rgb(shots["pose"]))
    for side, name in torques.items():  # the applied torques fill the view (no limit lines
        # squashing them: their limits are 4-13x their amplitude here)
        _check_joint_plot(_rgb(shots[name]), [n for n in body.dof_names(8)
                                              if n.startswith(side)], min_height=0.4)
