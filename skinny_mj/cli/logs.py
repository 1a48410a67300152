"""Where the package's diagnostics go under ``skinny``: its ``skinny_mj`` loggers'
records (warnings, notes, progress; never results, which commands print to stdout) as
plain lines on stderr, above a progress bar if one is running.

A program that imports skinny_mj configures logging itself; by default Python shows it the
warnings on stderr, and ``logging.getLogger("skinny_mj").setLevel(logging.ERROR)``
silences them.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Callable

__all__ = ["LEVELS", "to_stderr"]

#: ``skinny --log-level`` choices, quietest last.
LEVELS = ("debug", "info", "warning", "error")


class _StderrLines(logging.Handler):
    """One line per record on the current ``sys.stderr`` (the one a test captures), through
    tqdm's ``write`` when tqdm is loaded so a running bar is redrawn below the line."""

    def emit(self, record: logging.LogRecord) -> None:
        try:
            line = self.format(record)
            tqdm = sys.modules.get("tqdm")
            if tqdm is not None:
                tqdm.tqdm.write(line, file=sys.stderr)
            else:
                sys.stderr.write(line + "\n")
                sys.stderr.flush()
        except Exception:  # noqa: BLE001 (logging's own rule: a handler never raises)
            self.handleError(record)


def to_stderr(level: str = "warning") -> Callable[[], None]:
    """Send the ``skinny_mj`` loggers' records of ``level`` and above to stderr, as plain
    messages, and to nowhere else (an embedding program's root handlers do not print
    them twice); returns the function that undoes it."""
    logger = logging.getLogger("skinny_mj")
    handler = _StderrLines()
    handler.setFormatter(logging.Formatter("%(message)s"))
    saved = logger.level, logger.propagate
    logger.addHandler(handler)
    logger.setLevel(level.upper())
    logger.propagate = False

    def restore() -> None:
        logger.removeHandler(handler)
        logger.setLevel(saved[0])
        logger.propagate = saved[1]

    return restore
