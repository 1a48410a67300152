"""Compare two sweep folders' run files: same files, seeds and metrics bit for bit.

``python -m skinny_mj.engine.compare BEFORE AFTER`` prints every difference (exit 1 when
the metrics or seeds differ, 0 otherwise): run files only in one folder, and per run file
the fields that differ, the machine's measurements left out (``wall_s``, ``finished_at``,
any metric whose name holds ``wall_s``, ``cpu_s``, ``peak_rss``, ``wall_to`` or ``cpu_to``:
``train_wall_s``, ``wall_s_run``, ``peak_rss_mb``, ``cpu_to_0.05``, ...; also inside a
metric's lists of records, e.g. a learning curve's points). ``params``
differences are listed apart: a row whose parameters are spelled differently (e.g. as
config overrides) may still run the same thing, which the metrics then show.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

#: Record fields that are the machine's measurements (time, memory), not results.
WALL_FIELDS = ("wall_s", "finished_at", "fallback_traceback", "traceback")
#: Parts of metric names that mark a measurement of time or memory.
MEASURED = ("wall_s", "cpu_s", "peak_rss", "wall_to", "cpu_to")


def _is_wall(key: str) -> bool:
    return key in WALL_FIELDS or any(part in key for part in MEASURED)


def _load(folder: Path) -> dict[str, dict[str, Any]]:
    return {p.name: json.loads(p.read_text()) for p in sorted((folder / "runs").glob("*.json"))}


def _results(value: Any) -> Any:
    """A metric without the measurements in it (a list of records: each record's)."""
    if isinstance(value, dict):
        return {k: _results(v) for k, v in value.items() if not _is_wall(k)}
    if isinstance(value, list):
        return [_results(v) for v in value]
    return value


def _strip(record: dict[str, Any]) -> dict[str, Any]:
    out = {k: v for k, v in record.items() if not _is_wall(k)}
    out["metrics"] = _results(record.get("metrics", {}))
    return out


def compare(before: str | Path, after: str | Path) -> tuple[list[str], list[str]]:
    """``(differences, params_differences)`` between the two folders' run files."""
    a, b = _load(Path(before)), _load(Path(after))
    diffs = [f"only in {before}: {n}" for n in sorted(set(a) - set(b))]
    diffs += [f"only in {after}: {n}" for n in sorted(set(b) - set(a))]
    params: list[str] = []
    for name in sorted(set(a) & set(b)):
        x, y = _strip(a[name]), _strip(b[name])
        for key in sorted(set(x) | set(y)):
            if x.get(key) == y.get(key):
                continue
            if key == "params":
                params.append(f"{name}: params {x.get(key)} -> {y.get(key)}")
            elif key == "metrics":
                keys = sorted(set(x[key]) | set(y[key]))
                changed = [k for k in keys if x[key].get(k) != y[key].get(k)]
                diffs.append(f"{name}: metrics differ in {changed}")
            else:
                diffs.append(f"{name}: {key} {x.get(key)!r} -> {y.get(key)!r}")
    return diffs, params


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 2:
        print("usage: python -m skinny_mj.engine.compare BEFORE_DIR AFTER_DIR", file=sys.stderr)
        return 2
    diffs, params = compare(*args)
    n = len(_load(Path(args[0])))
    for line in [*diffs, *params]:
        print(line)
    print(f"{n} run files before; {len(diffs)} differences in files, seeds or metrics "
          f"(time and memory measurements left out); {len(params)} run files with other "
          "params")
    return 1 if diffs else 0


if __name__ == "__main__":
    sys.exit(main())
