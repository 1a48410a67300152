"""One run as one rerun recording (``.rrd``, rerun-sdk 0.41).

Layout of the entity tree (``rerun run.rrd`` opens on the saved default blueprint):

- ``/skinny/<side>/<joint>/{desired,actual,command}``: joint angles in degrees and the
  normalized velocity command, on the timelines ``step`` (control step) and ``time`` (s).
- ``/signals/<signal>/{desired,actual,sensed}``: the normalized position signals.
- ``/pose/{desired,actual}``: both arms as 3D line strips (shoulder, elbow, wrist) in
  world metres; ``/pose/torso`` and ``/pose/head`` are static.
- ``/torques/<dof>/{commanded,applied,gravity,limit_upper,limit_lower}``: N m (torque body).
- ``/curves/<name>``: learning curves on their own timeline ``epoch``.
- ``/info``: a static Markdown document with the DOFs, their ranges and the metadata.

Determinism: log time and log tick are off, every series is sent columnar with explicit
timelines, the recording id is a hash of the inputs and the blueprint's view and
container ids are derived from their names, so two writes of the same run hold the same
data (``rerun rrd compare`` passes). The bytes still differ: rerun 0.41 mints chunk and
row ids (TUIDs) from the clock, gives the blueprint store a random id and writes chunks
from a background thread, and none of that can be set from the Python API.
"""

from __future__ import annotations

import hashlib
import json
import uuid
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from skinny_mj.errors import SkinnyEnvironmentError, SkinnyInputError
from skinny_mj.io import atomic_path
from skinny_mj.plant import body
from skinny_mj.preflight import check_free_space
from skinny_mj.recording_layout import (  # noqa: F401 (colours re-exported for tests)
    ACTUAL_RGB,
    DESIRED_RGB,
    ROLE_RGB,
    SENSED_RGB,
    TORSO_RGB,
    blueprint,
    dof_entity,
    series_style,
    torque_spans,
)

PELVIS_HEIGHT_M = 0.95
HEAD_CENTRE_M = (0.0, 0.0, 1.64)
HEAD_HALF_SIZES_M = (0.08, 0.095, 0.115)


def _as_2d(name: str, a: np.ndarray, rows: int, cols: int) -> np.ndarray:
    a = np.asarray(a, dtype=np.float64)
    if a.shape != (rows, cols):
        raise SkinnyInputError(f"{name} must have shape ({rows}, {cols}), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise SkinnyInputError(f"{name} contains NaN or inf")
    return a


def _recording_id(arrays: Sequence[np.ndarray | None], text: str) -> str:
    """A UUID made from the inputs, so the same run always gets the same recording id."""
    h = hashlib.sha256(text.encode("utf-8"))
    for a in arrays:
        if a is not None:
            h.update(np.ascontiguousarray(a, dtype=np.float64).tobytes())
    return str(uuid.UUID(bytes=h.digest()[:16]))


def _info_markdown(title: str, skinny: body.Body, dof_names: Sequence[str],
                   signal_names: Sequence[str], dt: float, steps: int,
                   metadata: Mapping[str, Any]) -> str:
    lines = [f"# {title or 'Skinny-MJ run'}", "",
             f"{skinny.dof} DOF, {steps} steps of {dt * 1000:g} ms ({steps * dt:.2f} s).", "",
             "| DOF | range (deg) |", "|---|---|"]
    ranges = np.degrees(skinny.joint_ranges())
    for i, name in enumerate(dof_names):
        rng = "?" if ranges is None else f"{ranges[i, 0]:.0f} .. {ranges[i, 1]:.0f}"
        lines.append(f"| {name} | {rng} |")
    lines += ["", "Signals: " + ", ".join(signal_names), "", "## Metadata", "", "```json",
              json.dumps(dict(metadata), indent=2, sort_keys=True, default=str), "```"]
    return "\n".join(lines)


def _send_series(rec, entity: str, values: np.ndarray, steps: np.ndarray, dt: float) -> None:
    import rerun as rr

    rec.send_columns(
        entity,
        indexes=[rr.TimeColumn("step", sequence=steps),
                 rr.TimeColumn("time", duration=steps * dt)],
        columns=rr.Scalars.columns(scalars=values),
    )


def _send_pose(rec, entity: str, angles: np.ndarray, skinny: body.Body, dt: float,
               rgb) -> None:
    import rerun as rr

    points = skinny.arm_points(angles)  # (T, 2 arms, 3 points, 3)
    n_steps = points.shape[0]
    steps = np.arange(n_steps)
    rec.log(entity, rr.LineStrips3D.from_fields(colors=[rgb], radii=[0.012]), static=True)
    rec.send_columns(
        entity,
        indexes=[rr.TimeColumn("step", sequence=steps),
                 rr.TimeColumn("time", duration=steps * dt)],
        columns=rr.LineStrips3D.columns(strips=points.reshape(-1, 3, 3)).partition(
            lengths=np.full(n_steps, 2)),
    )


def _log_body(rec, skinny: body.Body) -> None:
    import rerun as rr

    shoulders = skinny.shoulder_positions()
    neck = shoulders.mean(axis=0)
    pelvis = np.array([0.0, 0.0, PELVIS_HEIGHT_M])
    hips = pelvis + np.array([[-0.12, 0.0, 0.0], [0.12, 0.0, 0.0]])
    rec.log("/pose/torso", rr.LineStrips3D(
        [shoulders, [neck, pelvis], hips], colors=[TORSO_RGB], radii=[0.02]), static=True)
    rec.log("/pose/head", rr.Ellipsoids3D(
        centers=[HEAD_CENTRE_M], half_sizes=[HEAD_HALF_SIZES_M], colors=[TORSO_RGB]),
        static=True)


def write_recording(
    path: str | Path,
    *,
    dt: float,
    which: body.BodyLike,
    dof_names: Sequence[str],
    signal_names: Sequence[str],
    desired_angles: np.ndarray,
    actual_angles: np.ndarray,
    commands: np.ndarray,
    desired_signals: np.ndarray,
    actual_signals: np.ndarray,
    sensed_signals: np.ndarray | None = None,
    title: str = "",
    metadata: Mapping[str, Any] | None = None,
    curves: Mapping[str, np.ndarray] | None = None,
    application_id: str = "skinny-mj",
    torques: Mapping[str, np.ndarray] | None = None,
) -> Path:
    """Write one run as an ``.rrd`` file (atomically) with a default blueprint.

    Parameters
    ----------
    path : output file, conventionally ``run.rrd``.
    dt : control step, s.
    which : the body (:data:`skinny_mj.plant.body.BODIES`); its arm drawing and joint
        ranges.
    dof_names : (n_dof,) names in :attr:`skinny_mj.plant.body.Body.dof_names` order.
    signal_names : (n_sig,) names of the position signals.
    desired_angles, actual_angles : (T, n_dof) joint angles, rad.
    commands : (T-1, n_dof) normalized velocity commands in [-1, 1]; command t moves
        the plant from step t to t+1.
    desired_signals, actual_signals : (T, n_sig) normalized position signals.
    sensed_signals : optional (T, n_sig) noisy signals the controller saw.
    title : shown in the info document and as the recording name.
    metadata : JSON-able facts about the run (config, metrics), shown in the info document.
    curves : name -> (E,) per-epoch values, or (R, E) for R runs; logged on timeline
        ``epoch`` under ``/curves/<name>`` (``/curves/<name>/run_<r>`` for 2-D).
    application_id : rerun application id.
    torques : torque body, optional: ``commanded_nm`` and ``applied_nm``
        (T-1, n_dof) N m (command x limit; the motors' ``qfrc_actuator``),
        ``gravity_nm`` (T, n_dof) the bias torque of each state, ``limit_nm`` (n_dof,);
        logged under ``/torques/<dof>/{commanded,applied,gravity,limit_upper,limit_lower}``.

    Returns
    -------
    The path written.
    """
    import rerun as rr

    skinny = body.body_of(which)
    dof_names, signal_names = list(dof_names), list(signal_names)
    if dt <= 0:
        raise SkinnyInputError(f"dt must be positive, got {dt}")
    n_dof, n_sig = len(dof_names), len(signal_names)
    desired_angles = np.asarray(desired_angles, dtype=np.float64)
    n_steps = desired_angles.shape[0] if desired_angles.ndim == 2 else 0
    if n_steps < 2:
        raise SkinnyInputError(f"need at least 2 steps, desired_angles has shape "
                               f"{desired_angles.shape}")
    desired_angles = _as_2d("desired_angles", desired_angles, n_steps, n_dof)
    actual_angles = _as_2d("actual_angles", actual_angles, n_steps, n_dof)
    commands = _as_2d("commands", commands, n_steps - 1, n_dof)
    desired_signals = _as_2d("desired_signals", desired_signals, n_steps, n_sig)
    actual_signals = _as_2d("actual_signals", actual_signals, n_steps, n_sig)
    if sensed_signals is not None:
        sensed_signals = _as_2d("sensed_signals", sensed_signals, n_steps, n_sig)
    curve_arrays = {k: np.atleast_1d(np.asarray(v, dtype=np.float64))
                    for k, v in (curves or {}).items()}
    for k, v in curve_arrays.items():
        if v.ndim > 2:
            raise SkinnyInputError(f"curve {k!r} must be (E,) or (R, E), got {v.shape}")
    metadata = dict(metadata or {})
    info = _info_markdown(title, skinny, dof_names, signal_names, dt, n_steps, metadata)
    rec_id = _recording_id(
        [desired_angles, actual_angles, commands, desired_signals, actual_signals,
         sensed_signals, *curve_arrays.values(), *(torques or {}).values()],
        json.dumps([dt, skinny.dof, dof_names, signal_names, title, application_id,
                    sorted(curve_arrays)]) + info,
    )

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    # A recording is ~6 bytes per logged value (0.53 MB for YMCA in 2D); x4 plus slack.
    logged = [desired_angles, actual_angles, commands, desired_signals, actual_signals,
              sensed_signals, *curve_arrays.values(), *(torques or {}).values()]
    check_free_space(path.parent, (8 << 20) + 4 * sum(np.asarray(a).nbytes for a in logged
                                                       if a is not None))
    with atomic_path(path) as tmp:
        rec = rr.RecordingStream(application_id, recording_id=rec_id, send_properties=False)
        rec.set_log_time_enabled(False)
        rec.set_log_tick_enabled(False)
        _io(path, rec.save, tmp, default_blueprint=blueprint(
            bool(curve_arrays), application_id, dof_names, (n_steps - 1) * dt,
            None if torques is None else torque_spans(dof_names, torques)))
        if title:
            rec.send_recording_name(title)
        rec.log("/info", rr.TextDocument(info, media_type=rr.MediaType.MARKDOWN), static=True)
        _log_body(rec, skinny)
        steps = np.arange(n_steps)
        roles = [("desired", desired_angles), ("actual", actual_angles)]
        for i, name in enumerate(dof_names):
            entity = dof_entity(name)
            for role, angles in roles:
                _log_style(rec, f"{entity}/{role}", *series_style(name, role))
                _send_series(rec, f"{entity}/{role}", np.degrees(angles[:, i]), steps, dt)
            _log_style(rec, f"{entity}/command", *series_style(name, "command"))
            _send_series(rec, f"{entity}/command", commands[:, i], steps[:-1], dt)
        sig_roles = [("desired", desired_signals), ("actual", actual_signals)]
        if sensed_signals is not None:
            sig_roles.append(("sensed", sensed_signals))
        for j, name in enumerate(signal_names):
            for role, sig in sig_roles:
                _log_style(rec, f"/signals/{name}/{role}", role, ROLE_RGB[role])
                _send_series(rec, f"/signals/{name}/{role}", sig[:, j], steps, dt)
        if torques is not None:
            _log_torques(rec, torques, dof_names, steps, dt)
        _send_pose(rec, "/pose/desired", desired_angles, skinny, dt, DESIRED_RGB)
        _send_pose(rec, "/pose/actual", actual_angles, skinny, dt, ACTUAL_RGB)
        for name, values in curve_arrays.items():
            rows = [values] if values.ndim == 1 else list(values)
            for r, row in enumerate(rows):
                entity = f"/curves/{name}" if values.ndim == 1 else f"/curves/{name}/run_{r}"
                rec.send_columns(entity,
                                 indexes=[rr.TimeColumn("epoch", sequence=np.arange(len(row)))],
                                 columns=rr.Scalars.columns(scalars=row))
        _io(path, rec.flush, timeout_sec=FLUSH_TIMEOUT_S)
        rec.disconnect()
    return path


#: Longest wait for rerun's file writer: with no timeout a writer thread that died (a
#: full disk) can leave flush() waiting forever.
FLUSH_TIMEOUT_S = 120.0


def _io(path: Path, call: Any, *args: Any, **kwargs: Any) -> None:
    """``call(*args, **kwargs)``, rerun's write failures (a RuntimeError: full disk, dead
    writer thread, timeout) turned into one-line environment errors naming ``path``."""
    try:
        call(*args, **kwargs)
    except RuntimeError as exc:
        raise SkinnyEnvironmentError(f"cannot write the recording {path}: {exc}") from None


def _log_style(rec, entity: str, label: str, rgb, width: float | None = None) -> None:
    import rerun as rr

    rec.log(entity, rr.SeriesLines(colors=[rgb], names=[label],
                                   widths=None if width is None else [width]), static=True)


def recording_entities(path: str | Path) -> list[str]:
    """Sorted entity paths of the recording store in ``path`` (rerun's own reader)."""
    from rerun.chunk import RrdReader

    return sorted({chunk.entity_path for chunk in RrdReader(str(path)).stream()})


def read_recording_series(path: str | Path, entity: str, timeline: str | None = None
                          ) -> np.ndarray:
    """Read one scalar series back with rerun's reader.

    Parameters
    ----------
    path : an ``.rrd`` written by :func:`write_recording`.
    entity : entity path, e.g. ``/skinny/right/shoulder_abduction/actual``.
    timeline : index to order by; default ``step`` (``epoch`` under ``/curves``).

    Returns
    -------
    (n,) float64 values ordered by the timeline.
    """
    from rerun.chunk import RrdReader

    path = Path(path)
    if not path.is_file():
        raise SkinnyInputError("no such recording", path=path)
    if timeline is None:
        timeline = "epoch" if entity.startswith("/curves") else "step"
    index: list[np.ndarray] = []
    values: list[np.ndarray] = []
    for chunk in RrdReader(str(path)).stream():
        if chunk.entity_path != entity or chunk.is_static:
            continue
        batch = chunk.to_record_batch()
        names = batch.schema.names
        if timeline not in names or "Scalars:scalars" not in names:
            continue
        index.append(batch.column(timeline).to_numpy(zero_copy_only=False).astype(np.int64))
        lists = batch.column("Scalars:scalars").to_pylist()
        values.append(np.array([v[0] if v else np.nan for v in lists], dtype=np.float64))
    if not values:
        raise SkinnyInputError(f"no scalar series {entity!r} on timeline {timeline!r}",
                               path=path)
    idx, val = np.concatenate(index), np.concatenate(values)
    return val[np.argsort(idx, kind="stable")]


def _log_torques(rec, torques: Mapping[str, np.ndarray], dof_names: list[str],
                 steps: np.ndarray, dt: float) -> None:
    """The torque series of :func:`write_recording` (``torques``), N m."""
    limit = np.asarray(torques["limit_nm"], float)
    bound = np.broadcast_to(limit, (len(steps), len(limit)))
    series = {"commanded": (torques["commanded_nm"], steps[:-1]),
              "applied": (torques["applied_nm"], steps[:-1]),
              "gravity": (torques["gravity_nm"], steps),
              "limit_upper": (bound, steps), "limit_lower": (-bound, steps)}
    for i, name in enumerate(dof_names):
        for role, (values, t) in series.items():
            entity = f"/torques/{name}/{role}"
            _log_style(rec, entity, *series_style(name, role))
            _send_series(rec, entity, np.asarray(values, float)[:, i].copy(), t, dt)


def record_test(path: str | Path, outcome: Any, title: str,
                metadata: Mapping[str, Any] | None = None, *,
                figures: Mapping[str, Any] | None = None) -> Path:
    """Write the closed-loop test of a trained run (a
    :class:`skinny_mj.training.result.RunResult`) as one ``.rrd``: desired vs actual angles
    and signals, commands, the arms in 3D, and the training curve; ``figures``: the
    test's figures for the recording's metadata
    (:func:`skinny_mj.engine.results.test_figures`)."""
    test, cfg, ro = outcome.test, outcome.config, outcome.test.rollout
    curve = outcome.train.position_nrmse
    curves = None
    if isinstance(curve, list) and curve:
        curves = {"train_position_nrmse": np.array([np.nan if v is None else v for v in curve],
                                                   dtype=float)}
    meta = {"seed": outcome.seed, "test": dict(figures or {}),
            "movement": cfg.movement.trajectory, **(metadata or {})}
    skinny = body.body_of(cfg.plant.body)
    return write_recording(
        path, dt=test.trajectory.dt, which=skinny, dof_names=list(skinny.dof_names),
        signal_names=list(skinny.signal_names(cfg.plant.signals)),
        desired_angles=test.trajectory.angles, actual_angles=ro.angles[0],
        commands=ro.commands[0], desired_signals=test.desired,
        actual_signals=ro.true_signals[0], sensed_signals=ro.sensed[0], title=title,
        metadata=meta, curves=curves,
        torques=None if test.torque is None else test.torque["series"],
    )
