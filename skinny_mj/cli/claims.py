"""``skinny claims``: every thesis claim scored from sweeps' run files.

The scorer and the catalogue are the studies' (``experiments/claims_score.py``); the package
never imports the studies by name in its source (tests/test_layers.py), so it is loaded by
name here, as the engine loads a study's report.
"""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

from skinny_mj.engine import registry
from skinny_mj.engine.stats import to_jsonable
from skinny_mj.errors import SkinnyInputError
from skinny_mj.io import atomic_write_json, atomic_write_text
from skinny_mj.preflight import check_new_file, check_writable, new_folder, timestamp

DEFAULT_PARENT = Path("results") / "claims"
FILES = ("claims.md", "claims.json")


def cmd_claims(args: argparse.Namespace) -> int:
    """Score, then write ``claims.md`` and ``claims.json`` into ``--out`` (default
    ``results/claims/<time>``) and print the count per reading."""
    scorer = importlib.import_module(f"{registry.PACKAGE}.claims_score")
    if args.out is not None:  # refused before the scoring, not after it
        if args.out.exists() and not args.out.is_dir():
            raise SkinnyInputError("--out is a file, not a folder; choose a folder",
                                   path=args.out)
        for name in FILES:
            check_new_file(args.out / name, args.overwrite)
    else:
        check_writable(DEFAULT_PARENT)
    sources = scorer.parse_sources(args.sources)
    scored = scorer.score(sources)
    out = new_folder(DEFAULT_PARENT, timestamp()) if args.out is None else args.out
    out.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / "claims.md", scorer.markdown(scored))
    atomic_write_json(out / "claims.json", to_jsonable(scored))
    for line in scorer.count_lines(scored):
        print(line)
    if scored["smoke"]:
        print("smoke test (--quick): these verdicts mean nothing about the claims; score "
              "full sweeps for those")
    print(f"wrote {out / 'claims.md'} and {out / 'claims.json'}")
    return 0
