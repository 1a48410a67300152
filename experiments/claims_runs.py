"""The runs the claims are scored from: which sweep makes each, what is read of it, and
the compact extract of it that the results page is checked against.

:data:`PLAN` is the run plan: for every (study, reading) key some claim reads
(:data:`claims_score.KEYS`), the ``skinny experiment`` command(s) that make its runs, at
the thesis's run counts (each study's own counts are the thesis's where it states them:
:data:`claims_rules.RUNS`). A band reading has one command per point of its band, in the
band's order. A key with no command says why (:data:`NO_COMMAND`). ``skinny claims
--plan`` prints them and the ``skinny claims`` line that scores the lot.

:data:`DERIVED` computes, from what a run file stores, the few metrics the catalogue reads
that the studies do not store as numbers: paper E's Fig. 3 cycle counts at the three
tolerances declared in advance (from the stored convergence curve) and paper B's
amplitude ratio and roughness per leader speed (from the stored traces).

An **extract** (:func:`extract`) is one sweep's runs reduced to what the claims read: per
row, per run, its index, seed, status and the catalogue's metrics only, with the command
that made the sweep and its seeding. Written as JSON by ``skinny claims --extract DIR``,
it is what the page's table is computed from, and small enough to commit; scoring an
extract gives the same verdicts and numbers as scoring the sweep's folder (the values are
the run files' floats, unrounded).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from skinny_mj.experiments.claims_catalogue import CATALOGUE, METRIC_UNDER_READING
from skinny_mj.experiments.claims_rules import READINGS
from skinny_mj.experiments.paper_e.study import cycles_to_converge

from skinny_mj.errors import SkinnyInputError

Key = tuple[str, str]  # (study, runs key: the readings that change the runs, "+"-joined)

_REC = ("--movement", "ymca-recorded")


def _band(study: str) -> tuple[tuple[str, ...], ...]:
    """One command per point of the u_error gain band (0.5, 1, 2) on the recorded data.
    Paper E's gain-2 point is ``--protocol thesis``: on paper E (and §5.1) that protocol
    sets exactly the recorded data and gain 2, so its sweep is the same runs; on paper D
    it also sets the true target's input noise, so paper D's point has its own sweep."""
    high = (study, "--protocol", "thesis") if study.startswith("paper-e") else \
        (study, *_REC, "--protocol", "gain-2")
    return ((study, *_REC, "--protocol", "gain-0.5"), (study, *_REC), high)


#: (study, runs key) -> the `skinny experiment` arguments of each sweep it needs.
PLAN: dict[Key, tuple[tuple[str, ...], ...]] = {
    ("paper-e", "default"): (("paper-e",),),
    ("paper-e", "recorded"): (("paper-e", *_REC),),
    ("paper-e", "recorded+gain-band"): _band("paper-e"),
    ("paper-e", "recorded+fitted-gain-2"): (("paper-e", "--protocol", "thesis"),),
    ("paper-e-explain", "default"): (("paper-e-explain",),),
    ("paper-e-explain", "recorded"): (("paper-e-explain", *_REC),),
    ("paper-e-explain", "recorded+gain-band"): _band("paper-e-explain"),
    ("paper-e-explain", "recorded+fitted-gain-2"): (("paper-e-explain", "--protocol",
                                                     "thesis"),),
    ("paper-d", "default"): (("paper-d",),),
    ("paper-d", "recorded+tt-clean"): (("paper-d", *_REC),),
    ("paper-d", "recorded+tt-clean+gain-band"): _band("paper-d"),
    ("paper-d", "recorded+fitted-gain-2+fitted-tt-noise"): (("paper-d", "--protocol",
                                                             "thesis"),),
    ("paper-a", "default"): (("paper-a",),),
    ("paper-a", "recorded"): (("paper-a", *_REC),),
    ("paper-b", "default"): (("paper-b",),),
    ("paper-b", "b-noise-free"): (("paper-b", "--protocol", "b-noise-free"),),
    ("paper-b", "b-sr0.9-nu0.02"): (("paper-b", "--protocol", "thesis"),),
    ("paper-c", "default"): (("paper-c",),),
    ("paper-c", "recorded"): (),
    ("figure-eight", "default"): (("figure-eight",),),
}
#: Keys no command can make today, and why.
NO_COMMAND = {
    ("paper-c", "recorded"): "paper C's rows are YMCA and movements derived from it (Y, Y "
                             "pure, YM, mirrors, speeds), which exist for the synthetic YMCA "
                             "only (--movement adds a row, it does not replace them)",
}

#: The options of a sweep's config.json that a command sets (the rest are the study's).
OPTIONS = ("movement", "asf", "dof", "signals", "protocol")


def command_options(args: Sequence[str]) -> dict[str, Any]:
    """``("paper-e", "--movement", "x", ...)`` -> {"movement": "x", ...} (every OPTIONS
    key; None where the command does not set it)."""
    out: dict[str, Any] = dict.fromkeys(OPTIONS)
    for flag, value in zip(args[1::2], args[2::2], strict=True):
        out[flag.removeprefix("--")] = value
    return out


def command_line(args: Sequence[str], out: str = "") -> str:
    """The shell line of a plan's command (``--workers 1``, and ``--out`` if given)."""
    return " ".join(["skinny experiment", *args, "--workers 1"]
                    + ([f"--out {out}"] if out else []))


def sweep_command(config: Mapping[str, Any], study: str) -> str:
    """The ``skinny experiment`` line a sweep's config.json says made it (its options and,
    when a subset, its rows)."""
    options = config.get("options") or {}
    parts = ["skinny experiment", study]
    for name in OPTIONS:
        if options.get(name) not in (None, ""):
            parts += [f"--{name}", str(options[name])]
    if options.get("quick"):
        parts.append("--quick")
    selection = config.get("selection")
    requested = selection.get("requested") if isinstance(selection, Mapping) else None
    if requested:
        parts += ["--rows", ",".join(requested)]
    return " ".join(parts)


def plan_point(key: Key, config: Mapping[str, Any]) -> int:
    """Which of ``key``'s planned commands a sweep's config.json matches (its index: the
    band point), or a one-line refusal naming the commands that would."""
    options = {k: (config.get("options") or {}).get(k) for k in OPTIONS}
    commands = PLAN.get(key, ())
    for i, args in enumerate(commands):
        if command_options(args) == options:
            return i
    want = "; ".join(command_line(a) for a in commands) or NO_COMMAND.get(key, "none")
    got = {k: v for k, v in options.items() if v is not None} or "the study's defaults"
    raise SkinnyInputError(f"its runs were made with {got}, not by the command {key[0]} "
                           f"under {key[1]} needs: {want}")


# -- derived metrics ----------------------------------------------------------------------
#: Paper E Fig. 3: "converged" when the excess over the final value is within this share
#: of the initial excess; the three tolerances declared in advance (E6 holds only if its
#: counts hold at every one: the study's own 5 % reproduced two of the thesis's counts).
FIG3_TOLERANCES = (0.01, 0.05, 0.10)


def _fig3(metrics: Mapping[str, Any]) -> dict[str, float]:
    curve = metrics.get("convergence_curve")
    if not isinstance(curve, list) or not curve:
        return {}
    return {f"cycles_to_converge_tol{round(t * 100)}": float(cycles_to_converge(curve, t))
            for t in FIG3_TOLERANCES}


def _paper_b(metrics: Mapping[str, Any]) -> dict[str, float]:
    """Per leader speed, from the stored lagging-shoulder traces (deg): the amplitude
    ratio (RMS swing of the actual angle / that of the desired: > 1 overshoots) and the
    roughness (RMS second difference of the actual / that of the desired: 1 = as smooth
    as its own target)."""
    out = {}
    for tag, trace in (metrics.get("traces") or {}).items():
        actual, desired = (np.asarray(trace[k], dtype=float) for k in ("actual", "desired"))
        swing = float(np.std(desired))
        rough = float(np.sqrt(np.mean(np.diff(desired, 2) ** 2)))
        if swing > 0:
            out[f"amplitude_ratio_{tag}"] = float(np.std(actual)) / swing
        if rough > 0:
            out[f"roughness_{tag}"] = float(np.sqrt(np.mean(np.diff(actual, 2) ** 2))) / rough
    return out


#: study -> a run's stored metrics -> the metrics derived from them.
DERIVED: dict[str, Callable[[Mapping[str, Any]], dict[str, float]]] = {
    "paper-e": _fig3, "paper-b": _paper_b}


def numeric_metrics(study: str, metrics: Mapping[str, Any]) -> dict[str, float | None]:
    """A run's numeric metrics (None kept: a metric the run could not measure) and the
    metrics :data:`DERIVED` from its stored series."""
    out = {k: v for k, v in metrics.items()
           if v is None or (isinstance(v, int | float) and not isinstance(v, bool))}
    if study in DERIVED:
        out.update(DERIVED[study](metrics))
    return out


def metrics_read(key: Key) -> list[str]:
    """The run-file metrics the catalogue reads of ``key``'s runs."""
    study, runs = key
    names = set()
    for check in CATALOGUE:
        for column in check.columns:
            ran = "+".join(r for r in column if r not in METRIC_UNDER_READING) or "default"
            if ran != runs:
                continue
            for comp in check.comparisons:
                if (comp.study or check.study) != study:
                    continue
                for metric in filter(None, (comp.metric, comp.metric_b)):
                    names.add(metric)
                    for reading in column:
                        if metric in METRIC_UNDER_READING.get(reading, {}):
                            names.add(METRIC_UNDER_READING[reading][metric][0])
    return sorted(names)


# -- extracts -----------------------------------------------------------------------------
def extract_name(key: Key, point: int = 0) -> str:
    """The extract's file name: ``<study>.<key>.json`` (a band's: ``.<point>`` before
    ``.json``, the point's index in the band)."""
    study, runs = key
    band = any(READINGS[r].band for r in runs.split("+"))
    return f"{study}.{runs}" + (f".{point}" if band else "") + ".json"


def extract(key: Key, point: int, command: str, config: Mapping[str, Any],
            records: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """One sweep's runs reduced to what the catalogue reads of ``key`` (JSON-able)."""
    keep = metrics_read(key)
    rows: dict[str, list[dict[str, Any]]] = {}
    for rec in sorted(records, key=lambda r: (r["row_index"], r["run_index"])):
        values = numeric_metrics(key[0], rec["metrics"])
        rows.setdefault(rec["row"], []).append({
            "run": rec["run_index"], "seed": rec["seed"], "status": rec["status"],
            "metrics": {m: _finite(values[m]) for m in keep if m in values}})
    return {"study": key[0], "key": key[1], "point": point, "command": command,
            "seeding": config.get("seeding"), "base_seed": config.get("base_seed"),
            "quick": bool((config.get("options") or {}).get("quick")),
            "metrics_read": keep, "rows": rows}


def extract_text(data: Mapping[str, Any]) -> str:
    """An extract as JSON text, one run per line (small, and its diffs readable)."""
    head = {k: v for k, v in data.items() if k != "rows"}
    lines = ["{" + json.dumps(head, allow_nan=False)[1:-1] + ', "rows": {']
    for i, (row, recs) in enumerate(data["rows"].items()):
        lines.append(f"  {json.dumps(row)}: [")
        lines += [f"    {json.dumps(r, allow_nan=False)}" + ("," if j < len(recs) - 1 else "")
                  for j, r in enumerate(recs)]
        lines.append("  ]" + ("," if i < len(data["rows"]) - 1 else ""))
    return "\n".join([*lines, "}}"]) + "\n"


def _finite(v: Any) -> float | None:
    return None if v is None or not math.isfinite(v) else v


def read_extract(path: Path) -> dict[str, Any]:
    """An extract written by :func:`extract` (a one-line refusal for anything else)."""
    try:
        data = json.loads(Path(path).read_text())
    except (OSError, ValueError) as exc:
        raise SkinnyInputError(f"not a claims extract ({exc})", path=path) from None
    if not isinstance(data, dict) or not {"study", "key", "rows", "command"} <= data.keys():
        raise SkinnyInputError("not a claims extract (no study, key, command, rows)",
                               path=path)
    return data


def plan_lines(parent: str = "results/claims-runs") -> list[str]:
    """``skinny claims --plan``: every sweep's command with an --out under ``parent`` (a
    command two keys share, e.g. a band's gain-1 point and the plain reading, runs once),
    then the ``skinny claims`` line that scores them into the page."""
    lines, sources, made = [], [], {}
    for (study, runs), commands in PLAN.items():
        lines.append(f"# {study} under {runs}")
        if not commands:
            lines.append(f"#   no sweep can make it: {NO_COMMAND[(study, runs)]}")
        for i, args in enumerate(commands):
            if args in made:
                lines.append(f"#   {command_line(args)}: the sweep of {made[args]}")
            else:
                made[args] = f"{parent}/{extract_name((study, runs), i).removesuffix('.json')}"
                lines.append(command_line(args, made[args]))
            sources.append(f"--from {study}" + ("" if runs == "default" else f":{runs}")
                           + f"={made[args]}")
    lines += ["# the page and its extracts, from every sweep above",
              "skinny claims " + " ".join(sources)
              + " --extract docs/results/claims-runs --page docs/results/claims.md"]
    return lines
