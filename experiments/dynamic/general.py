"""The torque twin's ``general`` preset: trained once, tested on movements it never saw.

A row of :mod:`skinny_mj.experiments.dynamic.study` whose ``params["tests"]`` names test
columns (:data:`TESTS`) runs as :data:`SHAPE` says: the engine trains the row's seeds in
lockstep (nothing, for a controller alone such as computed torque, ``arm-ct``), then tests
them at the row's K on every column. A ``floor`` row (:func:`floor_batch`) computes the least error
the torque limits allow on each column (iLQR knowing the true model and the whole
movement): what no controller can beat, the bound a learned one is measured against.
The shipped CMU clips need more torque than the motors have at full speed
(:func:`skinny_mj.training.torque.feasibility`), so each is a column twice: as shipped
(``md_02``, ``md_03``) and slowed to the fastest speed at which no step of its inverse
dynamics exceeds a limit (``md_02-feasible``; :data:`FEASIBLE_SPEED`, per body). The
learned rows and computed torque also take the clip re-timed locally to the limits
(``md_02-retimed``: ``md_02.amc@feasible``, TOPP-RA, slower only where a torque would pass
0.9 of its limit) and a speed curve (``md_02-x0.5``: the whole clip at 0.5×;
:data:`CURVE_SPEEDS`); the floor rows take :data:`FLOOR_TESTS` only.

Metrics per run: per column ``<col>__position_nrmse`` (test, K as the row's
``test.gain``), ``<col>__max_torque_ratio`` (max |commanded| or |applied| torque over
the limit) and ``<col>__limit_overshoot_rad``; the training movement's own
``train_position_nrmse`` (last epoch); ``n_test_failed`` (columns on which the run
diverged).
"""

from __future__ import annotations

import functools
import statistics
import time

from skinny_mj.experiments.claims import values

from skinny_mj import training
from skinny_mj.engine.results import train_failure
from skinny_mj.engine.stats import load_runs
from skinny_mj.engine.study import Shape, Test
from skinny_mj.plots import pyplot, save_figure
from skinny_mj.training.config import TrainConfig
from skinny_mj.training.imitation import TORQUE_METRICS
from skinny_mj.training.result import RunResult

#: Fastest speed (a factor of the clip's own, on a 0.01 grid from 0.6 down) at and below
#: which no step of the clip's inverse dynamics exceeds a torque limit, per body (dof).
#: Declared (the rows' results rest on them), and equal to the computation,
#: :func:`skinny_mj.training.feasible.fastest_uniform_speed` (tests/test_retime.py).
#: The clip re-timed locally instead (slower only where the limits need it):
#: ``md_02.amc@feasible``.
FEASIBLE_SPEED = {(4, "md_02.amc"): 0.18, (4, "md_03.amc"): 0.27,
                  (8, "md_02.amc"): 0.45, (8, "md_03.amc"): 0.44}
#: The speeds (factors of the clip's own) of the error-against-speed curve, beside 1 and
#: the body's feasible speed.
CURVE_SPEEDS = (0.25, 0.35, 0.5, 0.7)
CLIPS = ("md_02", "md_03")
#: Test column id -> (movement, speed: a factor, or None for the body's feasible speed).
TESTS = {"md_02": ("md_02.amc", 1.0), "md_03": ("md_03.amc", 1.0),
         "md_02-feasible": ("md_02.amc", None), "md_03-feasible": ("md_03.amc", None),
         "ymca": ("ymca", 1.0),
         **{f"{c}-retimed": (f"{c}.amc@feasible", 1.0) for c in CLIPS},
         **{f"{c}-x{v:g}": (f"{c}.amc", v) for c in CLIPS for v in CURVE_SPEEDS}}
#: The floor rows' columns (iLQR costs minutes per column; a re-timed clip is feasible
#: by construction, its floor near 0).
FLOOR_TESTS = ("md_02", "md_03", "md_02-feasible", "md_03-feasible", "ymca")
#: The unseen clips' columns the preset's goal is read on.
CLIP_COLUMNS = ("md_02", "md_03", "md_02-feasible", "md_03-feasible")
#: The held-out choice (group ``held-out``): candidate settings of the torque general
#: preset as it ships (the robot's sensing), per body, declared before any ran: name ->
#: changes to the preset's keys. One is chosen on one clip re-timed locally to the limits
#: (lowest mean position NRMSE) and scored on the other (:func:`held_out_lines`).
HELD_OUT = {4: {"preset": {}, "epochs15": {"method.epochs": 15},
                "omega10": {"actuation.omega": 10.0}, "forget0.9": {"method.fit.forgetting": 0.9}},
            8: {"preset": {}, "epochs30": {"method.epochs": 30},
                "omega10": {"actuation.omega": 10.0}, "forget0.8": {"method.fit.forgetting": 0.8}}}
HELD_OUT_TESTS = ("md_02-retimed", "md_03-retimed", "md_02-feasible", "md_03-feasible")
HELD_OUT_RUNS = 5


def speed_of(column: str, dof: int) -> float:
    """The speed factor test column ``column`` plays its movement at on body ``dof``."""
    movement, speed = TESTS[column]
    return FEASIBLE_SPEED[dof, movement] if speed is None else speed


@functools.lru_cache(maxsize=32)
def load_test(column: str, dof: int):
    """Test column ``column``'s movement for body ``dof`` (cached)."""
    # training.feasible: NAME@feasible too (it loads MuJoCo, on first use)
    return training.feasible.load_movement(TESTS[column][0], dof,
                                           speed=speed_of(column, dof))[0]


def _movement(column: str, config: TrainConfig):
    return load_test(column, config.plant.dof)


def tests(config: TrainConfig, row) -> tuple[Test, ...]:
    """A test on every column of ``row.params["tests"]`` (the row's K, a fresh plant)."""
    return tuple(Test(col, movement=functools.partial(_movement, col))
                 for col in row.params["tests"])


def metrics(result: RunResult) -> dict:
    """One run's file: the training's last epoch (a learned row), per column its figures
    (a column whose test diverged counts in ``n_test_failed``), the wall times."""
    train = result.train
    out: dict = {"train_wall_s": result.train_wall_s, "n_test_failed": 0,
                 **({} if train.kind == "none" else
                    {"train_position_nrmse": train.last_position_nrmse})}
    for col, test in result.tests.items():
        if test.failed:
            out["n_test_failed"] += 1
            continue
        tq = test.torque["metrics"]
        out.update({f"{col}__position_nrmse": test.position_nrmse,
                    f"{col}__max_torque_ratio": max(tq["max_commanded_ratio"],
                                                     tq["max_applied_ratio"]),
                    f"{col}__limit_overshoot_rad": tq["limit_overshoot_rad"]})
        # joint error (deg), hand error (cm), lag (s), RMS torque (N m), |work| (J)
        robot = {**test.robot_metrics(result.config.plant.body),
                 **{k: tq[k] for k in TORQUE_METRICS}}
        out.update({f"{col}__{k}": v for k, v in robot.items()})
    out["wall_s"] = result.wall_s
    return out


#: A general row's run: trained once in lockstep (nothing for a controller alone), then
#: tested on every column; a diverged training fails the run, a diverged test is counted.
SHAPE = Shape(metrics, tests=tests, failure=train_failure)


def floor_batch(config: TrainConfig, row, seeds: list[int]) -> list:
    """The torque-limited floor (:func:`skinny_mj.training.floor.torque_floor`: iLQR with
    the true model, the whole movement known, commands within the limits) on every column
    of ``row.params["tests"]``. Deterministic: every seed gets the same figures."""
    dof, out = config.plant.dof, {}
    start = time.perf_counter()
    for col in row.params["tests"]:
        movement = load_test(col, dof)
        floor = training.floor.torque_floor(movement, dof, iterations=row.params["iterations"],
                             tolerance=1e-5)
        figures = floor.metrics(movement.angles, dof, movement.dt)
        out[f"{col}__position_nrmse"] = floor.joint_nrmse
        out[f"{col}__max_torque_ratio"] = figures.pop("max_command")
        out.update({f"{col}__{k}": v for k, v in figures.items() if k != "joint_nrmse"})
    out.update(train_wall_s=0.0, n_test_failed=0, wall_s=time.perf_counter() - start)
    return [dict(out) for _ in seeds]


#: The goal for the ESN alone (K = 0) on the unseen clips, position NRMSE: a target to
#: measure against, not a number tuned to
GOAL = 0.02
#: ... and in RMS joint error (degrees) on the clips re-timed locally to the limits
GOAL_DEG = 3.0


def _cell(v: list[float]) -> str:
    if not v:
        return "—"
    return f"{statistics.fmean(v):.4f} ± {statistics.stdev(v) if len(v) > 1 else 0.0:.4f}"


def report_lines(out_dir, rows: tuple[str, ...], bodies: dict[str, int]) -> list[str]:
    """A markdown table of the general rows swept (position NRMSE per test column, mean ±
    sd over the ok runs), each body's computed-torque floor first, then the goal per
    preset row. The run files are read once."""
    get = functools.partial(values, out_dir, runs=load_runs(out_dir))
    lines = []
    for bd, dof in bodies.items():
        mine = [r for r in rows if r.startswith(f"{bd}-general")]
        # the floor, then computed torque, then the learned rows
        mine.sort(key=lambda r: (not r.endswith("-floor"), not r.endswith("-arm-ct")))
        if not any(get(r, "train_wall_s") for r in mine):
            continue
        head = " | ".join(f"{c} @ {speed_of(c, dof):g}" for c in FLOOR_TESTS)
        lines += [f"torque general, {bd}: position NRMSE per test column (the ESN alone, "
                  "K = 0; the arm-ct row: computed torque alone; the floor row: iLQR with "
                  "the true model and the whole movement known, the least error the torque "
                  "limits allow)",
                  f"| row | n | {head} |", "|---|---|" + "---|" * len(FLOOR_TESTS)]
        for r in mine:
            n = len(get(r, "train_wall_s"))
            if n:
                cells = " | ".join(_cell(get(r, f"{c}__position_nrmse"))
                                   for c in FLOOR_TESTS)
                lines.append(f"| {r} | {n} | {cells} |")
        preset = f"{bd}-general"
        for c in CLIP_COLUMNS:
            v = get(preset, f"{c}__position_nrmse")
            ct = get(f"{bd}-general-arm-ct", f"{c}__position_nrmse")
            floor = get(f"{bd}-general-floor", f"{c}__position_nrmse")
            if v:
                lines.append(f"goal {bd} torque general preset on unseen {c} (@ "
                             f"{speed_of(c, dof):g}) <= {GOAL}: {_cell(v)}, "
                             f"{sum(x <= GOAL for x in v)} / {len(v)} runs; computed "
                             f"torque {_cell(ct)}; floor {_cell(floor)}")
        lines += speed_curve_lines(get, mine, bd, dof)
        lines += held_out_lines(get, bd, dof)
        if (png := speed_curve_png(get, f"{out_dir}/speed_{bd}.png", mine, bd, dof)) is not None:
            lines.append(f"figure: {png}")
    return lines


def speed_curve_png(get, path: str, rows: list[str], bd: str, dof: int):
    """The figure at ``path``: per clip, position NRMSE (mean ± sd over runs) against the
    speed the whole clip plays at, per row with the curve, the locally re-timed clip as a
    marker at full speed; None without data. ``get(row, metric)``: the runs' values."""
    have = [r for r in rows if get(r, f"{CLIPS[0]}-x{CURVE_SPEEDS[0]:g}__position_nrmse")]
    if not have:
        return None
    plt = pyplot()
    fig, axes = plt.subplots(1, len(CLIPS), figsize=(9.6, 3.8), sharey=True)
    for ax, clip in zip(axes, CLIPS, strict=True):
        cols = curve_columns(clip, dof)
        x = [speed_of(c, dof) for c in cols]
        for k, r in enumerate(have):
            runs = [get(r, f"{c}__position_nrmse") for c in cols]
            mean = [statistics.fmean(v) for v in runs]
            sd = [statistics.stdev(v) if len(v) > 1 else 0.0 for v in runs]
            line = ax.errorbar(x, mean, yerr=sd, marker="o", capsize=3, label=r)
            timed = get(r, f"{clip}-retimed__position_nrmse")
            ax.plot([1.0], [statistics.fmean(timed)], marker="*", markersize=12,
                    color=line[0].get_color(), linestyle="none",
                    label="re-timed locally" if k == 0 else None)
        ax.axhline(GOAL, color="grey", linestyle=":", label=f"goal {GOAL}")
        ax.axvline(speed_of(f"{clip}-feasible", dof), color="grey", alpha=0.4)
        ax.set(xlabel="speed of the whole clip (× its own)", title=f"{clip}, {bd}",
               yscale="log")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("position NRMSE (K = 0)")
    axes[-1].legend(fontsize=7)
    return save_figure(fig, path)


def curve_columns(clip: str, dof: int) -> list[str]:
    """``clip``'s columns of the speed curve, slowest first (the feasible speed among
    them), then the full speed."""
    cols = [f"{clip}-x{v:g}" for v in CURVE_SPEEDS] + [f"{clip}-feasible", clip]
    return sorted(cols, key=lambda c: speed_of(c, dof))


def speed_curve_lines(get, rows: list[str], bd: str, dof: int) -> list[str]:
    """Position NRMSE (and RMS joint error in degrees) against the clip's speed, per row
    that has the curve's columns, and the clips re-timed locally to the limits.
    ``get(row, metric)``: the runs' values."""
    lines = []
    for clip in CLIPS:
        cols = curve_columns(clip, dof)
        have = [r for r in rows if get(r, f"{cols[0]}__position_nrmse")]
        if not have:
            continue
        lines += [f"torque general, {bd}, {clip}: position NRMSE (RMS joint error, deg) "
                  "against the speed the whole clip plays at; 'retimed': the clip re-timed "
                  "locally to 0.9 of the torque limits (full speed elsewhere)",
                  "| row | " + " | ".join(f"× {speed_of(c, dof):g}" for c in cols)
                  + " | retimed |", "|---|" + "---|" * (len(cols) + 1)]
        for r in have:
            cells = [f"{_mean(get(r, f'{c}__position_nrmse'))} "
                     f"({_mean(get(r, f'{c}__rms_error_deg'), 2)})"
                     for c in (*cols, f"{clip}-retimed")]
            lines.append(f"| {r} | " + " | ".join(cells) + " |")
        preset = f"{bd}-general"
        v = get(preset, f"{clip}-retimed__position_nrmse")
        deg = get(preset, f"{clip}-retimed__rms_error_deg")
        if v:
            lines.append(f"goal {bd} torque general preset on unseen {clip} re-timed locally "
                         f"to the limits <= {GOAL} and <= {GOAL_DEG:g} deg RMS: {_cell(v)}, "
                         f"{_mean(deg, 2)} deg, {sum(x <= GOAL for x in v)} / {len(v)} runs")
    return lines


def held_out_lines(get, bd: str, dof: int) -> list[str]:
    """The held-out choice (:data:`HELD_OUT`): each candidate's position NRMSE (RMS joint
    error, deg) on the clips re-timed locally to the limits, then per direction the
    candidate chosen on one clip and its score on the other, against the goal.
    ``get(row, metric)``: the runs' values."""
    names = [n for n in HELD_OUT[dof] if get(f"{bd}-heldout-{n}", "train_wall_s")]
    if not names:
        return []
    cols = [f"{c}-retimed" for c in CLIPS]
    lines = [f"torque general, {bd}, held-out choice: candidates of the preset (the robot's "
             "sensing), position NRMSE (RMS joint error, deg) on the clips re-timed locally "
             "to the limits, ESN alone (K = 0)",
             "| candidate | n | " + " | ".join(cols) + " |", "|---|---|" + "---|" * len(cols)]
    for n in names:
        r = f"{bd}-heldout-{n}"
        lines.append(f"| {n} | {len(get(r, 'train_wall_s'))} | " + " | ".join(
            f"{_cell(get(r, f'{c}__position_nrmse'))} ({_mean(get(r, f'{c}__rms_error_deg'), 2)})"
            for c in cols) + " |")
    for chose, scored in (cols, cols[::-1]):
        best = min(names, key=lambda n: statistics.fmean(
            get(f"{bd}-heldout-{n}", f"{chose}__position_nrmse") or [float("inf")]))
        v = get(f"{bd}-heldout-{best}", f"{scored}__position_nrmse")
        deg = get(f"{bd}-heldout-{best}", f"{scored}__rms_error_deg")
        if v:
            lines.append(
                f"goal {bd} held out: chosen on {chose} ({best}), scored on {scored} <= "
                f"{GOAL} and <= {GOAL_DEG:g} deg RMS: {_cell(v)}, {_mean(deg, 2)} deg, "
                f"{sum(x <= GOAL for x in v)} / {len(v)} runs")
    return lines


def _mean(v: list[float], digits: int = 4) -> str:
    return f"{statistics.fmean(v):.{digits}f}" if v else "—"
