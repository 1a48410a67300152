"""Repeating a run from the files it wrote: ``skinny train --config``, ``skinny experiment
--config``.

``skinny train`` writes ``metrics.json`` with the run's whole :class:`TrainConfig`
(``config``) and its ``seed``; a sweep writes ``config.json`` with the CLI options
(``options``: quick, movement, asf, dof, signals), the selection of rows and the runs per
row. Fed back, each repeats the run exactly; a flag given on the command line as well
overrides that one field (``args.given``, from :func:`skinny_mj.cli.given_options`, says
which flags were given: argparse defaults never override a file).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from skinny_mj.config import TrainConfig
from skinny_mj.errors import SkinnyInputError

__all__ = ["read_json", "read_train_file", "train_config", "SweepInvocation",
           "sweep_invocation", "apply_sweep_config", "check_experiment",
           "warn_if_rebuilt_differs"]

#: The CLI options a sweep's ``config.json`` records (``options``) and ``build`` takes.
SWEEP_OPTIONS = ("quick", "movement", "asf", "dof", "signals")


def read_json(path: str | Path) -> dict[str, Any]:
    """A JSON object from ``path``; anything else is a :class:`SkinnyInputError`."""
    path = Path(path)
    if not path.is_file():
        raise SkinnyInputError("no such config file", path=path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as err:
        raise SkinnyInputError(f"not a JSON config file ({err})", path=path) from None
    if not isinstance(data, dict):
        raise SkinnyInputError("a config file holds a JSON object", path=path)
    return data


def read_train_file(path: str | Path) -> tuple[dict[str, Any], int | None]:
    """The TrainConfig dict and seed in ``path``: a run's ``metrics.json`` (its
    ``config`` and ``seed``) or a bare TrainConfig dict (seed None)."""
    data = read_json(path)
    if "experiment" in data and "options" in data:
        raise SkinnyInputError("this is a sweep's config.json: repeat it with `skinny "
                               f"experiment {data['experiment']} --config {path}`", path=path)
    if isinstance(data.get("config"), dict):
        seed = data.get("seed")
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int)
                                 or seed < 0):
            raise SkinnyInputError(f"seed must be a whole number >= 0, got {seed!r}", path=path)
        return dict(data["config"]), seed
    return data, None


def _make(fields: dict[str, Any], path: Path | None) -> TrainConfig:
    try:
        return TrainConfig.from_dict(fields)
    except SkinnyInputError as err:
        if path is None:
            raise
        raise SkinnyInputError(str(err), path=path) from None
    except (TypeError, ValueError) as err:  # a field of the wrong type, e.g. "epochs": "3"
        raise SkinnyInputError(f"bad training config ({err})", path=path) from None


def train_config(args: argparse.Namespace) -> tuple[TrainConfig, int]:
    """The run ``skinny train`` was asked for, and its seed.

    Every parsed option whose dest is a :class:`TrainConfig` field sets that field;
    with ``--config FILE`` only the flags actually given do (``args.given``) and the
    file's fields and seed stand for the rest.
    """
    names = {f.name for f in dataclasses.fields(TrainConfig)}
    flags = {k: str(v) if isinstance(v, Path) else v for k, v in vars(args).items()
             if k in names}
    preset = getattr(args, "preset", None)
    if preset is not None:  # the preset's fields, then the flags given
        if getattr(args, "config", None) is not None:
            raise SkinnyInputError("give --preset or --config, not both")
        from skinny_mj.presets import preset_fields

        fields = preset_fields(preset, str(flags.get("actuation", "velocity")))
        given = getattr(args, "given", set())
        fields.update({k: v for k, v in flags.items() if k in given})
        return _make(fields, None), int(args.seed)
    if getattr(args, "config", None) is None:
        return _make(flags, None), int(args.seed)
    path = Path(args.config)
    fields, seed = read_train_file(path)
    given = getattr(args, "given", set())
    fields.update({k: v for k, v in flags.items() if k in given})
    if "seed" in given or seed is None:
        seed = int(args.seed)
    return _make(fields, path), seed


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
    """One line on stderr when the sweep just run (its ``out_dir/config.json``) is not
    the one the file recorded: flags changed it, or the code did since."""
    if inv is None:
        return
    now = read_json(Path(out_dir) / "config.json")
    changed = [k for k in ("config", "rows", "base_seed") if inv.recorded.get(k) != now.get(k)]
    if changed:
        print(f"skinny experiment: warning: {', '.join(changed)} differ from the config "
              "file's (flags given, or the code changed): this is not an exact repeat",
              file=sys.stderr)
