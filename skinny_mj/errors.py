"""User-facing input errors: the CLI prints one line and exits with code 2."""

from __future__ import annotations

from pathlib import Path


class SkinnyInputError(ValueError):
    """Bad input from a user: a malformed file, an unknown name, an invalid parameter.

    The message names the file (and line, where known) and what is wrong, so the
    command line can print it as one line without a traceback.
    """

    def __init__(self, message: str, *, path: str | Path | None = None, line: int | None = None):
        where = ""
        if path is not None:
            where = f"{path}:{line}: " if line is not None else f"{path}: "
        super().__init__(where + message)
        self.path = None if path is None else Path(path)
        self.line = line
