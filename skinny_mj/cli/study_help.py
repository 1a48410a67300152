"""What ``skinny experiment list`` and ``skinny experiment NAME --help`` print.

The help of one study is read off the study itself: its description (a Study's, or the
module docstring), the rows, groups and runs of the ``Experiment`` its ``build()`` returns, which
of ``--movement --body --signals`` change its runs (each tried: a changed ``config.json``
means the option is taken, a refusal that it is not, no change that it has no effect),
and its cost: the run count, the time per run measured by earlier sweeps under
``results/NAME/`` on this machine if any, and the wall time the docs report.
"""

from __future__ import annotations

import json
import os
import re
import textwrap
from pathlib import Path
from typing import Any

from skinny_mj.engine import registry
from skinny_mj.errors import SkinnyInputError

WIDTH = 88
#: Whole sweeps timed in the docs (runs, CPU time, workers, machine, page).
DOCUMENTED_WALL = {
    "paper-a": "440 runs in 1164 s of CPU time with --workers 1 on a shared 2-core machine "
               "(docs/compute.md)",
    "paper-b": "80 runs in 268 s of CPU time with --workers 1 on an idle 2-core machine "
               "(docs/compute.md)",
    "paper-c": "80 runs in 36 min 33 s with --workers 1 on a shared 2-core machine (2046 s "
               "of CPU time; docs/compute.md)",
    "paper-e": "410 runs in 612 s of CPU time with --workers 1 on a shared 2-core machine "
               "(docs/compute.md)",
}
_PROBES = (("movement", ("y",)), ("body", ("2d", "3d")), ("signals", ("joint", "cartesian")))


def list_text(width: int = WIDTH) -> str:
    """Every registered study with its whole description, wrapped under its name."""
    names = registry.names()
    pad = max(map(len, names), default=0) + 2
    blocks = []
    for name in names:
        text = _plain(registry.describe(name)) or "(no description)"
        blocks.append(textwrap.fill(text,
                                    width, initial_indent=name.ljust(pad),
                                    subsequent_indent=" " * pad))
    return "\n".join(blocks)


def _plain(text: str) -> str:
    """reStructuredText's ``literal`` as Markdown's `literal`, for a terminal."""
    return re.sub(r"``([^`]*)``", r"`\1`", text)


def _config(exp: Any) -> Any:
    """What ``config.json`` records of a built study: its config and its rows."""
    from skinny_mj.engine.stats import to_jsonable

    return to_jsonable({"config": exp.to_dict(),
                        "rows": [(r.id, r.settings, r.runs) for r in exp.rows]})


def option_effects(module: Any, base: Any) -> dict[str, str]:
    """Per option of ``_PROBES``: what the study does with it, tried value by value."""
    ref = _config(base)
    out = {}
    for option, values in _PROBES:
        said = {}
        for value in values:
            try:
                said[value] = "changes" if _config(module.build(**{option: value})) != ref \
                    else "same"
            except SkinnyInputError:
                said[value] = "refused"
        if option == "movement":
            out[option] = {"changes": "taken", "refused": "refused (fixed movements)",
                           "same": "no effect on this study"}[said["y"]]
            continue
        taken = [f"{v} (default)" if how == "same" else str(v)
                 for v, how in said.items() if how != "refused"]
        if all(how == "refused" for how in said.values()):
            taken = ["refused"]
        elif all(how == "same" for how in said.values()):
            taken = ["no effect on this study"]
        elif "same" not in said.values():
            taken[-1] += " (default: the study's own mix)"
        refused = [str(v) for v, how in said.items() if how == "refused" and taken != ["refused"]]
        out[option] = " | ".join(taken) + (f"; refuses {', '.join(refused)}" if refused
                                           else "")
    return out


def _cover(ids: list[str], groups: dict[str, tuple[str, ...]], skip: str = "") -> str:
    """``ids`` named by whole groups where one fits (largest first), the rest by id."""
    left, names = list(ids), []
    for g, members in sorted(groups.items(), key=lambda gm: -len(gm[1])):
        if g != skip and len(members) > 1 and set(members) <= set(left) \
                and set(members) != set(ids):  # not a group naming the same rows
            names.append(g)
            left = [i for i in left if i not in members]
    return ", ".join([*names, *left])


def _group(name: str, members: tuple[str, ...], groups: dict[str, tuple[str, ...]]) -> str:
    text = _cover(list(members), groups, skip=name)
    return f"{name} = {text}" if len(text) <= 160 else f"{name} ({len(members)} rows)"


def _runs_per_row(exp: Any) -> str:
    by_count: dict[int, list[str]] = {}
    for r in exp.rows:
        by_count.setdefault(r.runs or exp.runs, []).append(r.id)
    if len(by_count) == 1:
        text = f"{exp.runs} in every row"
    else:
        text = "; ".join(f"{n} in {_cover(ids, exp.groups)}" for n, ids in by_count.items())
    return f"{text} (--runs N caps every row at N)"


def measured_here(name: str, root: Path = Path("results")) -> str | None:
    """Mean time per run over the sweeps of ``name`` under ``root`` (their results.json)."""
    walls, folders = [], 0
    for path in sorted((root / name).glob("*/results.json")):
        try:
            rows = json.loads(path.read_text()).get("rows", [])
        except (OSError, ValueError):
            continue
        got = [(r["wall_s"]["mean"], r.get("n", 0) + r.get("n_error", 0)) for r in rows
               if isinstance(r.get("wall_s"), dict) and r["wall_s"].get("mean") is not None]
        walls += [(w, n) for w, n in got if n]
        folders += bool(got)
    n = sum(k for _, k in walls)
    if not n:
        return None
    mean = sum(w * k for w, k in walls) / n
    return (f"{mean:.1f} s of one worker per run, mean of {n} runs in {folders} earlier "
            f"sweep(s) under {root / name}")


def _wrap(label: str, text: str) -> str:
    return textwrap.fill(text, WIDTH, initial_indent=f"{label}: ",
                         subsequent_indent="    ", break_on_hyphens=False)


def study_help(name: str) -> str:
    """``skinny experiment NAME --help``: the study's description, rows, groups, runs,
    the options it takes and its cost. An unknown name is a SkinnyInputError."""
    module = registry.get(name)
    doc = _plain(registry.doc(name).strip())
    try:
        exp = module.build()
    except SkinnyInputError as err:  # e.g. an optional extra missing: the text still helps
        return (f"skinny experiment {name}\n\n{textwrap.dedent(doc)}\n\n"
                + _wrap("Rows", f"not listed here: {err}") + "\n")
    quick = module.build(quick=True)
    total = sum(r.runs or exp.runs for r in exp.rows)
    n_quick = sum(r.runs or quick.runs for r in quick.rows)
    parts = [f"skinny experiment {name}", "", textwrap.dedent(doc), "",
             _wrap(f"Rows ({len(exp.rows)}, --rows ID,...)",
                   ", ".join(r.id for r in exp.rows))]
    if exp.groups:
        parts.append(_wrap("Groups (--rows GROUP)", "; ".join(
            _group(g, m, exp.groups) for g, m in exp.groups.items())))
    parts.append(_wrap("Runs per row", _runs_per_row(exp)))
    from skinny_mj.engine import protocols  # here: `skinny experiment list` loads no study

    if read := [f"{p.name} ({'; '.join(r.setting for r in p.readings_for(name))})"
                for p in protocols.PROTOCOLS.values() if p.readings_for(name)]:
        parts.append(_wrap("Protocols (--protocol NAME)", ", ".join(read)))
    effects = option_effects(module, exp)
    parts.append(_wrap("Options", "; ".join(f"--{k}: {v}" for k, v in effects.items())
                       + f"; --quick: a smoke test of {n_quick} runs. Every study also "
                       "takes --runs --rows --workers --out --resume --scheduler --config "
                       "--quiet (skinny experiment --help)"))
    cost = [f"the full sweep is {total} runs"]
    if (here := measured_here(name)) is not None:
        cores = os.cpu_count() or 1
        per_run = float(here.split(" s ", 1)[0])
        cost.append(f"measured on this machine: {here}, so about "
                    f"{total * per_run / cores / 60:.0f} min on its {cores} cores")
    if name in DOCUMENTED_WALL:
        cost.append(f"documented: {DOCUMENTED_WALL[name]}")
    if len(cost) == 1:
        cost.append("no measured time yet (none documented, no earlier sweep under "
                    f"results/{name}); --quick first gives one")
    parts.append(_wrap("Cost", "; ".join(cost)))
    return "\n".join(parts) + "\n"
