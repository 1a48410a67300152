"""Progress bars of the long commands (train, demo, experiment, bench): a tqdm bar for a
person watching a terminal, nothing in a log or with ``--quiet``."""

from __future__ import annotations

import sys

__all__ = ["Progress", "progress_on"]


def progress_on(quiet: bool) -> bool:
    """Progress bars only for a person watching: not with --quiet, not into a log."""
    return not quiet and sys.stderr.isatty()


class Progress:
    """A tqdm bar on a terminal; silent otherwise (logs stay clean)."""

    def __init__(self, desc: str, quiet: bool = False):
        self.bar = None
        self.desc = desc
        self.quiet = quiet

    def __call__(self, done: int, total: int) -> None:
        if self.bar is None:
            from tqdm import tqdm

            self.bar = tqdm(total=total, desc=self.desc, unit="cycle", file=sys.stderr,
                            disable=not progress_on(self.quiet), leave=False)
        self.bar.update(done - self.bar.n)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
