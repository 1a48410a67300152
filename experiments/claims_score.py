"""Every claim of :mod:`claims_catalogue` scored from run files, by :mod:`claims_rules`.

The verdicts are computed here, not typed: give the sweeps' folders (``skinny claims
--from paper-e=results/paper-e/<time> ...``) and each claim is scored under each of its
reading columns whose runs were given: *holds*, *does not hold* (labelled weak when every
failing comparison is in the claimed direction but not significant) or *not testable*,
with the numbers behind it (means, n, p, ratio) and, when not testable, the measured
reason: no sweep given for that study and reading, the row missing from the sweep, the
metric absent from its run files, or fewer ok runs than the declared run count.

A source is ``STUDY[:READING+READING]=FOLDER``: the folder's runs are that study's under
that reading column (default: ``default``), accepted only if its config.json shows the
reading's planned command made it (:data:`claims_runs.PLAN`); FOLDER may be the sweep's
extract (``.json``, :func:`claims_runs.extract`) instead, which scores the same. A
reading that only changes how a metric is read
(:data:`claims_catalogue.METRIC_UNDER_READING`) reads the same runs, so it is left out
of the key. A band reading (``gain-band``) needs one folder per point of its band,
given as repeated ``--from`` of the same key (in any order: each sweep's command says its
point); the claim holds under the band only if it holds at every point
(:data:`claims_rules.READINGS`).

A claim is a conjunction of comparisons: one that does not hold decides it; else one that
is not testable makes it not testable; else it holds. A negated comparison holds when the
comparison does not hold (weak or not).
"""

from __future__ import annotations

import json
import math
from collections import Counter
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from skinny_mj.experiments import claims_runs
from skinny_mj.experiments.claims_catalogue import (
    CATALOGUE,
    METRIC_UNDER_READING,
    Check,
    Comparison,
)
from skinny_mj.experiments.claims_rules import ALPHA, MIN_RUNS, READINGS, RULES, RUNS, compare

from skinny_mj.engine.stats import iter_runs
from skinny_mj.errors import SkinnyInputError

#: The studies the catalogue reads.
STUDIES = tuple(sorted({c.study for c in CATALOGUE}
                       | {p.study for c in CATALOGUE for p in c.comparisons if p.study}))
#: The (study, runs key) pairs some claim's column reads.
KEYS = frozenset((p.study or c.study, "+".join(r for r in col if r not in METRIC_UNDER_READING)
                  or "default") for c in CATALOGUE for col in c.columns for p in c.comparisons)
#: The markers around the computed table in a results page (:func:`page_matches`).
BEGIN, END = "<!-- claims computed: begin -->", "<!-- claims computed: end -->"

Key = tuple[str, str]  # (study, runs key: readings that change the runs, "+"-joined)


def runs_key(column: Sequence[str]) -> str:
    """The readings of ``column`` that change the runs, ``+``-joined (``default``: none)."""
    ran = [r for r in column if r not in METRIC_UNDER_READING]
    return "+".join(ran) or "default"


def parse_sources(entries: Sequence[str]) -> dict[Key, list[Path]]:
    """``STUDY[:READINGS]=FOLDER`` entries (a sweep's folder, or its extract's ``.json``)
    -> {(study, runs key): [sources]}; a bad entry is a one-line :class:`SkinnyInputError`."""
    out: dict[Key, list[Path]] = {}
    for entry in entries:
        head, sep, folder = entry.partition("=")
        if not sep or not folder:
            raise SkinnyInputError(f"--from {entry!r}: give STUDY[:READINGS]=FOLDER, e.g. "
                                   "paper-e=results/paper-e/20261204-061500")
        study, _, column = head.partition(":")
        if study not in STUDIES:
            raise SkinnyInputError(f"--from {entry!r}: no claim reads study {study!r}; the "
                                   f"claims read {', '.join(STUDIES)}")
        readings = tuple(r for r in column.split("+") if r) or ("default",)
        unknown = [r for r in readings if r not in READINGS]
        if unknown:
            raise SkinnyInputError(f"--from {entry!r}: unknown reading {unknown[0]!r}; "
                                   f"known: {', '.join(READINGS)}")
        key = runs_key(readings)
        if (study, key) not in KEYS:
            known = sorted(k for s, k in KEYS if s == study)
            raise SkinnyInputError(f"--from {entry!r}: no claim reads {study} under {key}; "
                                   f"its claims read it under {', '.join(known)}")
        out.setdefault((study, key), []).append(Path(folder))
    for (study, key), folders in out.items():
        points = max((len(READINGS[r].band) for r in key.split("+")), default=0)
        if len(folders) > max(points, 1):
            raise SkinnyInputError(f"--from {study}:{key} given {len(folders)} times; only a "
                                   "band reading takes one folder per point")
    return out


def extract_sources(folder: Path) -> dict[Key, list[Path]]:
    """Every extract in ``folder`` (``skinny claims --extract``), keyed as
    :func:`parse_sources` keys its entries."""
    files = sorted(Path(folder).glob("*.json"))
    if not files:
        raise SkinnyInputError("no claims extracts (*.json) here", path=folder)
    return parse_sources([f"{d['study']}:{d['key']}={f}"
                          for f in files for d in (claims_runs.read_extract(f),)])


class Sweep:
    """One sweep's runs as the claims read them: per row, (status, numeric metrics) per
    run, from its folder's run files or from its extract (:mod:`claims_runs`)."""

    def __init__(self, source: Path, key: Key) -> None:
        self.source = Path(source)
        if self.source.is_file():
            data = claims_runs.read_extract(self.source)
            if (data["study"], data["key"]) != key:
                raise SkinnyInputError(f"an extract of {data['study']} under {data['key']}, "
                                       f"not of {key[0]} under {key[1]}", path=source)
        else:
            data = self._from_folder(self.source, key)
        self.extract = data
        self.point, self.command, self.quick = data["point"], data["command"], data["quick"]
        self.rows = {row: [(r["status"], r["metrics"]) for r in recs]
                     for row, recs in data["rows"].items()}

    @staticmethod
    def _from_folder(folder: Path, key: Key) -> dict[str, Any]:
        study = key[0]
        records = []
        for path, rec in iter_runs(folder):
            if rec["experiment"] != study:
                raise SkinnyInputError(f"holds a run of {rec['experiment']!r}, not of "
                                       f"{study!r}", path=path)
            records.append(rec)
        if not records:
            raise SkinnyInputError("no run files in runs/", path=folder)
        try:
            config = json.loads((folder / "config.json").read_text())
        except (OSError, ValueError):
            config = {}
        config = config if isinstance(config, dict) else {}
        try:
            point = claims_runs.plan_point(key, config)
        except SkinnyInputError as exc:
            raise SkinnyInputError(str(exc), path=folder) from None
        command = claims_runs.sweep_command(config, study)
        return claims_runs.extract(key, point, command, config, records)

    def counts(self) -> Counter:
        """Runs per status."""
        return Counter(s for recs in self.rows.values() for s, _ in recs)

    def values(self, row: str, metric: str, scale: float = 1.0, transform: str = "",
               need: int = MIN_RUNS) -> tuple[list[float] | None, str]:
        """The finite values of ``metric`` over ``row``'s ok runs, or None and the reason
        they cannot be compared (the row is not in the sweep, no ok run stores the metric,
        fewer values than ``need``)."""
        runs_ = self.rows.get(row)
        if not runs_:
            return None, f"row {row} is not in the sweep"
        status = Counter(s for s, _ in runs_)
        ok = [m for s, m in runs_ if s == "ok"]
        if ok and not any(metric in m for m in ok):
            return None, f"metric {metric} is absent from row {row}'s run files"
        vals = [float(m[metric]) * scale for m in ok
                if m.get(metric) is not None and math.isfinite(m[metric])]
        vals = [abs(v) for v in vals] if transform == "abs" else vals
        if len(vals) < need:
            return None, (f"row {row}: {len(vals)} ok runs with {metric} ({status['failed']} "
                          f"failed, {status['error']} errored, of {len(runs_)}) where {need} "
                          "are needed")
        return vals, ""


def _metric(column: Sequence[str], metric: str) -> tuple[str, float]:
    for reading in column:
        if metric in METRIC_UNDER_READING.get(reading, {}):
            return METRIC_UNDER_READING[reading][metric]
    return metric, 1.0


def _num(v: float | None) -> float | None:
    return None if v is None or not math.isfinite(v) else float(v)


def score_comparison(comp: Comparison, sweep: Sweep | None, column: Sequence[str],
                     need: int, missing: str = "") -> dict[str, Any]:
    """One comparison's verdict with its numbers (JSON-able)."""
    desc = ("not " if comp.negate else "") + f"{comp.a} {comp.metric} {comp.relation} " + (
        ", ".join(comp.b) if isinstance(comp.b, tuple) and all(isinstance(x, str)
                                                               for x in comp.b)
        else f"{comp.b}" + (f" {comp.metric_b}" if comp.metric_b else ""))
    out: dict[str, Any] = {"comparison": desc, "rule": comp.rule, "negate": comp.negate,
                           "outcome": "not testable", "weak": False, "p": None,
                           "statistic": RULES[comp.rule].statistic, "stat_a": None,
                           "stat_b": None, "n": [], "ratio": None,
                           "reason": missing,
                           "sweep": None if sweep is None else sweep.command}
    if sweep is None:
        return out
    kind = RULES[comp.rule].kind
    b: Any = comp.b
    if kind == "stable":  # per run: 1 finished, 0 diverged (errored runs are bugs)
        a = [1.0 if s == "ok" else 0.0 for s, _ in sweep.rows.get(comp.a, []) if s != "error"]
        why = "" if comp.a in sweep.rows else f"row {comp.a} is not in the sweep"
    else:
        metric, scale = _metric(column, comp.metric)
        a, why = sweep.values(comp.a, metric, scale, comp.transform, need)
    rows = (comp.b,) if isinstance(comp.b, str) else comp.b
    if not why and isinstance(rows, tuple) and all(isinstance(r, str) for r in rows):
        metric_b, scale_b = _metric(column, comp.metric_b or comp.metric)
        groups = []
        for row in rows:
            vals, why = sweep.values(row, metric_b, scale_b * comp.scale_b, comp.transform,
                                     need)
            if vals is None:
                break
            groups.append(vals)
        b = groups if kind == "best" else (groups[0] if groups else None)
    if why:
        out["reason"] = why
        return out
    v = compare(a, b, comp.relation, comp.rule, required_runs=need)
    outcome, weak = v.outcome, v.weak
    if comp.negate and outcome != "not testable":
        outcome, weak = ("does not hold" if v.holds else "holds"), False
    stat_a, stat_b = _num(v.stat_a), _num(v.stat_b)
    ratio = stat_a / stat_b if stat_a is not None and stat_b not in (None, 0.0) else None
    out.update(outcome=outcome, weak=weak, p=_num(v.p), stat_a=stat_a, stat_b=stat_b,
               n=list(v.n), ratio=ratio,
               reason=("negated: " if comp.negate else "") + v.reason)
    return out


def combine(comps: Sequence[Mapping[str, Any]]) -> tuple[str, bool, str]:
    """A conjunction's (outcome, weak, reason) from its comparisons' verdicts."""
    failing = [c for c in comps if c["outcome"] == "does not hold"]
    if failing:
        return ("does not hold", all(c["weak"] for c in failing),
                "; ".join(f"{c['comparison']}: {c['reason']}" for c in failing[:3])
                + (f" (+{len(failing) - 3} more)" if len(failing) > 3 else ""))
    untestable = [c for c in comps if c["outcome"] == "not testable"]
    if untestable:
        reasons = list(dict.fromkeys(c["reason"] for c in untestable))
        return ("not testable", False, "; ".join(reasons[:3])
                + (f" (+{len(reasons) - 3} more)" if len(reasons) > 3 else ""))
    return "holds", False, ""


def score_check(check: Check, sweeps: Mapping[Key, Sequence[Sweep]]) -> dict[str, Any]:
    """One claim under each of its columns (JSON-able)."""
    need = max(MIN_RUNS, RUNS[check.runs].runs)
    counted = check.counted_column()
    columns = []
    for column in check.columns:
        points = max(len(READINGS[r].band) for r in column) or 1
        comps = []
        for comp in check.comparisons:
            study, key = comp.study or check.study, runs_key(column)
            given = list(sweeps.get((study, key), ()))
            missing = "" if len(given) >= points else not_run((study, key), given)
            for sweep in (given if not missing else [None]):
                comps.append(score_comparison(comp, sweep, column, need, missing))
        outcome, weak, reason = combine(comps)
        status = [READINGS[r].status for r in column]
        columns.append({"column": "+".join(column), "counted": column == counted,
                        "status": ", ".join(dict.fromkeys(status)), "outcome": outcome,
                        "weak": weak, "reason": reason, "comparisons": comps})
    return {"id": check.id, "paper": check.paper, "line": check.line, "claim": check.claim,
            "quote": check.quote, "study": check.study, "runs_needed": need,
            "rules": sorted(check.rules), "columns": columns}


def not_run(key: Key, given: Sequence[Sweep]) -> str:
    """Why ``key``'s sweeps are missing, with the commands that would make them."""
    commands = claims_runs.PLAN.get(key, ())
    if not commands:
        return f"no sweep can make {key[0]} under {key[1]}: {claims_runs.NO_COMMAND[key]}"
    have = {s.point for s in given}
    todo = [claims_runs.command_line(a) for i, a in enumerate(commands) if i not in have]
    head = (f"{len(given)} of the {len(commands)} sweeps of its band run" if given
            else "sweep not run")
    return f"{head}: `" + "`; `".join(todo) + "`"


def load(sources: Mapping[Key, Sequence[Path]]) -> dict[Key, list[Sweep]]:
    """The sweeps of ``sources`` (folders or extracts), a band's in its points' order; one
    sweep per point."""
    out = {}
    for key, paths in sources.items():
        sweeps = sorted((Sweep(Path(p), key) for p in paths), key=lambda s: s.point)
        points = [s.point for s in sweeps]
        if len(set(points)) < len(points):
            raise SkinnyInputError(f"--from {key[0]}:{key[1]}: two sweeps made by the same "
                                   "command; a band takes one per point")
        out[key] = sweeps
    return out


def score(sources: Mapping[Key, Sequence[Path]] | Mapping[Key, Sequence[Sweep]]
          ) -> dict[str, Any]:
    """Every catalogue claim scored from ``sources``: :func:`parse_sources`' folders or
    extracts, or the sweeps :func:`load` made of them."""
    sweeps = {k: list(v) for k, v in sources.items()}
    if any(not isinstance(s, Sweep) for group in sweeps.values() for s in group):
        sweeps = load(sources)  # type: ignore[arg-type]
    return {"sources": [{"study": s, "key": k, "point": sw.point, "command": sw.command,
                         "extract": claims_runs.extract_name((s, k), sw.point),
                         "seeding": sw.extract.get("seeding"), "runs": dict(sw.counts())}
                        for (s, k), group in sorted(sweeps.items()) for sw in group],
            "alpha": ALPHA, "smoke": any(sw.quick for group in sweeps.values() for sw in group),
            "claims": [score_check(c, sweeps) for c in CATALOGUE]}


def counts(scored: Mapping[str, Any]) -> dict[str, Counter]:
    """Per column (and ``counted``: each claim's counted column): how many claims hold,
    do not hold (``weak`` among them), are not testable. From the verdicts only, so the
    JSON :func:`score` returns gives the same counts read back."""
    out: dict[str, Counter] = {"counted": Counter()}
    for claim in scored["claims"]:
        for col in claim["columns"]:
            for name in (col["column"], *(("counted",) if col["counted"] else ())):
                c = out.setdefault(name, Counter())
                c[col["outcome"]] += 1
                c["weak"] += bool(col["weak"])
    return out


def count_lines(scored: Mapping[str, Any]) -> list[str]:
    lines = []
    for name, c in counts(scored).items():
        total = c["holds"] + c["does not hold"] + c["not testable"]
        status = "" if name == "counted" else "; ".join(dict.fromkeys(
            READINGS[r].status for r in name.split("+")))
        note = " (fitted: not counted)" if "fitted" in status else \
            " (measured: shown, not counted)" if "measured" in status else ""
        lines.append(f"{name}{note}: {c['holds']} of {total} hold, {c['does not hold']} do "
                     f"not hold ({c['weak']} of them weak), {c['not testable']} not testable")
    return lines
