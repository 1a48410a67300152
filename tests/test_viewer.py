"""``skinny view`` and the look a recording opens on.

The default tests read the recording back with rerun's own reader, no pixels: the views its
saved blueprint holds and where they sit, which entities each view shows, each joint's
colour, legend name and line width, the axes' ranges, the time panel's timeline and where
the 3D view's eye looks. The screenshot tests (``pytest -m screenshot``, opt-in) look at
the headless viewer's picture, with measures relative to the picture (a joint's share of
the plotted pixels, colours present or absent); they need a Vulkan driver (Debian package
``mesa-vulkan-drivers``)."""

from __future__ import annotations

import os
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
from skinny_mj.recording import (
    ACTUAL_RGB,
    DESIRED_RGB,
    ROLE_RGB,
    read_recording_series,
    recording_entities,
    write_recording,
)


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
        path, dt=body.CONTROL_DT_S, which=dof, dof_names=list(body.body_of(dof).dof_names),
        signal_names=list(body.body_of(dof).signal_names("cartesian")), desired_angles=traj.angles,
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


NEEDS_VULKAN = pytest.mark.skipif(
    sys.platform.startswith("linux") and not viewer.vulkan_drivers(),
    reason="the headless rerun viewer needs a Vulkan driver (Debian package "
    "mesa-vulkan-drivers)")


@NEEDS_PROC_NET
@NEEDS_VULKAN
def test_native_viewer_listens_on_127_0_0_1_only(run_3d):
    grpc = _free_port()  # the native viewer's own gRPC server (rerun's default: 0.0.0.0)
    cmd = viewer.viewer_command([run_3d], grpc_port=grpc, executable=[
        sys.executable, "-m", "rerun"]) + ["--headless"]  # the same viewer, no window
    addresses = _addresses_while_viewing(cmd, [grpc])
    assert addresses and set(addresses) == {"0100007F"}  # 127.0.0.1, nothing else


# -- the saved look, read back from the recording ---------------------------------------
@pytest.fixture(scope="module")
def torque_3d(tmp_path_factory) -> Path:
    return _write_run(tmp_path_factory.mktemp("view") / "torque.rrd", 8, torque=True)


def _arm_views(title: str) -> dict[str, str]:
    return {side: f"{side} arm: {title}" for side in body.SIDES}


def _dofs(side: str) -> list[str]:
    return [n for n in body.body_of(8).dof_names if layout.split_dof(n)[0] == side]


def _last_time_s(path: Path, entity: str) -> float:
    """The last sample of ``entity`` on the ``time`` timeline, s."""
    from rerun.chunk import RrdReader

    return max(c.to_record_batch().column("time").to_numpy().astype(np.int64).max() / 1e9
               for c in RrdReader(str(path)).stream()
               if c.entity_path == entity and not c.is_static)


def test_a_views_entity_filter_reads_as_rerun_does():
    view = layout.SavedView("v", "TimeSeries", "/a", ("+ $origin/**", "- /a/b/**", "+ /a/b/c"))
    entities = ["/a", "/a/x", "/a/b", "/a/b/d", "/a/b/c", "/ab", "/z"]
    assert view.shows(entities) == ["/a", "/a/x", "/a/b/c"]  # the most specific rule wins
    assert layout.SavedView("v", "3D", "/", ("$origin/**",)).shows(entities) == entities


@pytest.mark.parametrize("torque", [False, True])
def test_saved_layout_has_the_views_in_their_places(run_3d, torque_3d, torque):
    saved = layout.read_layout(torque_3d if torque else run_3d)
    rows = [_arm_views(layout.ANGLES_TITLE)]
    if torque:
        rows.append(_arm_views(layout.TORQUES_TITLE))
    rows.append(_arm_views(f"command (normalized, ±1 = "
                           f"{'torque limit' if torque else 'full scale'})"))
    # the pose left, the plots right: per quantity a row with the arms side by side, then
    # the tabs of signals, learning curves and the info page
    root = saved.root
    assert (root.kind, root.children[0], root.shares) == ("Horizontal", "pose", (2.0, 5.0))
    series = root.children[1]
    assert series.kind == "Vertical" and len(series.children) == len(rows) + 1
    for row, names in zip(series.children, rows, strict=False):
        assert (row.kind, row.children) == ("Horizontal", tuple(names.values()))
    tabs = series.children[-1]
    assert (tabs.kind, tabs.children) == ("Tabs", ("signals", "learning curves", "info"))
    kinds = {name: view.kind for name, view in saved.views.items()}
    assert kinds.pop("pose") == "3D" and kinds.pop("info") == "TextDocument"
    assert set(kinds.values()) == {"TimeSeries"} and len(kinds) == 2 * len(rows) + 2
    # the entity tree and the selection start folded, the time panel on ``time`` (s)
    assert saved.panels == {"blueprint_panel": "Collapsed", "selection_panel": "Collapsed",
                            "time_panel": "Collapsed"}
    assert saved.timeline == "time"


@pytest.mark.parametrize("torque", [False, True])
def test_each_view_shows_its_entities_and_nothing_is_missing(run_3d, torque_3d, torque):
    path = torque_3d if torque else run_3d
    saved, entities = layout.read_layout(path), recording_entities(path)
    for view in saved.views.values():  # every entity a view names is in the recording
        named = [q.split(" ", 1)[1] for q in view.query if q.startswith("+ /")]
        assert set(named) <= set(entities), (view.name, set(named) - set(entities))
    shows = {name: set(view.shows(entities)) for name, view in saved.views.items()}
    assert shows["pose"] == {"/pose/desired", "/pose/actual", "/pose/torso", "/pose/head"}
    assert shows["info"] == {"/info"}
    assert shows["learning curves"] == {"/curves/train_position_nrmse"}
    assert shows["signals"] == {e for e in entities if e.startswith("/signals/")}
    for side in body.SIDES:
        dofs = _dofs(side)
        assert shows[_arm_views(layout.ANGLES_TITLE)[side]] == {
            f"{layout.dof_entity(n)}/{r}" for n in dofs for r in ("desired", "actual")}
        command = next(n for n in saved.views if n.startswith(f"{side} arm: command"))
        assert shows[command] == {f"{layout.dof_entity(n)}/command" for n in dofs}
        if torque:  # applied and bias torques; the limits stay off the N m plot
            assert shows[_arm_views(layout.TORQUES_TITLE)[side]] == {
                f"/torques/{n}/{r}" for n in dofs for r in ("gravity", "applied")}
    assert not any("limit" in e for shown in shows.values() for e in shown)


@pytest.mark.parametrize("torque", [False, True])
def test_one_colour_and_one_legend_name_per_joint(run_3d, torque_3d, torque):
    path = torque_3d if torque else run_3d
    saved, styles = layout.read_layout(path), layout.read_styles(path)
    entities = recording_entities(path)
    joint_colours = {layout.joint_rgb(n) for n in body.body_of(8).dof_names}
    assert len(joint_colours) == 4 and not joint_colours & {DESIRED_RGB, ACTUAL_RGB}
    arm_plots = [v for v in saved.views.values() if " arm: " in v.name]
    assert len(arm_plots) == (6 if torque else 4)
    for view in arm_plots:
        assert view.legend == "RightTop"
        legend: dict[str, set] = {}
        for entity in view.shows(entities):
            dof = next(n for n in body.body_of(8).dof_names
                       if entity.startswith(f"{layout.dof_entity(n)}/")
                       or entity.startswith(f"/torques/{n}/"))
            role = entity.rsplit("/", 1)[1]
            thin = role in ("desired", "gravity")
            assert styles[entity] == {  # thick: actual, applied, command; thin and lighter
                "colors": [layout.joint_rgb(dof, light=thin)],
                "names": [layout.joint_label(dof)],
                "widths": [layout.THIN if thin else layout.THICK]}, (view.name, entity)
            legend.setdefault(layout.joint_label(dof), set()).add(dof)
        # the legend names each of the arm's joints once (thick and thin share the name)
        side = view.name.split(" ", 1)[0]
        assert {k: sorted(v) for k, v in legend.items()} == {
            layout.joint_label(n): [n] for n in _dofs(side)}
    assert styles["/pose/desired"]["colors"] == [DESIRED_RGB]
    assert styles["/pose/actual"]["colors"] == [ACTUAL_RGB]
    for entity in saved.views["signals"].shows(entities):
        role = entity.rsplit("/", 1)[1]
        assert styles[entity]["colors"] == [ROLE_RGB[role]] and styles[entity]["names"] == [role]


@pytest.mark.parametrize("torque", [False, True])
def test_axes_hold_the_data_and_leave_room_for_the_legend(run_3d, torque_3d, torque):
    path = torque_3d if torque else run_3d
    saved = layout.read_layout(path)
    end_s = _last_time_s(path, "/skinny/right/elbow_flexion/actual")
    assert end_s == pytest.approx(312 * body.CONTROL_DT_S)  # YMCA: 313 steps
    for view in saved.views.values():  # time runs 30 % past the end: the legend's room
        if view.kind == "TimeSeries" and view.origin != "/curves":
            assert view.time_range_s == pytest.approx((0.0, 1.3 * end_s))
    for side in body.SIDES:
        assert saved.views[_arm_views(layout.ANGLES_TITLE)[side]].value_range is None  # fit
        command = next(v for v in saved.views.values()
                       if v.name.startswith(f"{side} arm: command"))
        assert command.value_range == (-1.1, 1.1)
        for n in _dofs(side):
            values = read_recording_series(path, f"{layout.dof_entity(n)}/command")
            assert np.abs(values).max() <= 1.0
        if torque:  # the applied torques inside the axis and filling at least 40 % of it
            low, high = saved.views[_arm_views(layout.TORQUES_TITLE)[side]].value_range
            applied = np.concatenate([read_recording_series(path, f"/torques/{n}/applied")
                                      for n in _dofs(side)])
            assert low == -high and np.abs(applied).max() <= high
            assert np.abs(applied).max() >= 0.4 * high


#: rerun's 3D view: vertical field of view 55 degrees (on the headless viewer's picture the
#: arms' ends fall within 4 px of this projection); the pose column of a 1600 x 1000 window
#: (2 of 7 shares) is 451 x 900 px, a width / height of 0.5: 0.45 leaves slack.
FOV_Y_DEG, POSE_ASPECT = 55.0, 0.45


def test_pose_view_frames_both_arms_from_the_front(run_3d):
    from rerun.chunk import RrdReader

    eye = layout.read_layout(run_3d).views["pose"].eye
    assert eye is not None and eye["eye_up"] == (0.0, 0.0, 1.0)
    position, target = np.array(eye["position"]), np.array(eye["look_target"])
    forward = (target - position) / np.linalg.norm(target - position)
    right = np.cross(forward, eye["eye_up"])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    points = np.concatenate([
        np.array(c.to_record_batch().column("LineStrips3D:strips").to_pylist()).reshape(-1, 3)
        for c in RrdReader(str(run_3d)).stream()
        if c.entity_path in ("/pose/desired", "/pose/actual") and not c.is_static])
    assert len(points) == 2 * 313 * 2 * 3  # both poses, every step, 2 arms x 3 points
    rel = points - position
    depth = rel @ forward
    assert forward[1] > 0.99 and depth.min() > 0  # from the front (Skinny faces -y)
    half_y = np.tan(np.radians(FOV_Y_DEG / 2))
    x, y = (rel @ right) / depth / (half_y * POSE_ASPECT), (rel @ up) / depth / half_y
    assert np.abs(x).max() < 0.95 and np.abs(y).max() < 0.95, (np.abs(x).max(), np.abs(y).max())
    assert x.min() < -0.3 and x.max() > 0.3  # one arm either side of the middle


# -- skinny view --screenshot: the command line (no viewer started) ---------------------
@pytest.mark.parametrize("argv, words", [
    (["--screenshot", "{tmp}/shot.jpg", "{run}"], ".png"),
    (["--screenshot", "{tmp}/shot.png", "{folder}"], "2 recordings"),
    (["--screenshot", "{tmp}/shot.png", "--at", "-1", "{run}"], "--at"),
    (["--screenshot", "{tmp}/shot.png", "--web", "{run}"], "--web"),
])
def test_screenshot_bad_input_is_one_line_exit_2(run_3d, tmp_path, capsys, argv, words):
    folder = tmp_path / "two"
    for name in ("a", "b"):
        (folder / name).mkdir(parents=True)
        (folder / name / "run.rrd").write_bytes(run_3d.read_bytes())
    fill = {"tmp": tmp_path, "run": run_3d, "folder": folder}
    assert main(["view", *[a.format(**fill) for a in argv]]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0]
    assert not list(tmp_path.glob("*.png")) and not list(tmp_path.glob("*.jpg"))


def test_screenshot_without_a_vulkan_driver_names_the_package(run_3d, tmp_path, capsys,
                                                              monkeypatch):
    monkeypatch.setattr(sys, "platform", "linux")
    monkeypatch.setenv("VK_DRIVER_FILES", str(tmp_path / "none.json"))
    assert viewer.vulkan_drivers() == []
    assert main(["view", "--screenshot", str(tmp_path / "shot.png"), str(run_3d)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "mesa-vulkan-drivers" in err[0]
    assert not (tmp_path / "shot.png").exists()


# -- the screenshot (opt-in: pytest -m screenshot) --------------------------------------
def _near(pixels: np.ndarray, rgb: tuple[int, int, int], tol: int = 60) -> np.ndarray:
    return np.abs(pixels - np.array(rgb)).sum(axis=2) <= tol


def _rgb(path: Path) -> np.ndarray:
    from PIL import Image

    with Image.open(path) as img:
        return np.asarray(img.convert("RGB")).astype(np.int64)


def _check_arms(pose: np.ndarray) -> None:
    """Both arms whole in the 3D view, desired (blue) and actual (orange) each a fair part
    of what is drawn of Skinny (the grey torso and head included)."""
    desired, actual = _near(pose, DESIRED_RGB), _near(pose, ACTUAL_RGB)
    drawn = (desired | actual | _near(pose, layout.TORSO_RGB, 30)).sum()
    assert desired.sum() > 0.1 * drawn and actual.sum() > 0.1 * drawn, (
        desired.sum(), actual.sum(), drawn)
    ys, xs = np.nonzero(desired | actual)
    h, w = desired.shape
    # both arms whole: clear of the view's edges, one either side of the middle
    assert xs.min() > 0.03 * w and xs.max() < 0.97 * w, (xs.min(), xs.max(), w)
    assert ys.min() > 0.05 * h and ys.max() < 0.97 * h, (ys.min(), ys.max(), h)
    assert xs.min() < 0.4 * w and xs.max() > 0.6 * w


def _check_joint_plot(img: np.ndarray, dofs: list[str], min_height: float = 0.0) -> None:
    """Per joint of ``dofs``, in its own colour: at least 5 % of the plotted pixels (an
    equal share would be 25 %; the joint lines overlap), across the time axis as far as
    the data go, its vertical extent at least ``min_height`` of the view (not squashed),
    and a legend entry in the blank right of the data (the axis runs 30 % past the end)
    as large as half an average entry."""
    h, w = img.shape[:2]
    data, legend = img[:, : int(0.72 * w)], img[:, int(0.8 * w):]
    lines = {dof: _near(data, layout.joint_rgb(dof)) for dof in dofs}
    plotted = np.logical_or.reduce(list(lines.values()))
    span = np.ptp(np.flatnonzero(plotted.any(axis=0)))
    entries = {dof: _near(legend, layout.joint_rgb(dof)).sum() for dof in dofs}
    for dof, line in lines.items():
        share = line.sum() / plotted.sum()
        cols, rows = np.flatnonzero(line.any(axis=0)), np.flatnonzero(line.any(axis=1))
        assert share > 0.05, f"no {dof} line: {share:.1%} of the plotted pixels"
        assert np.ptp(cols) > 0.8 * span, f"the {dof} line does not cross the time axis"
        assert np.ptp(rows) > min_height * h, f"the {dof} trace is squashed: {np.ptp(rows)} px"
        assert entries[dof] > 0.5 * np.mean(list(entries.values())), \
            f"no legend entry for {dof}: {entries}"


@pytest.mark.parametrize("torque", [False, True])
@pytest.mark.screenshot
@NEEDS_VULKAN
def test_viewer_screenshot_frames_both_arms_and_plots_have_lines(run_3d, torque_3d,
                                                                 tmp_path, torque):
    # 0.6 s in, the actual arms lag the desired ones by 0.2 s: both colours show
    plots = _arm_views(layout.TORQUES_TITLE if torque else layout.ANGLES_TITLE)
    shots = viewer.screenshot(torque_3d if torque else run_3d, tmp_path / "viewer.png",
                              at_s=0.6, views=["pose", *plots.values()])
    _check_arms(_rgb(shots["pose"]))
    for side, name in plots.items():  # one colour per joint, each with its legend entry;
        # the applied torques fill their view (their limits are 4-13x their amplitude)
        _check_joint_plot(_rgb(shots[name]), _dofs(side), min_height=0.4 if torque else 0)
    assert _rgb(shots["window"]).shape[:2] == (1000, 1600)


@pytest.mark.screenshot
@NEEDS_VULKAN
def test_skinny_view_screenshot_writes_the_window(run_3d, tmp_path, capsys):
    out = tmp_path / "pictures" / "viewer.png"
    assert main(["view", "--screenshot", str(out), "--at", "0.6", str(run_3d)]) == 0
    assert capsys.readouterr().out.strip() == f"wrote {out}"
    img = _rgb(out)
    assert img.shape[:2] == (1000, 1600)
    for rgb in (DESIRED_RGB, ACTUAL_RGB, *(layout.joint_rgb(n) for n in _dofs("right"))):
        assert _near(img, rgb).any(), rgb  # each colour of the layout present
    assert sorted(p.name for p in out.parent.iterdir()) == ["viewer.png"]  # no scratch files
