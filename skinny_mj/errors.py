"""User-facing errors: bad input (exit 2) and environment faults (exit 1), one line each."""

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


class SkinnyEnvironmentError(OSError):
    """A fault of the machine, not of the user's input: an output folder that cannot be
    written or is full, no OpenGL backend, a missing model folder, an unreachable
    cluster. The CLI prints it as one line and exits with code 1 (as for any OSError).
    """
