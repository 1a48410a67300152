"""Repeating a run from the files it wrote: ``skinny train --config``, ``skinny experiment
--config``.

``skinny train`` writes ``metrics.json`` with the run's whole :class:`TrainConfig`
(``config``, flat dotted keys) and its ``seed``; a sweep writes ``config.json`` with the
CLI options (``options``: quick, movement, asf, body, signals), the selection of rows and
the runs per row. Fed back, each repeats the run exactly; a flag given on the command line
as well overrides that one setting (only the flags given reach ``skinny train``'s
arguments; ``skinny experiment``'s ``args.given``, from :func:`skinny_mj.cli.parser.given_options`,
says which were given: argparse defaults never override a file). A ``metrics.json`` or
config file of an earlier version (flat fields such as ``"reservoir": 200``) is read
through :data:`skinny_mj.training.config.LEGACY_KEYS`.
"""

from __future__ import annotations

import argparse
import json
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from skinny_mj.cli.config_flags import (
    TRAIN_FLAGS,
    changes,
    check_no_conflict,
    flag_names,
    given,
    pairs,
)
from skinny_mj.errors import SkinnyInputError
from skinny_mj.training.config import DERIVED, TrainConfig
from skinny_mj.training.legacy import is_legacy
from skinny_mj.training.overrides import renamed
from skinny_mj.training.presets import preset_fields, torque_defaults
from skinny_mj.trajectories.library import check_asf

_log = logging.getLogger(__name__)

__all__ = ["read_json", "read_train_file", "file_config", "train_config", "SweepInvocation",
           "sweep_invocation", "apply_sweep_config", "check_experiment",
           "warn_if_rebuilt_differs"]

#: The CLI options a sweep's ``config.json`` records (``options``): ``build`` takes them, but
#: ``protocol``, which is applied to the study before it is built.
SWEEP_OPTIONS = ("quick", "movement", "asf", "body", "signals", "protocol")
#: An earlier version's options: ``dof`` (4 or 8) is ``body`` by its number of hinges.
_OLD_OPTIONS = {"dof": "body"}


def read_json(path: str | Path) -> dict[str, Any]:
    """A JSON object from ``path``; anything else is a :class:`SkinnyInputError`."""
    path = Path(path)
    if path.is_dir():
        raise SkinnyInputError("a folder, not a config file", path=path)
    if not path.is_file():
        raise SkinnyInputError("no such config file", path=path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as err:
        raise SkinnyInputError(f"not a JSON config file ({err})", path=path) from None
    if not isinstance(data, dict):
        raise SkinnyInputError("a config file holds a JSON object", path=path)
    return data


#: The JSON other commands write, told apart from a training config by their keys.
_OTHER_FILES = [
    (lambda d: "model" in d and "test" in d, "a `skinny test` run's metrics.json"),
    (lambda d: "position_nrmse" in d and "max_speed_rad_s" in d,
     "a `skinny track` run's metrics.json"),
    (lambda d: "load_avg_start" in d or "esn_run_vs_reservoirpy" in d,
     "`skinny bench`'s results"),
    (lambda d: "experiment" in d and "n_runs" in d, "a sweep's results.json"),
]


def read_train_file(path: str | Path) -> tuple[dict[str, Any], int | None]:
    """The TrainConfig dict and seed in ``path``: a run's ``metrics.json`` (its
    ``config`` and ``seed``) or a bare TrainConfig dict (seed None)."""
    data = read_json(path)
    if "experiment" in data and "options" in data:
        raise SkinnyInputError("this is a sweep's config.json: repeat it with `skinny "
                               f"experiment {data['experiment']} --config {path}`", path=path)
    if not isinstance(data.get("config"), dict):
        for looks, what in _OTHER_FILES:
            if looks(data):
                raise SkinnyInputError(f"this is {what}, which holds no training config: give "
                                       "a `skinny train` run's metrics.json or a config of "
                                       "dotted keys (esn.n_reservoir, ...)", path=path)
        nested = [k for k, v in data.items() if isinstance(v, dict) and "." not in k]
        if nested:  # {"esn": {"n_reservoir": 20}}: the keys are flat and dotted
            inner = next(iter(data[nested[0]]), "KEY")
            raise SkinnyInputError(f"config keys are flat and dotted: write "
                                   f"\"{nested[0]}.{inner}\": ..., not a section "
                                   f"\"{nested[0]}\": {{...}}", path=path)
    if isinstance(data.get("config"), dict):
        seed = data.get("seed")
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int)
                                 or seed < 0):
            raise SkinnyInputError(f"seed must be a whole number >= 0, got {seed!r}", path=path)
        return dict(data["config"]), seed
    return data, None


def file_config(path: str | Path) -> TrainConfig:
    """The TrainConfig a config file holds (a run's ``metrics.json`` or a bare config;
    its seed, if any, is not part of it)."""
    fields, _ = read_train_file(path)
    return _make(fields, Path(path), TrainConfig())


def _make(fields: dict[str, Any], path: Path | None, base: TrainConfig | None = None
          ) -> TrainConfig:
    """The config of a file's ``fields`` (today's dotted keys over ``base``, or an earlier
    version's flat fields); a bad field names the file."""
    try:
        if base is None or is_legacy(fields):
            return TrainConfig.from_dict(fields)
        return base.override({k: v for k, v in fields.items() if k not in DERIVED})
    except SkinnyInputError as err:
        if path is None:
            raise
        raise SkinnyInputError(str(err), path=path) from None


def train_config(args: argparse.Namespace) -> tuple[TrainConfig, int]:
    """The run ``skinny train`` was asked for, and its seed: ``TrainConfig()``, then
    ``--preset``'s keys, then ``--config FILE``'s (and its seed), then the flags and
    ``KEY=VALUE`` overrides given (:mod:`skinny_mj.cli.config_flags`). A run on a torque
    body without ``--preset`` starts from the torque body's defaults instead of
    ``TrainConfig()``: :func:`skinny_mj.training.presets.torque_defaults`."""
    flags = given(args, TRAIN_FLAGS)
    keyed = renamed(TrainConfig(), pairs(getattr(args, "overrides", None) or []))
    check_no_conflict(flags, keyed, flag_names(TRAIN_FLAGS))
    texts = {**flags, **keyed}
    names = {k: f for k, f in flag_names(TRAIN_FLAGS).items() if k in flags and k not in keyed}
    base = TrainConfig()
    if getattr(args, "preset", None) is None:
        body = _body_asked(args, texts, names)
        if body.torque is not None:  # the torque body's own defaults
            base = base.override({**torque_defaults(body.plant.dof),
                                  "plant.body": body.plant.body})
    return _settings(args, texts, keyed, names, base)


#: the keys that choose the body and its actuation
_BODY_KEYS = ("plant.body", "actuation", "plant.dof")


def _body_asked(args: argparse.Namespace, texts: dict[str, Any], names: dict[str, str]
                ) -> TrainConfig:
    """TrainConfig() on the body (and actuation) the run asks for: ``--config FILE``'s,
    then the flags'."""
    cfg = TrainConfig()
    if getattr(args, "config", None) is not None:
        path = Path(args.config)
        fields, _ = read_train_file(path)
        if not is_legacy(fields):
            cfg = _make({k: fields[k] for k in _BODY_KEYS if k in fields}, path, cfg)
    asked = {k: texts[k] for k in _BODY_KEYS if k in texts}
    return cfg.override(changes(cfg, asked, {k: v for k, v in names.items() if k in asked}))


def _settings(args: argparse.Namespace, texts: dict[str, Any], keyed: dict[str, Any],
              names: dict[str, str], cfg: TrainConfig) -> tuple[TrainConfig, int]:
    """``cfg``, then ``--preset``'s keys, then ``--config FILE``'s, then the flags."""
    texts, names, seed = dict(texts), dict(names), None
    preset = getattr(args, "preset", None)
    if preset is not None:
        fields = preset_fields(preset, str(texts.get("actuation", "velocity")),
                               dof=texts.get("plant.dof"), signals=texts.get("plant.signals"),
                               body=texts.get("plant.body"))
        cfg = cfg.override(fields)
        # --signals chose a preset that refines them (cartesian -> cartesian-elbow): keep it
        if "plant.signals" not in keyed and str(fields.get("plant.signals")).startswith(
                f"{texts.get('plant.signals')}-"):
            texts.pop("plant.signals")
            names.pop("plant.signals", None)
    if getattr(args, "config", None) is not None:
        path = Path(args.config)
        fields, seed = read_train_file(path)
        cfg = _make(fields, path, cfg)
    cfg = cfg.override(changes(cfg, texts, names))
    if {"movement.asf", "movement.retarget"} & texts.keys():  # not for a movement without
        check_asf(cfg.movement.trajectory, cfg.movement.asf, cfg.movement.retarget)  # mocap
    if getattr(args, "seed", None) is not None:
        seed = int(args.seed)
    return cfg, 0 if seed is None else seed


@dataclass(frozen=True)
class SweepInvocation:
    """What a sweep's ``config.json`` asks ``build`` and ``run_sweep`` for, with the
    command line's flags applied (``recorded`` is the file as read)."""

    options: dict[str, Any]
    rows: list[str] | None
    runs: int | None
    recorded: dict[str, Any]


def sweep_invocation(args: argparse.Namespace, name: str, options: dict[str, Any],
                     rows: list[str] | None) -> SweepInvocation:
    """Merge ``--config FILE`` (a sweep's ``config.json``) with the flags given.

    Parameters
    ----------
    args : the parsed ``skinny experiment`` arguments (``config``, ``given``, ``runs``).
    name : the experiment's registered name (``skinny experiment NAME``).
    options, rows : the command line's options dict and row selection.
    """
    path = Path(args.config)
    data = read_json(path)
    recorded_opts = data.get("options")
    selection = data.get("selection")
    if not isinstance(recorded_opts, dict) or not isinstance(selection, dict):
        raise SkinnyInputError("not a sweep's config.json (no options or selection); a "
                               "training run's file goes to `skinny train --config`",
                               path=path)
    recorded_opts = {_OLD_OPTIONS.get(k, k): v for k, v in recorded_opts.items()}
    unknown = sorted(set(recorded_opts) - set(SWEEP_OPTIONS))
    if unknown:
        raise SkinnyInputError(f"unknown sweep option(s) {unknown}", path=path)
    given = getattr(args, "given", set())
    merged = {k: options[k] if k in given else recorded_opts.get(k, options[k])
              for k in SWEEP_OPTIONS}
    merged["quick"] = bool(merged["quick"])
    requested = selection.get("requested")
    if requested is not None and not (isinstance(requested, list)
                                      and all(isinstance(e, str) for e in requested)):
        raise SkinnyInputError(f"selection.requested must be a list of row ids, got "
                               f"{requested!r}", path=path)
    runs = data.get("runs")
    if runs is not None and (isinstance(runs, bool) or not isinstance(runs, int) or runs < 1):
        raise SkinnyInputError(f"runs must be a whole number >= 1, got {runs!r}", path=path)
    return SweepInvocation(
        options=merged, rows=rows if "rows" in given else requested,
        runs=args.runs if "runs" in given else runs, recorded=data)


def apply_sweep_config(args: argparse.Namespace, options: dict[str, Any],
                       rows: list[str] | None
                       ) -> tuple[dict[str, Any], list[str] | None, int | None,
                                  SweepInvocation | None]:
    """``(options, rows, runs, invocation)`` for ``skinny experiment``: the command
    line's as they are without ``--config``, else :func:`sweep_invocation`'s."""
    if getattr(args, "config", None) is None:
        return options, rows, args.runs, None
    inv = sweep_invocation(args, args.name, options, rows)
    return inv.options, inv.rows, inv.runs, inv


def check_experiment(inv: SweepInvocation | None, experiment: Any) -> None:
    """Refuse (exit 2, before any run) a config file of another experiment."""
    if inv is not None and inv.recorded.get("experiment") != experiment.name:
        raise SkinnyInputError(f"the config file is experiment "
                               f"{inv.recorded.get('experiment')!r}'s, not {experiment.name!r}")


def warn_if_rebuilt_differs(inv: SweepInvocation | None, out_dir: str | Path) -> None:
    """A warning (logging) when the sweep just run (its ``out_dir/config.json``) is not
    the one the file recorded: flags changed it, or the code did since."""
    if inv is None:
        return
    now = read_json(Path(out_dir) / "config.json")
    changed = [k for k in ("config", "rows", "base_seed") if inv.recorded.get(k) != now.get(k)]
    if changed:
        _log.warning("%s differ from the config file's (flags given, or the code changed): "
                     "this is not an exact repeat", ", ".join(changed))
