"""Atomic writers: a crash never leaves a half-written result, table or text file.

Files are written to a temporary file in the same folder, fsynced and renamed over the target;
they get the ordinary mode of a new file (0644 under the usual umask), like the figures.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

#: Mode of a written file before the process's umask is applied (rw-rw-rw-, as ``open`` uses).
FILE_MODE = 0o666


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_table_atomic(path: Path, table: dict[str, np.ndarray], float_format: str = "%.9g") -> None:
    """Write a CSV table so that a crash never leaves a half-written file."""
    df = pd.DataFrame(table)
    write_text_atomic(path, df.to_csv(index=False, float_format=float_format, lineterminator="\n"))


def write_text_atomic(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically: a temporary file in the same folder, flushed and
    fsynced, then renamed over ``path`` (``os.replace``). A crash at any point leaves either the
    previous file or the new one, never a mixture; the temporary file is removed on any error
    (a SIGKILL between the write and the rename can leave a ``.NAME.*.tmp`` file, never a
    half-written ``path``)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, FILE_MODE & ~_umask())  # mkstemp makes 0600; results are for sharing
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    _fsync_dir(path.parent)


def _fsync_dir(folder: Path) -> None:
    """Make a rename durable (best effort; not every platform can open a folder)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def write_yaml_atomic(path: Path, data: dict) -> None:
    write_text_atomic(path, yaml.safe_dump(data, sort_keys=False))
