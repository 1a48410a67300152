"""``skinny claims``: every thesis claim scored from sweeps' run files.

The scorer, the catalogue, the run plan and the page are the studies'
(``experiments/claims_*.py``); the package never imports the studies by name in its
source (tests/test_layers.py), so they are loaded by name here, as the engine loads a
study's report.
"""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

from skinny_mj.engine import registry
from skinny_mj.engine.stats import to_jsonable
from skinny_mj.errors import SkinnyInputError
from skinny_mj.io import atomic_write_json, atomic_write_text, read_page_with_section
from skinny_mj.preflight import check_new_file, check_writable, new_folder, timestamp

DEFAULT_PARENT = Path("results") / "claims"
FILES = ("claims.md", "claims.json")


def _module(name: str):
    return importlib.import_module(f"{registry.PACKAGE}.{name}")


def cmd_claims(args: argparse.Namespace) -> int:
    """``--plan``: print the sweeps' commands. Else score the sweeps (``--from``) or the
    extracts (``--extracts``); write the extracts (``--extract``), the page's computed
    section (``--page``) and ``claims.md`` / ``claims.json`` (``--out``, default
    ``results/claims/<time>`` unless --page), and print the count per reading."""
    if args.plan:
        for line in _module("claims_runs").plan_lines():
            print(line)
        return 0
    scorer, page = _module("claims_score"), _module("claims_page")
    if bool(args.sources) == bool(args.extracts):
        raise SkinnyInputError("give the sweeps (--from STUDY[:READINGS]=FOLDER, repeated) "
                               "or a folder of their extracts (--extracts DIR), one of them")
    if args.page is not None:  # refused before the scoring, not after it
        read_page_with_section(args.page, scorer.BEGIN, scorer.END)
    if args.out is not None:  # refused before the scoring, not after it
        if args.out.exists() and not args.out.is_dir():
            raise SkinnyInputError("--out is a file, not a folder; choose a folder",
                                   path=args.out)
        for name in FILES:
            check_new_file(args.out / name, args.overwrite)
    elif args.page is None:
        check_writable(DEFAULT_PARENT)
    sources = (scorer.parse_sources(args.sources) if args.sources
               else scorer.extract_sources(args.extracts))
    sweeps = scorer.load(sources)
    if args.extract is not None:
        _write_extracts(args.extract, sweeps, _module("claims_runs"))
    scored = scorer.score(sweeps)
    if args.page is not None:
        page.write_page(args.page, scored)
        print(f"wrote the computed section of {args.page}")
    if args.out is not None or args.page is None:
        out = new_folder(DEFAULT_PARENT, timestamp()) if args.out is None else args.out
        out.mkdir(parents=True, exist_ok=True)
        atomic_write_text(out / "claims.md", page.markdown(scored))
        atomic_write_json(out / "claims.json", to_jsonable(scored))
        print(f"wrote {out / 'claims.md'} and {out / 'claims.json'}")
    for line in scorer.count_lines(scored):
        print(line)
    if scored["smoke"]:
        print("smoke test (--quick): these verdicts mean nothing about the claims; score "
              "full sweeps for those")
    return 0


def _write_extracts(folder: Path, sweeps, runs) -> None:
    """One extract per sweep into ``folder``; the folder's other extracts are left alone
    (an extract of a key not re-scored now stays as it was)."""
    folder.mkdir(parents=True, exist_ok=True)
    for key, group in sweeps.items():
        for sweep in group:
            path = folder / runs.extract_name(key, sweep.point)
            atomic_write_text(path, runs.extract_text(to_jsonable(sweep.extract)))
    print(f"wrote {sum(map(len, sweeps.values()))} extracts into {folder}")
