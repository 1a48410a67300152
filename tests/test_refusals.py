"""Refused up front, in one line: numeric flags out of range, runs too big for the
memory, unwritable outputs, movements whose values overflow, non-finite gym actions;
and nothing written (or left half-written) by a refused or failed command."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("hypothesis")
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from skinny_mj import preflight  # noqa: E402
from skinny_mj.cli.flags import RULES, check_args, check_value  # noqa: E402
from skinny_mj.cli.parser import build_parser, main  # noqa: E402
from skinny_mj.engine.memory import row_estimate  # noqa: E402
from skinny_mj.errors import SkinnyInputError  # noqa: E402
from skinny_mj.preflight import cleaned_on_failure  # noqa: E402
from skinny_mj.training.config import TrainConfig  # noqa: E402
from skinny_mj.training.memory import generation_estimate, train_estimate  # noqa: E402
from skinny_mj.trajectories import Trajectory, ymca  # noqa: E402

FLAGS = settings(max_examples=200, deadline=None, database=None)


def _one_line_exit_2(argv, capsys) -> str:
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's usage error
        code = exc.code
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "Traceback" not in err, err
    return err


# -- numeric flags --------------------------------------------------------------------------
def _in_range(dest: str, value: float) -> bool:
    kind, ok, _ = RULES[dest]
    return math.isfinite(value) and (kind is float or float(value).is_integer()) and ok(value)


def _accepted_exactly_in_range(dest: str, value) -> None:
    import argparse

    ns = argparse.Namespace(**{dest: value})
    if _in_range(dest, value):
        check_args(ns)
    else:
        with pytest.raises(SkinnyInputError, match="--" + dest.replace("_", "-")):
            check_args(ns)


@FLAGS
@given(dest=st.sampled_from(sorted(d for d, r in RULES.items() if r[0] is int)),
       value=st.integers(min_value=-(2**70), max_value=2**70))
def test_whole_number_flags_accept_exactly_their_range(dest, value):
    _accepted_exactly_in_range(dest, value)


@FLAGS
@given(dest=st.sampled_from(sorted(d for d, r in RULES.items() if r[0] is float)),
       value=st.floats(allow_nan=True, allow_infinity=True))
def test_real_flags_accept_exactly_their_finite_range(dest, value):
    _accepted_exactly_in_range(dest, value)


def test_every_rule_is_a_flag_of_some_command():
    parser = build_parser()
    dests = {a.dest for sub in parser.subcommands.values() for a in sub._actions}
    for sub in parser.subcommands.values():  # nested: skinny trajectory export
        for action in sub._actions:
            choices = getattr(action, "choices", None)
            for inner in (choices.values() if isinstance(choices, dict) else ()):
                if hasattr(inner, "_actions"):
                    dests |= {a.dest for a in inner._actions}
    assert set(RULES) <= dests, set(RULES) - dests


def test_wrong_kinds_are_refused():
    for dest, value in (("seed", 1.5), ("seed", True), ("speed", "1")):
        with pytest.raises(SkinnyInputError):
            check_value(dest, value)


@pytest.mark.parametrize("argv,flag", [
    (["train", "--seed", "-1"], "--seed"), (["track", "--seed", "-1"], "--seed"),
    (["test", "--model", "m.npz", "--seed", "-3"], "--seed"), (["demo", "--seed", "-1"], "--seed"),
    (["train", "--speed", "nan"], "--speed"),
    (["track", "--sensor-noise", "inf"], "--sensor-noise"),
    (["train", "--reservoir", "0"], "--reservoir"),
    (["train", "--spectral-radius", "-1"], "--spectral-radius"),
    (["train", "--noise", "-0.1"], "--noise"), (["train", "--beta", "1.5"], "--beta"),
    (["render", "--out", "x.png", "--frame", "-1"], "--frame"),
])
def test_cli_refuses_a_flag_out_of_range_in_one_line(argv, flag, capsys, tmp_path,
                                                     monkeypatch):
    monkeypatch.chdir(tmp_path)
    err = _one_line_exit_2(argv, capsys)
    assert flag in err
    assert list(tmp_path.iterdir()) == []  # nothing written


@settings(max_examples=60, deadline=None, database=None)
@given(command=st.sampled_from(["train", "track", "demo", "test"]),
       seed=st.integers(max_value=-1))
def test_cli_refuses_every_negative_seed_before_any_work(command, seed, tmp_path_factory):
    import contextlib
    import io

    out = tmp_path_factory.mktemp("neg") / "o"
    model = ["--model", "m.npz"] if command == "test" else []
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = main([command, *model, "--seed", str(seed), "--out", str(out)])
    line = err.getvalue()
    assert code == 2 and line.count("\n") == 1 and "--seed must be >= 0" in line
    assert not out.exists()


# -- memory ---------------------------------------------------------------------------------
def test_available_memory_is_read():
    free = preflight.available_bytes()
    assert free is None or free > 0


@pytest.mark.parametrize("argv,names", [
    (["train", "--reps", "100000000"], "--reps 100000000"),
    (["train", "--reservoir", "10000000"], "--reservoir 10000000"),
    (["train", "--epochs", "1000000000"], "--epochs 1000000000"),
    (["track", "--reps", "100000000"], "--reps 100000000"),
    (["trajectory", "export", "ymca", "--reps", "100000000", "--out", "x.npz"],
     "--reps 100000000"),
])
def test_too_big_for_memory_is_refused_before_any_work(argv, names, capsys, tmp_path,
                                                       monkeypatch):
    if preflight.available_bytes() is None:
        pytest.skip("this system does not say how much memory is free")
    monkeypatch.chdir(tmp_path)
    err = _one_line_exit_2([*argv[:1], *argv[1:], *(["--out", "o"] if "--out" not in argv
                                                     else [])], capsys)
    assert names in err and "available" in err and "memory" in err
    assert list(tmp_path.iterdir()) == []


def test_the_estimate_grows_with_steps_runs_and_reservoir():
    cfg = TrainConfig()
    base = train_estimate(cfg, 313, 313)
    longer = train_estimate(cfg, 3130, 313)
    for part in ("per-step buffers", "readout fit"):  # in proportion to the steps
        assert longer.parts[part] == 10 * base.parts[part]
    assert longer.parts["reservoir weights"] == base.parts["reservoir weights"]
    lockstep = train_estimate(cfg, 313, 313, runs=10)
    assert lockstep.parts["per-step buffers"] > 9 * base.parts["per-step buffers"]
    big = train_estimate(TrainConfig().override(esn__n_reservoir=2000), 313, 313)
    # the reservoir weights: at least the N x N float64 matrix itself
    assert big.parts["reservoir weights"] >= 2000**2 * 8
    assert big.parts["reservoir weights"] > 50 * base.parts["reservoir weights"]


def test_check_names_the_cause_and_what_is_available():
    est = preflight.Estimate({"a": 10, "b": 1000}, {"a": "x", "b": "--reps 7"})
    preflight.check(est, "the run", available=2000)
    with pytest.raises(SkinnyInputError, match=r"the run needs about 1010 B .*--reps 7.*1000 B"):
        preflight.check(est, "the run", available=1000)


def test_a_sweeps_largest_row_is_refused(capsys, tmp_path):
    if preflight.available_bytes() is None:
        pytest.skip("this system does not say how much memory is free")
    err = _one_line_exit_2(["experiment", "paper-e", "--movement", "ymca@0.002",
                            "--workers", "1", "--out", str(tmp_path / "sw")], capsys)
    assert "largest row" in err and "available" in err
    assert not (tmp_path / "sw").exists()


def _every_study(monkeypatch) -> list[str]:
    """Every registered study's name; rl-vs-fel's build does not need its extra here."""
    from skinny_mj.experiments.rl_vs_fel import runs as rl_vs_fel_runs

    from skinny_mj.engine import registry

    monkeypatch.setattr(rl_vs_fel_runs, "require_rl", lambda: None)
    return registry.names()


def test_every_study_estimates_every_row_quick_and_full(monkeypatch):
    from skinny_mj.engine import registry

    names = _every_study(monkeypatch)
    assert {"paper-d", "paper-e", "dynamic"} <= set(names)
    cache: dict = {}  # movements' lengths, shared by the studies
    for name in names:
        module = registry.get(name)
        for quick in (True, False):
            exp = module.build(quick=quick, movement=None, asf=None, body=None, signals=None)
            ests = {r.id: row_estimate(module, exp, r, exp.runs, cache)
                    for r in exp.rows}
            missing = [rid for rid, est in ests.items() if est is None]
            assert not missing, f"{name} says nothing of these rows' memory: {missing}"
            assert all(v >= 0 for est in ests.values() for v in est.parts.values()), name
            assert min(est.total for est in ests.values()) > 0, name


@pytest.mark.parametrize("name", ["adaptation", "figure-eight", "mackey-glass", "paper-c",
                                  "three-d", "rl-vs-fel"])
def test_a_study_too_big_for_the_memory_left_is_refused(name, monkeypatch, capsys, tmp_path):
    _every_study(monkeypatch)
    monkeypatch.setattr(preflight, "available_bytes", lambda: 1024**2)
    err = _one_line_exit_2(["experiment", name, "--quick", "--workers", "1", "--out",
                            str(tmp_path / "sw")], capsys)
    assert "largest row" in err and "more than the 1.0 MiB available" in err
    assert not (tmp_path / "sw").exists()


def test_the_generation_estimate_grows_with_steps_runs_and_rls():
    base = generation_estimate(200, 1, 2, 1200, 2000)
    assert base.parts["reservoir weights"] >= 200**2 * 8
    longer = generation_estimate(200, 1, 2, 12000, 2000)
    assert longer.parts["readout fit"] == 10 * base.parts["readout fit"]
    lockstep = generation_estimate(200, 1, 2, 1200, 2000, runs=20)
    assert lockstep.parts["per-step buffers"] == 20 * base.parts["per-step buffers"]
    assert lockstep.parts["reservoir weights"] >= 20 * 200**2 * 8
    force = generation_estimate(200, 1, 2, 1200, 2000, rls=True)
    assert force.parts["rls"] >= 3 * 204**2 * 8 and force.parts["readout fit"] == 0


# -- outputs ----------------------------------------------------------------------------------
def test_bench_out_under_a_file_is_refused_before_the_bench(capsys, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["bench", "--quick", "--out", str(blocker / "b.json")]) == 2  # input
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and str(blocker) in err and ".skinny-write-probe" not in err


def test_a_failed_write_removes_what_it_started(tmp_path):
    out = tmp_path / "new"
    with pytest.raises(RuntimeError), cleaned_on_failure(out):
        out.mkdir()
        (out / "run.rrd").write_text("half")
        raise RuntimeError("JSON writer died")
    assert not out.exists()
    old = tmp_path / "old"
    old.mkdir()
    (old / "keep.txt").write_text("mine")
    with pytest.raises(RuntimeError), cleaned_on_failure(old):
        (old / "run.rrd").write_text("half")
        (old / "sub").mkdir()
        raise RuntimeError
    assert sorted(p.name for p in old.iterdir()) == ["keep.txt"]


def _huge_csv(path: Path) -> Path:
    Trajectory(ymca(4).angles[:30], name="huge").save(path)
    lines = path.read_text().splitlines()
    row = lines[3].split(",")
    lines[3] = ",".join(["1e308", *row[1:]])
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_movement_whose_values_overflow_is_refused_when_read(tmp_path, capsys):
    path = _huge_csv(tmp_path / "huge.csv")
    with pytest.raises(SkinnyInputError, match="not a joint angle"):
        Trajectory.load(path)
    err = _one_line_exit_2(["track", "--trajectory", str(path), "--out",
                            str(tmp_path / "o")], capsys)
    assert "1e+308" in err
    assert not (tmp_path / "o").exists()


def test_angles_at_the_bound_still_load():
    angles = np.full((3, 4), 999.0)
    assert Trajectory(angles).angles.max() == 999.0


# -- gymnasium --------------------------------------------------------------------------------
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_gym_refuses_non_finite_actions_and_clips_finite_ones(bad):
    pytest.importorskip("gymnasium")
    from skinny_mj.gym.env import SkinnyEnv

    env = SkinnyEnv(trajectory="ymca")
    env.reset(seed=0)
    env.step(np.full(4, 5.0))  # finite, outside [-1, 1]: clipped by the task
    action = np.zeros(4)
    action[2] = bad
    with pytest.raises(ValueError, match=r"action \(2,\).*finite"):
        env.step(action)
    obs, *_ = env.step(np.zeros(4))  # the refused action did not end or break the episode
    assert np.all(np.isfinite(obs))


def test_vector_env_refuses_non_finite_actions():
    pytest.importorskip("gymnasium")
    from skinny_mj.gym.vector import SkinnyVectorEnv

    env = SkinnyVectorEnv(num_envs=2, trajectory="ymca")
    env.reset(seed=0)
    actions = np.zeros((2, 4))
    actions[1, 0] = np.nan
    with pytest.raises(ValueError, match=r"action \(1, 0\)"):
        env.step(actions)


def test_a_movement_too_long_for_the_memory_is_refused_before_it_is_made():
    if preflight.available_bytes() is None:
        pytest.skip("this system does not say how much memory is free")
    traj = Trajectory(ymca(4).angles, name="ymca")
    with pytest.raises(SkinnyInputError, match=r"speed 1e-09: 313000000000 steps of ymca"):
        traj.resample(1e-9)
    with pytest.raises(SkinnyInputError, match=r"10000000000 repetitions of ymca"):
        traj.repeat(10**10)
    assert len(traj.resample(0.5)) == 626 and len(traj.repeat(3)) == 939  # ordinary sizes


# -- a body's MJCF ----------------------------------------------------------------------------
def _edited_models(tmp_path: Path, edit) -> Path:
    """A copy of the shipped models folder with ``edit(text) -> text`` applied to
    ``skinny_2d.xml``."""
    import shutil

    from skinny_mj.plant.body import models_dir

    folder = tmp_path / "models"
    shutil.copytree(models_dir(), folder)
    robot = folder / "skinny_2d.xml"
    robot.write_text(edit(robot.read_text()))
    return folder


def _drop_line(needle: str):
    return lambda text: "\n".join(ln for ln in text.splitlines() if needle not in ln)


@pytest.mark.parametrize("edit,says", [
    (lambda text: text[:1500], "skinny_2d.xml:26: not well-formed XML"),  # truncated
    (lambda text: "", "skinny_2d.xml: empty file"),
    (lambda text: text.replace('<joint name="right_shoulder_abduction"',
                               '<joint foo="1" name="right_shoulder_abduction"'),
     "skinny_2d.xml:26: MJCF error: Schema violation: unrecognized attribute: 'foo'"),
    (lambda text: text.replace('class="shoulder_abduction" axis="0 1 0"',
                               'class="shoulder_abduction" axis="0 0 0"', 1),
     "skinny_2d.xml:26: MJCF error: axis too small"),
    (_drop_line('<velocity name="right_shoulder_abduction"'),
     "skinny_2d.xml: not a body of two arms: the actuators ['right_elbow_flexion', "
     "'left_shoulder_abduction', 'left_elbow_flexion'] are not one per hinge"),
    (_drop_line('<site name="left_wrist"'), "no site 'left_wrist'"),
    (lambda text: text.replace("skinny_defaults.xml", "nope.xml"),
     "nope.xml: cannot read the file: No such file or directory (included by skinny_2d.xml)"),
])
def test_a_broken_mjcf_is_one_line_naming_file_and_line(edit, says, tmp_path, monkeypatch,
                                                       capsys):
    from skinny_mj.plant.body import MODELS_ENV_VAR
    from skinny_mj.plant.model import load_model

    monkeypatch.setenv(MODELS_ENV_VAR, str(_edited_models(tmp_path, edit)))
    err = _one_line_exit_2(["track", "--out", str(tmp_path / "o")], capsys)
    assert says in err
    assert not (tmp_path / "o").exists()
    with pytest.raises(SkinnyInputError, match="skinny_2d.xml"):
        load_model(4)
    assert load_model("2d-torque").nu == 4  # the torque body is a file of its own


# -- motion capture's skeleton -----------------------------------------------------------------
def test_an_amc_without_its_subjects_skeleton_is_refused_and_the_one_used_is_said(
        tmp_path, capsys, caplog):
    import shutil

    data = Path(__file__).parent / "data"
    shutil.copy(data / "tiny.amc", tmp_path / "86_02.amc")
    shutil.copy(data / "tiny.asf", tmp_path / "12.asf")  # another subject's skeleton
    argv = ["trajectory", "show", str(tmp_path / "86_02.amc")]
    err = _one_line_exit_2(argv, capsys)
    assert "86_02.amc: no skeleton 86.asf of its subject; beside it: 12.asf" in err
    assert "--asf" in err
    assert main([*argv, "--asf", str(tmp_path / "12.asf")]) == 0  # given: taken as it is
    capsys.readouterr()
    shutil.copy(data / "tiny.asf", tmp_path / "86.asf")
    assert main(argv) == 0  # found beside it: a warning (stderr, or the test's log capture)
    said = capsys.readouterr().err + "\n".join(caplog.messages)
    assert f"86_02.amc: skeleton {tmp_path / '86.asf'} (beside it, by the clip's subject)" \
        in said


# -- bad values on the command line: exit 2, one line naming the culprit -----------------------
@pytest.mark.parametrize("argv,culprit", [
    (["experiment", "paper-e", "--quick", "--rows", ""], "--rows: '' names no row"),
    (["experiment", "paper-e", "--quick", "--rows", " , "], "--rows: ' , ' names no row"),
    (["sweep", "esn.spectral_radius=0.5,0.9", "--rows", ""], "--rows: '' names no row"),
    (["train", "--epochs", "1", "method.epochs=2"], "--epochs 1 and method.epochs=2"),
    (["train", "--dof", "8", "plant.dof=4"], "--dof 8 and plant.dof=4"),
    (["train", "method.epochs=1", "method.epochs=2"], "method.epochs=1 and method.epochs=2"),
])
def test_cli_refuses_a_bad_value_in_one_line_naming_it(argv, culprit, capsys, tmp_path,
                                                       monkeypatch):
    monkeypatch.chdir(tmp_path)
    err = _one_line_exit_2([*argv, "--out", str(tmp_path / "o")], capsys)
    assert culprit in err, err
    assert list(tmp_path.iterdir()) == []  # nothing written


@pytest.mark.parametrize("gl", ["disabled", "off"])
def test_render_with_rendering_off_says_how_to_turn_it_on(gl, capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("MUJOCO_GL", gl)
    err = _one_line_exit_2(["render", "--out", str(tmp_path / "x.png")], capsys)
    assert f"rendering is off (MUJOCO_GL={gl})" in err and "MUJOCO_GL=egl" in err
    assert list(tmp_path.iterdir()) == []


# -- a hidden set of bad inputs: files, names, specs, models -----------------------------------
@pytest.fixture(scope="module")
def bad(tmp_path_factory) -> Path:
    """A folder of damaged inputs (``{bad}`` in the argv below)."""
    import json

    from skinny_mj.trajectories.samples import SAMPLE_ASF

    root = tmp_path_factory.mktemp("bad")
    Trajectory(ymca(8).angles[:40], name="t8").save(root / "t8.npz")
    Trajectory(ymca(4).angles[:40], name="t4").save(root / "t4.csv")
    lines = (root / "t4.csv").read_text().splitlines()
    (root / "onerow.csv").write_text("\n".join(lines[:3]) + "\n")
    (root / "dt01.csv").write_text("\n".join(lines).replace("dt=0.02", "dt=0.01") + "\n")
    (root / "bom.csv").write_text("\n".join(lines) + "\n", encoding="utf-8-sig")
    (root / "empty.npz").write_bytes(b"")
    (root / "empty.asf").write_text("")
    (root / "folder.npz").mkdir()
    (root / "folder.json").mkdir()
    (root / "86_02.amc").write_text((Path(__file__).parent / "data" / "tiny.amc").read_text())
    (root / "moderndance.asf").write_text(SAMPLE_ASF.read_text())  # subject md's, not 86's
    with np.load(_shipped("general-2d-joint")) as data:
        arrays = dict(data)
    meta = json.loads(str(arrays["metadata"]))

    def model(name: str, **changes) -> None:
        np.savez(root / name, **{**arrays, "metadata": np.array(json.dumps({**meta, **changes}))})

    model("dof5.npz", dof=5)
    model("speeds.npz", max_speed_rad_s=[1.0, 2.0])
    model("dof8.npz", dof=8, max_speed_rad_s=meta["max_speed_rad_s"] * 2)
    model("forward.npz", config={**meta["config"], "forward": "parallel"})
    np.savez(root / "cfg.npz", **{**arrays, "config": np.array(json.dumps([1, 2]))})
    return root


def _shipped(name: str) -> Path:
    from skinny_mj.training.presets import model_path

    return model_path(name)


@pytest.mark.parametrize("argv,culprit", [
    # movement files and names
    (["track", "--trajectory", "{bad}/t8.npz"], "t8.npz: DOF mismatch: file has 8 DOFs"),
    (["track", "--trajectory", "{bad}/onerow.csv"], "onerow.csv: 1 step(s)"),
    (["track", "--trajectory", "{bad}/dt01.csv"], "dt01.csv: 40 step(s) every 0.01 s"),
    (["track", "--trajectory", "{bad}/empty.npz"], "empty.npz: not a readable trajectory"),
    (["track", "--trajectory", "{bad}/folder.npz"], "folder.npz: a folder, not a movement"),
    (["track", "--trajectory", ""], "empty movement name"),
    (["track", "--trajectory", "ymca@"], "'ymca@' has no speed after '@'"),
    (["track", "--trajectory", "ymca@0"], "speed must be in (0, 10], got 0"),
    (["track", "--trajectory", "{bad}/t4.csv@start"], "bad excerpt 'start'"),
    (["track", "--trajectory", "{bad}/t4.csv@start=-1"], "needs start >= 0"),
    (["track", "--trajectory", "{bad}/t4.csv@start=0.5,duration=100"], "is outside 't4'"),
    (["track", "--trajectory", "babble:seed=-1"], "babble seed must be a whole number"),
    (["track", "--trajectory", "babble:duration=1e12"], "babble duration 1e+12 s"),
    (["track", "--trajectory", "babble:vmin=5,vmax=1"], "0 < vmin <= vmax"),
    (["track", "--trajectory", "set:ymca++y"], "bad training set 'set:ymca++y'"),
    (["track", "--trajectory", "set:ymca+nope"], "unknown movement 'nope'"),
    (["track", "--trajectory", "{bad}/86_02.amc"], "86_02.amc: no skeleton 86.asf"),
    (["track", "--trajectory", "md_02.amc", "--asf", "{bad}/empty.asf"], "empty.asf: file is"),
    (["track", "--trajectory", "md_02.amc", "--asf", "{bad}/folder.npz"], "folder.npz: a fold"),
    (["track", "--trajectory", "ymca", "--asf", "{bad}/empty.asf"], "and the movement 'ymca' "
                                                                    "has none: leave --asf out"),
    (["train", "--asf", "{bad}/empty.asf"], "the movement 'ymca' has none"),
    (["track", "--trajectory", "set:ymca+y", "--asf", "{bad}/empty.asf"], "has none"),
    (["experiment", "paper-e", "--quick", "--asf", "{bad}/empty.asf"], "give the clip as the"),
    (["track", "--trajectory", "ymca", "--retarget", "positions"], "--retarget positions "
                                                                    "reads motion capture"),
    (["train", "--retarget", "positions"], "and the movement 'ymca' has none"),
    # models for `skinny test`
    (["test", "--model", "{bad}/empty.npz"], "empty.npz: not a model written by `skinny train`"),
    (["test", "--model", "{bad}/folder.npz"], "folder.npz: a folder, not a model file"),
    (["test", "--model", "general-9d"], "general-9d: no such model file (shipped models:"),
    (["test", "--model", "{bad}/dof5.npz"], "dof5.npz: model metadata: dof must be"),
    (["test", "--model", "{bad}/speeds.npz"], "speeds.npz: model metadata: max_speed_rad_s"),
    (["test", "--model", "{bad}/dof8.npz"], "dof8.npz: the network has 8 inputs and 4 outputs"),
    (["test", "--model", "{bad}/forward.npz"], "forward.npz: the model was trained with a "
                                               "forward model"),
    (["test", "--model", "{bad}/cfg.npz"], "cfg.npz: not a model written by `skinny train`"),
    (["test", "--model", "general-2d-joint", "--trajectory", "{bad}/t8.npz"], "DOF mismatch"),
    # configs, studies, rows, schedulers
    (["train", "--config", "{bad}/folder.json"], "folder.json: a folder, not a config file"),
    (["train", "--config", "{bad}/t4.csv"], "t4.csv: not a JSON config file"),
    (["train", "esn.spectral_radius=nan"], "esn.spectral_radius must be a number"),
    (["experiment", "paper-zz"], "unknown experiment 'paper-zz'"),
    (["experiment", "paper-e", "--quick", "--rows", "nope"], "has no row or group 'nope'"),
    (["experiment", "paper-e", "--quick", "--scheduler", "bogus"], "--scheduler: scheduler mu"),
    (["experiment", "paper-e", "--quick", "--movement", "{bad}/t8.npz"], "DOF mismatch"),
    (["sweep", "esn.spectral_radius=0.5", "--study", "paper-e", "--row", "nope"], "no row 'nope'"),
])
def test_cli_refuses_a_hidden_set_of_bad_inputs_in_one_line(argv, culprit, bad, capsys,
                                                            tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv = [a.format(bad=bad) for a in argv]
    err = _one_line_exit_2([*argv, "--out", str(tmp_path / "o")], capsys)
    assert culprit in err, err
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_a_csv_saved_with_a_byte_order_mark_reads(bad):
    assert Trajectory.load(bad / "bom.csv").angles.shape == (40, 4)


@pytest.mark.parametrize("call,culprit", [
    (lambda bad: __import__("skinny_mj").load(trajectory="ymca@"), "no speed after '@'"),
    (lambda bad: __import__("skinny_mj").load(trajectory=bad / "folder.npz"), "a folder"),
    (lambda bad: __import__("skinny_mj").load(seed=-1), "seed must be a whole number >= 0"),
    (lambda bad: __import__("skinny_mj").load(sensor_noise=None), "sensor_noise must be a n"),
    (lambda bad: __import__("skinny_mj").load(max_speed_rad_s="fast"), "max_speed_rad_s must"),
    (lambda bad: _load_movement("md_02.amc", fps=0), "fps must be a number > 0, got 0"),
    (lambda bad: _load_movement("md_02.amc", fps=float("nan")), "fps must be a number > 0"),
    (lambda bad: _load_movement("md_02.amc", cutoff_hz=0), "cutoff_hz must be a number > 0"),
    (lambda bad: _load_movement(bad / "86_02.amc"), "no skeleton 86.asf"),
    (lambda bad: _load_movement("babble:duration=1e12"), "more than the"),
    (lambda bad: Trajectory.load(bad / "folder.npz"), "a folder, not a trajectory file"),
])
def test_the_python_api_refuses_the_same_inputs_with_a_skinny_input_error(call, culprit, bad):
    if culprit == "more than the" and preflight.available_bytes() is None:
        pytest.skip("this system does not say how much memory is free")
    with pytest.raises(SkinnyInputError) as caught:
        call(bad)
    assert isinstance(caught.value, ValueError) and culprit in str(caught.value)


def _load_movement(name, **kwargs):
    from skinny_mj.trajectories import load_movement

    return load_movement(name, 4, **kwargs)


def test_render_refuses_a_frame_without_a_movement(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("MUJOCO_GL", "egl")  # past the rendering check; nothing is drawn
    err = _one_line_exit_2(["render", "--frame", "5", "--out", str(tmp_path / "x.png")],
                           capsys)
    assert "--frame 5 needs --trajectory" in err
    assert list(tmp_path.iterdir()) == []


def test_a_memory_refusal_says_a_huge_need_in_a_readable_number():
    assert preflight.fmt_bytes(1.5 * 1024**3) == "1.5 GiB"
    assert preflight.fmt_bytes(222 * 1024**5) == "222.0 PiB"
    assert preflight.fmt_bytes(1e300) == "8.88e+284 PiB"  # not 285 digits
