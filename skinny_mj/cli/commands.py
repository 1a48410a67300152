"""The handlers behind ``skinny``'s sub-commands (the parser lives in :mod:`skinny_mj.cli.parser`).

Every command computes first and writes last, each file atomically, so a command that
fails on bad input leaves nothing half-written in ``--out``; and none writes over earlier
results unless told to (``--overwrite``; :mod:`skinny_mj.preflight`).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from skinny_mj import preflight
from skinny_mj.cli import config_files as cf
from skinny_mj.cli import memory
from skinny_mj.cli.claims import cmd_claims  # noqa: F401 (the `skinny claims` handler)
from skinny_mj.cli.config_files import file_config, train_config
from skinny_mj.cli.config_flags import (
    TEST_FLAGS,
    TRACK_FLAGS,
    changes,
    chosen_body,
    flag_names,
    given,
)
from skinny_mj.cli.memory import check_bench, check_export, check_sweep, check_train
from skinny_mj.cli.movement_list import list_text
from skinny_mj.cli.viewer import cmd_view  # noqa: F401 (the `skinny view` handler; no rerun import)
from skinny_mj.controllers.metrics import position_nrmse
from skinny_mj.engine import folder, protocols, registry
from skinny_mj.engine.experiment import default_out_dir, run_sweep
from skinny_mj.engine.grid import grid_study
from skinny_mj.engine.results import (
    run_metrics,
    test_figures,
    test_motor_nrmse,
    test_position_nrmse,
)
from skinny_mj.engine.stats import SMOKE_NOTE
from skinny_mj.errors import SkinnyInputError
from skinny_mj.io import atomic_write_json, atomic_write_text
from skinny_mj.plant import body, task
from skinny_mj.plant.ideal import IdealController
from skinny_mj.plant.render import render_png
from skinny_mj.plots import learning_curve_png
from skinny_mj.preflight import (
    check_new_file,
    check_run_folder,
    check_writable,
    run_folder,
)
from skinny_mj.progress import Progress as _Progress
from skinny_mj.progress import progress_on as _progress_on
from skinny_mj.recording import record_test, write_recording
from skinny_mj.training import loop
from skinny_mj.training import torque as torque_training
from skinny_mj.training.config import Movement, TrainConfig
from skinny_mj.training.feasible import load_movement  # NAME@feasible too, else trajectories'
from skinny_mj.training.imitation import (
    imitation_metrics,
    movement_stats,
    saturation,
)
from skinny_mj.training.memory import steps_cause
from skinny_mj.training.model_file import check_model, read_model
from skinny_mj.trajectories.library import SET_PREFIX, check_asf, set_pieces

DEFAULT_RESULTS = Path("results")


def _out_dir(args: argparse.Namespace, kind: str) -> Path:
    """``--out``, refused before the work if it holds results and no ``--overwrite``
    (exit 2), and checked writable (a read-only or full disk: exit 1); by default
    ``results/<kind>/<time the command started>``, made (unique) when the run is
    written (:func:`_writing`)."""
    if args.out is None:
        return check_writable(DEFAULT_RESULTS / kind / preflight.timestamp())
    return check_writable(check_run_folder(args.out, args.overwrite))


def _writing(args: argparse.Namespace, out: Path):
    """The folder to write the computed run into: ``out`` from :func:`_out_dir`, or for
    the default a new folder of that name, ``-2`` if another run took it since
    (:func:`skinny_mj.preflight.run_folder`)."""
    if args.out is None:
        return run_folder(None, out.parent, stamp=out.name)
    return run_folder(out, out.parent, overwrite=args.overwrite)


def _flag_config(args: argparse.Namespace, groups, base=None):
    """``base`` (default ``TrainConfig()``) with the config flags of ``groups`` given in
    ``args`` (:mod:`skinny_mj.cli.config_flags`)."""
    base = TrainConfig() if base is None else base
    return base.override(changes(base, given(args, groups), flag_names(groups)))


def _load_movement(mv, which, check=None):
    """The movement ``mv`` (a :class:`skinny_mj.training.config.Movement`) for the body
    ``which``; ``check(steps, cause)``
    first sees its length x reps (one repetition loaded), so a run too big for the
    memory is refused before it is."""
    check_asf(mv.trajectory, mv.asf, mv.retarget)  # not silently unused
    kw = {"asf": mv.asf, "speed": mv.speed, "retarget": mv.retarget}
    if check is not None:
        one, report = load_movement(mv.trajectory, which, reps=1, **kw)
        check(len(one) * mv.reps, steps_cause(one.name, len(one), mv.reps))
        if mv.reps == 1:
            return one, report
    return load_movement(mv.trajectory, which, reps=mv.reps, **kw)


def _recording(path: Path, *, which, signals: str, desired_angles, actual_angles, commands,
               desired_signals, actual_signals, sensed_signals=None, title: str = "",
               metadata: dict | None = None, curves: dict | None = None,
               torques: dict | None = None) -> Path:
    skinny = body.body_of(which)
    return write_recording(
        path, dt=body.CONTROL_DT_S, which=skinny, dof_names=list(skinny.dof_names),
        signal_names=list(skinny.signal_names(signals)), desired_angles=desired_angles,
        actual_angles=actual_angles, commands=commands, desired_signals=desired_signals,
        actual_signals=actual_signals, sensed_signals=sensed_signals, title=title,
        metadata=metadata, curves=curves, torques=torques,
    )


# -- track ------------------------------------------------------------------------------
def cmd_track(args: argparse.Namespace) -> int:
    cfg = _flag_config(args, TRACK_FLAGS)
    skinny, signals, mv = body.body_of(cfg.plant.body), cfg.plant.signals, cfg.movement
    if skinny.actuation != "velocity":  # the ideal controller commands joint velocities
        raise SkinnyInputError(f"track runs the ideal velocity commands: the {skinny.name} "
                               "body is torque-driven (a torque controller alone: skinny "
                               f"train --body {skinny.name} --feedback ct --method none "
                               "test.gain=1)")
    dof = skinny.dof
    out = _out_dir(args, "track")
    traj, report = _load_movement(
        mv, skinny, memory.check_track(dof, skinny.n_signals(signals)))
    env = task.load(skinny, signals, traj, sensor_noise=cfg.plant.sensor_noise, seed=args.seed)
    ctrl = IdealController(traj.angles, env.task.max_speed_rad_s, traj.dt)
    ts = env.reset()
    angles, true_sig = [env.physics.joint_angles()], [env.physics.position_signals(signals)]
    sensed, commands = [ts.observation["sensed"]], []
    while not ts.last():
        command = ctrl.command(int(ts.observation["step"]), ts.observation["joint_angles"])
        ts = env.step(command)
        commands.append(command)
        angles.append(env.physics.joint_angles())
        true_sig.append(env.physics.position_signals(signals))
        sensed.append(ts.observation["sensed"])
    desired = traj.position_signals(signals)
    true_sig = np.array(true_sig)
    nrmse = float(position_nrmse(true_sig[None], desired)[0])
    metrics = {
        "position_nrmse": nrmse, "steps": len(traj), "body": skinny.name, "dof": dof,
        "signals": signals,
        "trajectory": str(mv.trajectory), "speed": mv.speed, "reps": mv.reps,
        "seed": args.seed, "sensor_noise": cfg.plant.sensor_noise,
        "max_speed_rad_s": [float(v) for v in env.task.max_speed_rad_s],
        "clipped_samples": int(report.clipped_samples), "retarget": report.to_dict(),
    }
    with _writing(args, out) as out:
        _recording(out / "run.rrd", which=skinny, signals=signals,
                   desired_angles=traj.angles, actual_angles=np.array(angles),
                   commands=np.array(commands), desired_signals=desired,
                   actual_signals=true_sig, sensed_signals=np.array(sensed),
                   title=f"ideal controller on {traj.name}", metadata=metrics)
        atomic_write_json(out / "metrics.json", metrics)
    print(f"track {traj.name}: {skinny.name} ({dof} DOF), {len(traj)} steps, position NRMSE "
          f"{nrmse:.2e}, "
          f"clipped samples {report.clipped_samples} -> {out}")
    return 0


# -- train / demo / test ----------------------------------------------------------------
def _write_run(out: Path, outcome, title: str, preset: str | None = None) -> None:
    """metrics.json, model.npz, run.rrd (the test run) and learning_curve.png; for a
    failed (diverged) run only metrics.json, which says why. The model's metadata says
    what it was trained on (``training``: movement, its pieces, steps, seconds, preset)."""
    metrics = run_metrics(outcome)
    if outcome.failed:
        atomic_write_json(out / "metrics.json", metrics)
        return
    cfg = outcome.config
    train_curve = outcome.train.position_nrmse
    if isinstance(train_curve, list) and train_curve:  # FEL: one value per epoch
        curve = np.array([np.nan if v is None else v for v in train_curve], dtype=float)
        learning_curve_png(out / "learning_curve.png", {"position NRMSE (evaluation cycle)": curve},
                           "position NRMSE", title=title, log_y=True,
                           xlabel="epoch (feedback gain K falls linearly from 1 to 0 in the last)")
    record_test(out / "run.rrd", outcome, title, figures=test_figures(outcome))
    outcome.esn.save(out / "model.npz", metadata={
        "body": cfg.plant.body, "dof": cfg.plant.dof, "signals": cfg.plant.signals,
        "sensor_noise": cfg.plant.sensor_noise, "actuation": cfg.actuation.kind,
        "max_speed_rad_s": [float(v) for v in outcome.max_speed_rad_s],
        "trained_on": cfg.movement.trajectory, "config": cfg.to_dict(),
        "training": _training_metadata(outcome, preset),
    })
    atomic_write_json(out / "metrics.json", metrics)


def _training_metadata(outcome, preset: str | None) -> dict[str, Any]:
    """What a model was trained on: the movement, its pieces (a ``set:``),
    steps and seconds per cycle, repetitions, the seed and the preset."""
    mv, steps = outcome.config.movement, outcome.steps_per_cycle
    name = str(mv.trajectory)
    pieces = set_pieces(name) if name.lower().startswith(SET_PREFIX) else [name]
    return {"movement": name, "pieces": pieces, "asf": mv.asf, "speed": mv.speed,
            "reps": mv.reps, "steps_per_cycle": steps,
            "seconds_per_cycle": steps * outcome.test.trajectory.dt,
            "seed": int(outcome.seed), "preset": preset}


def _train_and_write(cfg, seed: int, args: argparse.Namespace, out: Path, title: str,
                     preset: str | None = None):
    """Train, then write the run (:func:`_write_run`); the outcome and the folder."""
    bar = _Progress(title, args.quiet)
    try:
        outcome = loop.train(cfg, seed, progress=bar)
    finally:
        bar.close()
    with _writing(args, out) as out:
        _write_run(out, outcome, title, preset)
    return outcome, out


def _fmt(v: float | None) -> str:
    return "failed" if v is None else f"{v:.4f}"


def _robot_line(f: dict) -> str:
    """The test's figures in a roboticist's units (``RunResult.robot_figures``: joint
    error, hand error, lag; torque body: RMS torque, |work|) as one line ('' when the test
    has none, e.g. a diverged network)."""
    if f.get("rms_error_deg") is None:
        return ""
    line = (f"  joint error RMS {f['rms_error_deg']:.2f}°, peak {f['peak_error_deg']:.2f}°; "
            f"hand error RMS {f['hand_error_cm']:.2f} cm, peak {f['peak_hand_error_cm']:.2f} "
            f"cm; lag {f['lag_s']:+.2f} s")
    if f.get("torque_rms_nm") is not None:
        line += f"; torque RMS {f['torque_rms_nm']:.3f} N m, |work| {f['abs_work_j']:.3f} J"
    return line


def cmd_train(args: argparse.Namespace) -> int:
    cfg, seed = train_config(args)
    out = _out_dir(args, "train")
    check_train(cfg)
    outcome, out = _train_and_write(cfg, seed, args, out,
                                    f"{cfg.method.kind} on {cfg.movement.trajectory}",
                                    preset=getattr(args, "preset", None))
    if outcome.failed:
        print(f"skinny train: run failed: {outcome.fail_reason} (details in "
              f"{out}/metrics.json)", file=sys.stderr)
        return 1
    print(f"test position NRMSE {_fmt(test_position_nrmse(outcome))}, motor NRMSE "
          f"{_fmt(test_motor_nrmse(outcome))}, {outcome.wall_s:.1f} s -> {out}")
    if line := _robot_line(outcome.robot_figures()):
        print(line)
    return 0


def cmd_demo(args: argparse.Namespace) -> int:
    cfg = TrainConfig()  # paper E, experiment 5
    out = _out_dir(args, "demo")
    check_train(cfg, "the demo")
    print("Training an ESN inverse model (N = 200) to make 2D Skinny dance YMCA:")
    print("paper E experiment 5 - new method, beta = 0.1, 3 learning cycles x 10 epochs, "
          "feedback gain K 1 -> 0, then a test with the feedback controller off.")
    start = time.perf_counter()
    outcome, out = _train_and_write(cfg, args.seed, args, out, "demo: paper E exp. 5")
    wall = time.perf_counter() - start
    paper = registry.get("paper-e").row("5").paper
    rows = [
        ("test position NRMSE", _fmt(test_position_nrmse(outcome)),
         f"{paper['position_nrmse']:.4f}"),
        ("test motor NRMSE", _fmt(test_motor_nrmse(outcome)), f"{paper['motor_nrmse']:.4f}"),
        ("wall time (s)", f"{wall:.1f}", "-"),
    ]
    ours_head = f"ours (seed {args.seed})"
    print(f"\n| {'':22} | {ours_head:>14} | {'paper (mean of 20)':>18} |")
    print(f"|{'-' * 24}|{'-' * 16}|{'-' * 20}|")
    for name, ours, theirs in rows:
        print(f"| {name:22} | {ours:>14} | {theirs:>18} |")
    print(f"\nRecording: {out / 'run.rrd'}  (open it with: skinny view {out})")
    print(f"Also: {out / 'metrics.json'}, {out / 'learning_curve.png'}, {out / 'model.npz'}")
    if outcome.failed:
        print(f"the run failed: {outcome.fail_reason}", file=sys.stderr)
        return 1
    return 0


def cmd_test(args: argparse.Namespace) -> int:
    path, esn, meta = read_model(args.model)  # a shipped model's name, or a file
    which, dof, signals = meta["body"], meta["dof"], meta["signals"]

    asked = _flag_config(args, TEST_FLAGS)  # the test's movement and sensor noise
    out = _out_dir(args, "test")
    if args.overwrite and args.out is not None and path.resolve().parent == out.resolve():
        raise SkinnyInputError("--overwrite would delete the --model itself (it is in --out); "
                               "choose another --out", path=path)
    traj, report = _load_movement(asked.movement, which, memory.check_test(
        esn.cfg, dof, body.body_of(which).n_signals(signals)))
    saved = meta.get("config") if isinstance(meta.get("config"), dict) else {}
    try:
        cfg = TrainConfig.from_dict(saved).override({
            "plant.body": which, "plant.signals": signals,
            "plant.sensor_noise": asked.plant.sensor_noise})
    except SkinnyInputError as err:
        raise SkinnyInputError(f"model metadata holds a bad config ({err})", path=path) from None
    check_model(esn, cfg, path)  # a model of another body, an edited file
    run = loop.run_of(cfg, esn, meta["max_speed_rad_s"], traj,
                      [loop.run_streams(args.seed).plant_seed])
    (test,) = loop.evaluate(run)
    metrics: dict[str, Any] = {
        "model": str(path), "trained_on": meta.get("trained_on"),
        "trajectory": str(asked.movement.trajectory),
        "body": which, "dof": dof, "signals": signals, "steps": len(traj), "seed": args.seed,
        "clipped_samples": int(report.clipped_samples), "failed": test.failed,
        "fail_reason": test.fail_reason,
        "test": {"position_nrmse": test.position_nrmse, "motor_nrmse": test.motor_nrmse},
    }
    # joint error (deg), hand error (cm), lag (s), as the train command's test dict has them
    if not test.failed:
        metrics["test"].update(loop.test_robot_metrics(run, test))
    if test.torque is not None:  # torque body: limits, |torque|, work, MuJoCo warnings
        metrics["test"]["torque"] = test.torque["metrics"]
    if not test.failed and cfg.torque is None:  # DTW, within 5°, lag

        # beside "test" (which stays the train command's own test dict, key for key)
        metrics["imitation"] = {**imitation_metrics(test, which),
                                "saturated": saturation(traj.angles, traj.dt, run.max_speed_rad_s)}
    ro = test.rollout
    with _writing(args, out) as out:
        _recording(out / "run.rrd", which=which, signals=signals, desired_angles=traj.angles,
                   actual_angles=ro.angles[0], commands=ro.commands[0],
                   desired_signals=test.desired, actual_signals=ro.true_signals[0],
                   sensed_signals=ro.sensed[0], title=f"test on {traj.name}",
                   metadata=metrics,
                   torques=None if test.torque is None else test.torque["series"])
        atomic_write_json(out / "metrics.json", metrics)
    if test.failed:
        print(f"skinny test: the network diverged: {test.fail_reason}", file=sys.stderr)
        return 1
    print(f"test on {traj.name}: position NRMSE {_fmt(test.position_nrmse)}, motor NRMSE "
          f"{_fmt(test.motor_nrmse)} -> {out}")
    if line := _robot_line({**test.robot_metrics(dof), **(test.torque_figures or {})}):
        print(line)
    extra = metrics.get("imitation", {})
    if extra:
        dtw = extra.get("dtw_nrmse")
        print(f"  DTW NRMSE {'n/a (pip install dtaidistance)' if dtw is None else f'{dtw:.4f}'}"
              f", within 5°: {100 * extra['within5']:.1f} % of steps, "
              f"commands beyond full scale: {100 * extra['saturated']:.1f} %")
    return 0


# -- trajectory / render ----------------------------------------------------------------
def cmd_trajectory(args: argparse.Namespace) -> int:
    if args.action == "list":
        print(list_text())
        return 0
    which = body.body_name(chosen_body(args))
    if args.action == "show":
        traj, _ = _load_movement(Movement(args.name, asf=args.asf, retarget=args.retarget),
                                 which)
        print(f"{traj.name} (body {which}, {traj.dof} DOF, explicit desired signals: "
              f"{sorted(traj.desired) if traj.desired else 'none'})")
        for key, value in movement_stats(traj).items():
            print(f"  {key:32} {value:.4g}")
        if getattr(args, "actuation", "velocity") == "torque":
            print("torque twin: inverse-dynamics torques of the movement against the limits")
            for line in torque_training.feasibility_report(which, traj):
                print(line)
        return 0
    out = check_new_file(args.out, args.overwrite)
    traj, _ = _load_movement(Movement(args.name, asf=args.asf, speed=args.speed,
                                      reps=args.reps), which,
                             check_export(body.body_of(which).dof, args.out))
    traj.save(check_new_file(out, args.overwrite))  # again: another command may have written it
    print(f"wrote {traj.name}: {len(traj)} steps, body {which} ({traj.dof} DOF) -> {out}")
    return 0


def cmd_render(args: argparse.Namespace) -> int:
    if args.trajectory is None and args.frame != 0:  # not silently the rest pose
        raise SkinnyInputError(f"--frame {args.frame} needs --trajectory (a movement's frame)")
    if Path(args.out).suffix.lower() != ".png":  # not PNG bytes under another name
        raise SkinnyInputError(f"--out: render writes a PNG: give a name ending in .png, got "
                               f"{args.out}")
    check_new_file(args.out, args.overwrite)
    angles, which = None, body.body_name(chosen_body(args))
    if args.trajectory is not None:
        traj, _ = _load_movement(Movement(args.trajectory), which)
        if not 0 <= args.frame < len(traj):
            raise SkinnyInputError(f"--frame must be in [0, {len(traj) - 1}], got {args.frame}")
        angles = traj.angles[args.frame]
    check_new_file(args.out, args.overwrite)  # again: another command may have written it
    path = render_png(which, args.out, width=args.width, height=args.height, angles=angles)
    print(f"wrote {path}")
    return 0


# -- experiment -------------------------------------------------------------------------
def cmd_experiment(args: argparse.Namespace) -> int:
    """Build the experiment with the CLI's options (each None = the paper's default), run
    the selected rows, write table/claims/report; exit 1 if any run errored (a bug)."""
    module = registry.get(args.name)  # `experiment list` is answered by the parser's main
    rows = [r.strip() for r in args.rows.split(",") if r.strip()] if args.rows else None
    options = {"quick": bool(args.quick), "movement": args.movement,
               "asf": None if args.asf is None else str(args.asf),
               "body": chosen_body(args, None),
               "signals": args.signals, "protocol": args.protocol}

    options, rows, runs, invocation = cf.apply_sweep_config(args, options, rows)
    if options["asf"] is not None:  # a skeleton for --movement CLIP.amc only
        check_asf(options["movement"], options["asf"])
    if options["protocol"] is not None:  # readings of unstated settings, on the study's base

        module = protocols.apply(options["protocol"], module, args.name)
    exp = module.build(**{k: v for k, v in options.items() if k != "protocol"})
    cf.check_experiment(invocation, exp)
    return _sweep_and_report(args, module, exp, rows, runs, options, invocation)


def cmd_sweep(args: argparse.Namespace) -> int:
    """``skinny sweep KEY=V1,V2 ...``: a grid over config keys (:mod:`skinny_mj.engine.grid`)
    on the experiment engine, from TrainConfig's defaults, a config file or a study's row."""
    study = None
    if args.study is not None:
        study = registry.get(args.study)
    base = None if args.config is None else file_config(args.config)
    grid = grid_study(args.axes, study=study, row=args.row, runs=args.runs,
                      quick=args.quick, base=base)
    rows = [r.strip() for r in args.rows.split(",") if r.strip()] if args.rows else None
    options = {"axes": list(args.axes), "study": args.study, "row": args.row,
               "quick": args.quick, "config": None if args.config is None else str(args.config)}
    return _sweep_and_report(args, grid, grid.build(), rows, None, options, None)


def _sweep_and_report(args: argparse.Namespace, module: Any, exp: Any, rows: Any, runs: Any,
                      options: dict[str, Any], invocation: Any) -> int:
    """Run ``exp`` into ``--out`` (checked first), then its report; exit 1 on errored runs."""
    overwrite = bool(getattr(args, "overwrite", False))
    out = folder.choose_out_dir(args.out, None, resume=args.resume,
                                overwrite=overwrite)  # nothing lost in silence
    check_writable(DEFAULT_RESULTS / exp.name if out is None else out)  # before the sweep
    if out is not None:
        folder.check_unlocked(out)
    check_sweep(module, exp, rows, runs, args.workers, args.scheduler)
    if out is None:  # made now: two sweeps started in the same second get two folders
        out = default_out_dir(exp.name, DEFAULT_RESULTS)
    start = time.perf_counter()
    with folder.sweep_lock(out):  # held until the report is written
        folder.choose_out_dir(out, None, resume=args.resume,  # again: another sweep may
                              overwrite=overwrite)  # have written there and ended since
        if overwrite:
            folder.clear_sweep(out)
        results = run_sweep(exp, out, rows=rows, runs=runs, workers=args.workers,
                            resume=args.resume, scheduler=args.scheduler,
                            progress=_progress_on(args.quiet), options=options)
        cf.warn_if_rebuilt_differs(invocation, out)
        wall = time.perf_counter() - start
        claims = exp.report(results, out)
        summary = (out / "table.md").read_text()
        if claims and options.get("quick"):  # a smoke test's verdicts mean nothing
            claims = f"{SMOKE_NOTE}\n\n{claims}"
        if claims:  # a study without a report has no claims
            summary += f"\n## Claims\n{claims}\n"
            atomic_write_text(out / "claims.md", f"## Claims\n{claims}\n")
        summary += f"\nwall time {wall:.1f} s\n"
    print(summary)
    n_error = int(results.get("n_error", 0))
    if n_error:
        print(f"{n_error} run(s) errored (bugs, not data): see {out / 'runs'}/*.json")
    if options.get("quick"):
        print("smoke test (--quick): these numbers and verdicts mean nothing about the "
              "claims; run without --quick for those")
    print(f"results: {out}")
    return 1 if n_error else 0


# -- bench ------------------------------------------------------------------------------
def cmd_bench(args: argparse.Namespace) -> int:
    from skinny_mj.cli import bench  # here: the bench's imports cost every command ~0.09 s

    if args.out is not None:  # before the bench, not after it
        check_new_file(args.out, args.overwrite)

    check_bench(args.workers, args.quick)
    figures = bench.run_with_bar(quick=args.quick, workers=args.workers,
                                 show=_progress_on(args.quiet))
    print(bench.table(figures))
    if args.out is not None:
        atomic_write_json(check_new_file(args.out, args.overwrite), figures)
        print(f"wrote {args.out}")
    return 0
