"""From run files to results: per-row statistics and the markdown table.

:func:`aggregate` reads ``out/runs/*.json`` only (each run file carries its row, params
and the paper's values), so results can always be rebuilt from what finished.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from skinny_mj.errors import SkinnyInputError
from skinny_mj.io import atomic_write_json

_STATS = ("mean", "variance", "sd", "median", "min", "max", "n")


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


def load_runs(out_dir: str | Path) -> list[dict[str, Any]]:
    """All run records under ``out_dir/runs``, ordered by (row index, run index)."""
    runs_dir = Path(out_dir) / "runs"
    if not runs_dir.is_dir():
        raise SkinnyInputError("no runs/ folder: not a sweep output", path=out_dir)
    records = []
    for path in sorted(runs_dir.glob("*.json")):
        try:
            rec = json.loads(path.read_text())
            key = (int(rec["row_index"]), int(rec["run_index"]), str(rec["row"]))
        except (ValueError, KeyError, TypeError) as exc:
            raise SkinnyInputError(f"not a run file ({exc})", path=path) from exc
        records.append((key, rec))
    records.sort(key=lambda kv: kv[0])
    return [rec for _, rec in records]


def aggregate(out_dir: str | Path, *, write: bool = True) -> dict[str, Any]:
    """Per-row statistics of every numeric metric, from the run files only.

    Returns ``{"experiment", "n_runs", "rows": [{"row", "params", "paper", "n_ok",
    "n_failed", "failures", "seeds", "metrics": {name: {mean, variance, sd, median,
    min, max, n}}, "wall_s": {"mean", "total"}}]}`` and writes it to
    ``out_dir/results.json`` unless ``write`` is False. Failed runs count in
    ``n_failed`` and give no metric values.
    """
    records = load_runs(out_dir)
    rows: dict[str, dict[str, Any]] = {}
    values: dict[str, dict[str, list[float]]] = {}
    for rec in records:
        row = rows.setdefault(rec["row"], {
            "row": rec["row"], "params": rec.get("params", {}), "paper": rec.get("paper", {}),
            "n_ok": 0, "n_failed": 0, "failures": [], "seeds": [], "wall": []})
        row["seeds"].append(rec["seed"])
        row["wall"].append(float(rec.get("wall_s", 0.0)))
        if rec.get("status") != "ok":
            row["n_failed"] += 1
            row["failures"].append({"seed": rec["seed"], "error": rec.get("error")})
            continue
        row["n_ok"] += 1
        per_metric = values.setdefault(rec["row"], {})
        for name, v in rec.get("metrics", {}).items():
            if _is_number(v) or v is None:
                per_metric.setdefault(name, []).append(v)
    out_rows = []
    for row_id, row in rows.items():
        wall = row.pop("wall")
        row["metrics"] = {m: summarize(v) for m, v in values.get(row_id, {}).items()}
        row["wall_s"] = {"mean": float(np.mean(wall)), "total": float(np.sum(wall))}
        out_rows.append(row)
    experiment = records[0]["experiment"] if records else Path(out_dir).name
    results = {"experiment": experiment, "n_runs": len(records), "rows": out_rows}
    if write:
        atomic_write_json(Path(out_dir) / "results.json", results)
    return results


def _fmt(v: float | None) -> str:
    if v is None:
        return "—"
    return f"{v:.4f}" if 1e-3 <= abs(v) < 1e4 or v == 0 else f"{v:.2e}"


def markdown_table(results: Mapping[str, Any],
                   columns: Sequence[str] | Mapping[str, str] | None = None) -> str:
    """Our mean (variance) beside the paper's value for each metric column.

    ``columns``: metric names, or ``{metric: header}``; default every metric seen.
    A paper value ``<metric>_var`` is shown as the paper's variance.
    """
    rows = list(results["rows"])
    if columns is None:
        seen: dict[str, None] = {}
        for row in rows:
            seen.update(dict.fromkeys(row["metrics"]))
        columns = list(seen)
    headers = dict(columns) if isinstance(columns, Mapping) else {c: c for c in columns}
    head = ["row", "ok / failed"]
    for label in headers.values():
        head += [f"{label} (ours: mean (var))", f"{label} (paper)"]
    lines = [f"### {results.get('experiment', '')}", "",
             "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for row in rows:
        cells = [row["row"], f"{row['n_ok']} / {row['n_failed']}"]
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
    return "\n".join(lines)
