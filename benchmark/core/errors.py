"""Errors a user can act on. The command-line entry points print them without a traceback
(set ``IMBENCH_DEBUG=1`` for one) and exit with status 2."""

from __future__ import annotations


def where(path, column: str | None = None, row: int | None = None) -> str:
    """``path, column 'c', row r`` of a message: rows count from the header (row 0), so data row
    ``r`` of a text table is its line ``r + 1``, which the message says too."""
    out = str(path)
    if column is not None:
        out += f", column '{column}'"
    if row is not None:
        text = str(path).lower().endswith((".csv", ".txt"))
        out += f", row {row}" + (f" (line {row + 1} of the file)" if text else "")
    return out


class UserError(Exception):
    """Base class: a message that names what to fix (file, column, row, or config key)."""


class DataError(UserError):
    """A data set on disk is malformed. The message names the file, and the column and row
    where they are known."""

    def __init__(self, path, message: str, column: str | None = None, row: int | None = None):
        super().__init__(f"{where(path, column, row)}: {message}")
        self.path, self.column, self.row, self.message = str(path), column, row, message


class ConfigError(UserError):
    """A configuration value is invalid. The message starts with the config key."""


class ResumeError(UserError):
    """A run cannot be resumed from its checkpoint (another configuration wrote it, or it is
    unreadable). The message says what differs and how to start afresh."""


class ImbenchWarning(UserWarning):
    """Base class of the warnings the command line prints as one ``warning: ...`` line."""


class ResumeWarning(ImbenchWarning):
    """A resumed run could not replay its whole checkpoint (a non-deterministic plugin) or had
    nothing to resume."""


class DataWarning(ImbenchWarning):
    """Data that load but look wrong (e.g. a speed column that may be in rpm, an unknown
    ``meta.yaml`` key). The command line prints it as one ``warning: ...`` line and the run
    records it in ``result.json``."""

    @classmethod
    def at(cls, path, message: str, column: str | None = None, row: int | None = None) -> DataWarning:
        return cls(f"{where(path, column, row)}: {message}")
