"""The claims page (docs/results/claims.md) against the runs it was computed from: its
computed section is the table `skinny claims` computes from the committed extracts
(docs/results/claims-runs/), and a re-scoring written here from the rules' text (scipy's
Welch and one-sample t-tests on the extracts' JSON, none of claims_score's code) gives
the same count per reading."""

from __future__ import annotations

import json
import math
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from scipy import stats
from skinny_mj.experiments import claims_page as page
from skinny_mj.experiments import claims_score as cs
from skinny_mj.experiments.claims_catalogue import CATALOGUE, METRIC_UNDER_READING
from skinny_mj.experiments.claims_rules import READINGS, RUNS

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "results" / "claims.md"
EXTRACTS = ROOT / "docs" / "results" / "claims-runs"


@pytest.fixture(scope="module")
def scored():
    return cs.score(cs.extract_sources(EXTRACTS))


def test_the_page_is_the_table_computed_from_its_extracts(scored):
    section = page.page_section(PAGE.read_text(encoding="utf-8"))
    assert section is not None, "the page has no computed section"
    assert section == page.markdown(scored), (
        "docs/results/claims.md differs from the table its extracts give: rerun "
        "`skinny claims --extracts docs/results/claims-runs --page docs/results/claims.md`")


def test_every_claim_cites_its_sentence_and_every_non_hold_its_reason(scored):
    assert len(scored["claims"]) == 64
    for claim in scored["claims"]:
        assert claim["quote"] and claim["line"] > 0
        for col in claim["columns"]:
            assert col["outcome"] == "holds" or len(col["reason"]) > 10, (claim["id"], col)


def test_no_fitted_or_measured_reading_is_counted(scored):
    for claim in scored["claims"]:
        for col in claim["columns"]:
            fitted = any(READINGS[r].status in ("fitted", "measured", "band")
                         for r in col["column"].split("+"))
            assert not (fitted and col["counted"]), (claim["id"], col["column"])


def test_the_sweeps_table_has_one_line_per_study_naming_every_sweep(scored):
    lines = page.sources_table(scored)[2:]
    studies = [s["study"] for s in scored["sources"]]
    assert [line.split(" | ")[0].lstrip("| ") for line in lines] == list(dict.fromkeys(studies))
    for s in scored["sources"]:
        line = next(x for x in lines if x.startswith(f"| {s['study']} |"))
        assert f"`{s['command']}`" in line and f"{s['key']}: " in line
    runs = {"ok": 5, "failed": 1}
    one = [{"study": "paper-a", "key": k, "command": f"skinny experiment paper-a {k}",
            "runs": runs} for k in ("x", "y")]
    assert page.sources_table({"sources": one})[2].endswith("| 2 sweeps, each 5 / 1 / 0 |")
    one[1] = {**one[1], "runs": {"ok": 4}}
    assert page.sources_table({"sources": one})[2].endswith("| 5 / 1 / 0, 4 / 0 / 0 |")


# -- an independent re-scoring ------------------------------------------------------------
ALPHA, CLOSE, STABLE = 0.05, 1.5, 0.9


def _extracts() -> dict[tuple[str, str], list[dict]]:
    out: dict[tuple[str, str], list[dict]] = {}
    for path in sorted(EXTRACTS.glob("*.json")):
        data = json.loads(path.read_text())
        out.setdefault((data["study"], data["key"]), []).append(data)
    return {k: sorted(v, key=lambda d: d["point"]) for k, v in out.items()}


def _values(data, row, metric, scale, absolute):
    runs = data["rows"].get(row, [])
    vals = [r["metrics"][metric] * scale for r in runs
            if r["status"] == "ok" and r["metrics"].get(metric) is not None
            and math.isfinite(r["metrics"][metric])]
    return np.abs(vals) if absolute else np.asarray(vals, float)


def _welch(a, b, alternative):
    if np.ptp(a) == 0 and np.ptp(b) == 0:  # both constant: the difference is exact
        if a[0] == b[0]:
            return 1.0
        return 0.0 if {"less": a[0] < b[0], "greater": a[0] > b[0],
                       "two-sided": True}[alternative] else 1.0
    return float(stats.ttest_ind(a, b, equal_var=False, alternative=alternative).pvalue)


def _one_sample(a, t, alternative):
    if np.ptp(a) == 0:
        return 0.0 if (a[0] < t if alternative == "less" else a[0] > t) else 1.0
    return float(stats.ttest_1samp(a, t, alternative=alternative).pvalue)


def _verdict(comp, data, column, need):
    """'holds', 'no' or 'untestable' for one comparison on one sweep's extract."""
    metric, scale = comp.metric, 1.0
    for reading in column:
        metric, scale = METRIC_UNDER_READING.get(reading, {}).get(comp.metric, (metric, scale))
    absolute = comp.transform == "abs"
    if comp.rule == "stable":
        runs = [r for r in data["rows"].get(comp.a, []) if r["status"] != "error"]
        if len(runs) < need:
            return "untestable"
        ok = sum(r["status"] == "ok" for r in runs) / len(runs) >= STABLE
        return _negate(comp, ok)
    a = _values(data, comp.a, metric, scale, absolute)
    if len(a) < need:
        return "untestable"
    alt = {"<": "less", ">": "greater"}.get(comp.relation)
    rows = (comp.b,) if isinstance(comp.b, str) else comp.b
    if isinstance(rows, tuple) and all(isinstance(r, str) for r in rows):
        mb, sb = comp.metric_b or comp.metric, 1.0
        for reading in column:
            mb, sb = METRIC_UNDER_READING.get(reading, {}).get(comp.metric_b or comp.metric,
                                                               (mb, sb))
        groups = [_values(data, r, mb, sb * comp.scale_b, absolute) for r in rows]
        if any(len(g) < need for g in groups):
            return "untestable"
        ma, means = a.mean(), [g.mean() for g in groups]
        if comp.rule in ("better", "significantly", "best"):
            right = all(ma < m if alt == "less" else ma > m for m in means)
            ok = right and max(_welch(a, g, alt) for g in groups) < ALPHA
        elif comp.rule == "tie":
            ok = _welch(a, groups[0], "two-sided") >= ALPHA
        elif comp.rule == "close":
            ok = means[0] / CLOSE <= ma <= means[0] * CLOSE
        elif comp.rule == "extremes":
            ok = a.max() < groups[0].min() if alt == "less" else a.min() > groups[0].max()
        else:
            raise AssertionError(comp.rule)
        return _negate(comp, ok)
    ma = a.mean()
    if comp.rule == "threshold":
        t = float(comp.b)
        ok = (ma < t if alt == "less" else ma > t) and _one_sample(a, t, alt) < ALPHA
    elif comp.rule == "close":
        lo, hi = (comp.b, comp.b) if isinstance(comp.b, int | float) else sorted(comp.b)
        ok = lo / CLOSE * (1 - 1e-9) <= ma <= hi * CLOSE * (1 + 1e-9)
    else:
        raise AssertionError(comp.rule)
    return _negate(comp, ok)


def _negate(comp, ok):
    return "holds" if ok != comp.negate else "no"


def _independent_counts() -> dict[str, Counter]:
    sweeps = _extracts()
    out: dict[str, Counter] = {"counted": Counter()}
    for check in CATALOGUE:
        need = max(2, RUNS[check.runs].runs)
        counted = check.counted_column()
        for column in check.columns:
            key_runs = "+".join(r for r in column if r not in METRIC_UNDER_READING) or "default"
            points = max(len(READINGS[r].band) for r in column) or 1
            verdicts = []
            for comp in check.comparisons:
                given = sweeps.get((comp.study or check.study, key_runs), [])
                if len(given) < points:
                    verdicts.append("untestable")
                    continue
                verdicts += [_verdict(comp, data, column, need) for data in given]
            outcome = ("does not hold" if "no" in verdicts else
                       "not testable" if "untestable" in verdicts else "holds")
            for name in ("+".join(column), *(("counted",) if column == counted else ())):
                out.setdefault(name, Counter())[outcome] += 1
    return out


def test_an_independent_rescoring_of_the_extracts_gives_the_same_count(scored):
    mine = {name: Counter({k: c[k] for k in ("holds", "does not hold", "not testable") if c[k]})
            for name, c in cs.counts(scored).items()}
    assert _independent_counts() == mine
