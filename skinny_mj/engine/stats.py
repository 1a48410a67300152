"""From run files to results: validated run records, per-row statistics, the table.

:func:`aggregate` reads ``out/runs/*.json`` only (each run file carries its row, params
and the paper's values), so results can always be rebuilt from what finished. The run
record schema is documented in :mod:`skinny_mj.engine.experiment`.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from skinny_mj.errors import SkinnyInputError
from skinny_mj.io import atomic_write_json

_STATS = ("mean", "variance", "sd", "median", "min", "max", "n")

#: A run's status: ``ok`` (metrics), ``failed`` (diverged: data, ``fail_reason``) or
#: ``error`` (any other exception: a bug, not data; ``error`` and ``traceback``).
STATUSES = ("ok", "failed", "error")
#: Keys every run file holds (:func:`load_run` refuses a file without them).
REQUIRED_KEYS = ("experiment", "row", "row_index", "run_index", "seed", "status", "metrics")
#: The line under every table: what the means are over.
MEANS_NOTE = ("Means (variance) over the runs that did not fail "
              "(failed = diverged, excluded).")
ERRORS_NOTE = "Errored runs (+N error: bugs, not data) are excluded too: see runs/*.json."


def to_jsonable(obj: Any) -> Any:
    """NumPy scalars/arrays -> Python numbers/lists; NaN and inf -> None (JSON has none)."""
    if isinstance(obj, Mapping):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, bool | np.bool_):
        return bool(obj)
    if isinstance(obj, int | np.integer):
        return int(obj)
    if isinstance(obj, float | np.floating):
        return float(obj) if math.isfinite(obj) else None
    return obj


def _is_number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool)


def summarize(values: Sequence[float]) -> dict[str, float | int | None]:
    """mean, variance (sample, ddof=1; 0 for one value), sd, median, min, max, n."""
    a = np.asarray([v for v in values if v is not None and math.isfinite(v)], dtype=float)
    if a.size == 0:
        return {k: (0 if k == "n" else None) for k in _STATS}
    var = float(a.var(ddof=1)) if a.size > 1 else 0.0
    return {"mean": float(a.mean()), "variance": var, "sd": math.sqrt(var),
            "median": float(np.median(a)), "min": float(a.min()), "max": float(a.max()),
            "n": int(a.size)}


def load_run(path: str | Path) -> dict[str, Any]:
    """One run record, validated: a clear :class:`SkinnyInputError` naming the file if
    it is not JSON, lacks a required key (:data:`REQUIRED_KEYS`), has an unknown
    ``status`` or is not named ``<row>-<seed>.json``. Run files are written atomically,
    so a bad one was damaged (disk fault) or edited, and is never skipped silently."""
    path = Path(path)
    try:
        rec = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise SkinnyInputError(f"not a readable JSON run file ({exc}); run files are "
                               "written atomically, so this one was damaged or edited: "
                               "delete it and --resume to run it again", path=path) from exc
    if not isinstance(rec, dict):
        raise SkinnyInputError(f"not a run file: holds a JSON {type(rec).__name__}, "
                               "not an object", path=path)
    missing = [k for k in REQUIRED_KEYS if k not in rec]
    if missing:
        raise SkinnyInputError(f"not a run file: lacks {', '.join(missing)}", path=path)
    if rec["status"] not in STATUSES:
        raise SkinnyInputError(f"run status {rec['status']!r} is none of "
                               f"{', '.join(STATUSES)}", path=path)
    ints = [k for k in ("row_index", "run_index", "seed")
            if not isinstance(rec[k], int) or isinstance(rec[k], bool)]
    if ints or not isinstance(rec["row"], str) or not isinstance(rec["metrics"], dict):
        raise SkinnyInputError("not a run file: row must be a string, metrics an object, "
                               "row_index, run_index and seed integers", path=path)
    if path.name != f"{rec['row']}-{rec['seed']}.json":
        raise SkinnyInputError(f"holds row {rec['row']!r} seed {rec['seed']}, so it should "
                               f"be named {rec['row']}-{rec['seed']}.json", path=path)
    return rec


def load_runs(out_dir: str | Path) -> list[dict[str, Any]]:
    """Every run record under ``out_dir/runs``, validated (:func:`load_run`), ordered by
    (row index, run index). Hidden files (the ``.<name>.*.tmp`` left by an interrupted
    atomic write) are ignored; any other file that is not a valid run file is an error."""
    records = [(_order(rec), rec) for _, rec in iter_runs(out_dir)]
    records.sort(key=lambda kv: kv[0])
    return [rec for _, rec in records]


def _order(rec: Mapping[str, Any]) -> tuple[int, int, str]:
    return rec["row_index"], rec["run_index"], rec["row"]


def iter_runs(out_dir: str | Path) -> Iterator[tuple[Path, dict[str, Any]]]:
    """``(path, record)`` of every run file of :func:`load_runs`, validated, one at a time
    in file-name order (so a caller can keep what it needs of each, not every record)."""
    runs_dir = Path(out_dir) / "runs"
    if not runs_dir.is_dir():
        raise SkinnyInputError("no runs/ folder: not a sweep output", path=out_dir)
    for path in sorted(runs_dir.iterdir()):
        if path.name.startswith("."):
            continue
        if path.suffix != ".json" or not path.is_file():
            raise SkinnyInputError("not a run file (run files are <row>-<seed>.json)",
                                   path=path)
        yield path, load_run(path)


def _records_in_order(out_dir: str | Path) -> Iterator[dict[str, Any]]:
    """The records of :func:`load_runs` in its (row, run) order, streamed: a first pass
    keeps only each file's place, a second reads them again one at a time, so the
    parent's memory does not grow with the records of a 10 000-run sweep
    (tests/test_engine_load.py)."""
    order = sorted((_order(rec), i, path) for i, (path, rec) in enumerate(iter_runs(out_dir)))
    for _, _, path in order:
        yield load_run(path)


def aggregate(out_dir: str | Path, *, write: bool = True) -> dict[str, Any]:
    """Per-row counts and statistics of every numeric metric, from the run files only.

    Returns (and writes to ``out_dir/results.json`` unless ``write`` is False)::

        {"experiment", "n_runs", "n_ok", "n_failed", "n_error",
         "rows": [{"row", "row_index", "params", "paper",
                   "n", "n_ok", "n_failed", "n_error", "n_fallback",
                   "failures": [{"seed", "fail_reason"}], "errors": [{"seed", "error"}],
                   "seeds", "metrics": {name: {mean, variance, sd, median, min, max, n}},
                   "wall_s": {"mean", "total"}}]}

    ``n = n_ok + n_failed``: the runs that are data (a failed run diverged); errored runs
    (bugs) are counted apart in ``n_error``; ``n_runs`` counts every run file. Metric
    statistics are over the ok runs only (``metrics[name]["n"]``: those with a finite
    value). Rows appear in experiment order, only those with run files on disk.
    """
    rows: dict[str, dict[str, Any]] = {}
    values: dict[str, dict[str, list[float]]] = {}
    experiment, n_runs = Path(out_dir).name, 0
    for rec in _records_in_order(out_dir):
        experiment = rec["experiment"] if n_runs == 0 else experiment
        n_runs += 1
        row = rows.setdefault(rec["row"], {
            "row": rec["row"], "row_index": rec["row_index"], "params": rec.get("params", {}),
            "paper": rec.get("paper", {}), "n": 0, "n_ok": 0, "n_failed": 0, "n_error": 0,
            "n_fallback": 0, "failures": [], "errors": [], "seeds": [], "wall": []})
        row["seeds"].append(rec["seed"])
        row["wall"].append(float(rec.get("wall_s") or 0.0))
        row["n_fallback"] += bool(rec.get("fallback"))
        if rec["status"] == "error":
            row["n_error"] += 1
            row["errors"].append({"seed": rec["seed"], "error": rec.get("error")})
            continue
        row["n"] += 1
        if rec["status"] == "failed":
            row["n_failed"] += 1
            # records older than the "error" status kept the reason in "error"
            reason = rec.get("fail_reason") or rec.get("error")
            row["failures"].append({"seed": rec["seed"], "fail_reason": reason})
            continue
        row["n_ok"] += 1
        per_metric = values.setdefault(rec["row"], {})
        for name, v in rec["metrics"].items():
            if _is_number(v) or v is None:
                per_metric.setdefault(name, []).append(v)
    out_rows = []
    for row_id, row in rows.items():
        wall = row.pop("wall")
        row["metrics"] = {m: summarize(v) for m, v in values.get(row_id, {}).items()}
        row["wall_s"] = {"mean": float(np.mean(wall)), "total": float(np.sum(wall))}
        out_rows.append(row)
    results = {"experiment": experiment, "n_runs": n_runs,
               **{k: sum(r[k] for r in out_rows) for k in ("n_ok", "n_failed", "n_error")},
               "rows": out_rows}
    if write:
        atomic_write_json(Path(out_dir) / "results.json", results)
    return results


def _fmt(v: float | None) -> str:
    if v is None:
        return "—"
    return f"{v:.4f}" if 1e-3 <= abs(v) < 1e4 or v == 0 else f"{v:.2e}"


def failed_cell(row: Mapping[str, Any]) -> str:
    """``failed / n`` of one results row, errored runs beside: ``1 / 20 (+1 error)``."""
    n_failed = int(row.get("n_failed", 0))
    n = int(row.get("n", int(row.get("n_ok", 0)) + n_failed))
    n_error = int(row.get("n_error", 0))
    cell = f"{n_failed} / {n}"
    if n_error:
        cell += f" (+{n_error} error{'s' if n_error > 1 else ''})"
    return cell


#: Said in a ``--quick`` sweep's table, claims and output.
SMOKE_NOTE = ("**Smoke test (--quick):** a few short runs per row, to show the pipeline "
              "runs end to end. Its numbers and verdicts mean nothing about the claims; "
              "run the study without --quick for those.")


def markdown_table(results: Mapping[str, Any],
                   columns: Sequence[str] | Mapping[str, str] | None = None, *,
                   smoke: bool = False) -> str:
    """Our mean (variance) beside the paper's value for each metric column, a
    ``failed / n`` column, and a line under the table saying what the means exclude.

    ``columns``: metric names, or ``{metric: header}``; default every metric seen.
    A paper value ``<metric>_var`` is shown as the paper's variance. ``smoke``: the
    sweep was a ``--quick`` one; :data:`SMOKE_NOTE` stands under the title.
    """
    rows = list(results["rows"])
    if columns is None:
        seen: dict[str, None] = {}
        for row in rows:
            seen.update(dict.fromkeys(row["metrics"]))
        columns = list(seen)
    headers = dict(columns) if isinstance(columns, Mapping) else {c: c for c in columns}
    head = ["row", "failed / n"]
    for label in headers.values():
        head += [f"{label} (ours: mean (var))", f"{label} (paper)"]
    lines = [f"### {results.get('experiment', '')}", ""]
    if smoke:
        lines += [SMOKE_NOTE, ""]
    lines += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for row in rows:
        cells = [row["row"], failed_cell(row)]
        for metric in headers:
            st = row["metrics"].get(metric)
            ours = "—" if not st or st["mean"] is None else \
                f"{_fmt(st['mean'])} ({_fmt(st['variance'])})"
            paper = row.get("paper", {})
            ref = _fmt(paper.get(metric)) if metric in paper else "—"
            if f"{metric}_var" in paper:
                ref += f" ({_fmt(paper[f'{metric}_var'])})"
            cells += [ours, ref]
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", MEANS_NOTE]
    if any(int(row.get("n_error", 0)) for row in rows):
        lines.append(ERRORS_NOTE)
    return "\n".join(lines)
