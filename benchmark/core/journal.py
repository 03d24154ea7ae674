"""The checkpoint journal: every evaluated batch of a run, appended to a binary file, so an
interrupted run can be resumed and finish identical to an uninterrupted one."""

from __future__ import annotations

import contextlib
import json
import os
import struct
import time
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

# -- checkpoint journal ------------------------------------------------------------------------
KIND_EVALUATE = 0
KIND_RESIDUALS = 1


@dataclass
class JournalRecord:
    """One journaled batch: kind, the evaluated points (n, n_var), their costs, and where the
    record sits in the file (``offset`` .. ``end``)."""

    kind: int
    X: np.ndarray
    cost: np.ndarray
    offset: int
    end: int


@dataclass
class JournalContents:
    header: dict
    records: list[JournalRecord]
    valid_end: int  # bytes of header + complete records
    ignored_bytes: int  # a truncated or corrupt tail (a kill during a write), ignored


class EvaluationJournal:
    """Append-only binary log of every evaluated batch of a run (its checkpoint).

    Layout: ``MAGIC`` (16 bytes), ``<I`` header length, the header as JSON (fingerprint of
    the run, ``n_var``, parameter names, budget), ``<I`` CRC-32 of the header; then one record
    per batch: ``<4sBBHII`` (``b"EVAL"``, kind, 0, 0, n_rows, n_var), the points as
    little-endian float64 ``(n_rows, n_var)``, the costs as float64 ``(n_rows,)``, and ``<I``
    CRC-32 of all that. Each record is written with one ``write`` and flushed to the
    operating system (so it survives a SIGKILL; an ``fsync`` at most every
    :attr:`fsync_interval_s` also covers a power cut up to that interval). A record cut short by
    a kill fails its length or CRC check and is ignored, with everything after it.
    """

    MAGIC = b"IMBENCH-JOURNAL1"
    RECORD = struct.Struct("<4sBBHII")
    TAG = b"EVAL"
    fsync_interval_s = 5.0

    def __init__(self, path: Path, fh, position: int):
        self.path = Path(path)
        self._fh = fh
        self._pos = position  # end of the last record that belongs to this run
        self._last_sync = time.monotonic()

    # -- writing
    @classmethod
    def create(cls, path: Path, header: dict) -> EvaluationJournal:
        """Start a new journal at ``path`` (replacing any previous one)."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        body = json.dumps(header, sort_keys=True, default=str).encode()
        blob = cls.MAGIC + struct.pack("<I", len(body)) + body + struct.pack("<I", zlib.crc32(body))
        fh = open(path, "wb", buffering=0)  # noqa: SIM115 - kept open for the run
        fh.write(blob)
        os.fsync(fh.fileno())
        return cls(path, fh, len(blob))

    @classmethod
    def reopen(cls, path: Path, contents: JournalContents) -> EvaluationJournal:
        """Continue a journal on resume: the ignored tail is cut off; replayed records are
        kept; new records go after the last replayed one."""
        fh = open(path, "r+b", buffering=0)  # noqa: SIM115 - kept open for the run
        fh.truncate(contents.valid_end)
        header_end = contents.records[0].offset if contents.records else contents.valid_end
        return cls(path, fh, header_end)

    def skip(self, rec: JournalRecord) -> None:
        """A replayed record stays: new records go after it."""
        self._pos = rec.end

    def truncate_here(self) -> None:
        """Drop the records after the last replayed one (they belong to another trajectory)."""
        self._fh.truncate(self._pos)

    def append(self, kind: int, X: np.ndarray, cost: np.ndarray) -> None:
        X = np.ascontiguousarray(X, dtype="<f8")
        cost = np.ascontiguousarray(cost, dtype="<f8")
        n, n_var = X.shape
        body = self.RECORD.pack(self.TAG, kind, 0, 0, n, n_var) + X.tobytes() + cost.tobytes()
        # live records only follow the replayed ones (a mismatch cut the rest off first)
        self._fh.seek(self._pos)
        self._fh.write(body + struct.pack("<I", zlib.crc32(body)))
        self._pos += len(body) + 4
        now = time.monotonic()
        if now - self._last_sync > self.fsync_interval_s:
            os.fsync(self._fh.fileno())
            self._last_sync = now

    def close(self) -> None:
        if self._fh is not None and not self._fh.closed:
            with contextlib.suppress(OSError):
                os.fsync(self._fh.fileno())
            self._fh.close()

    # -- reading
    @classmethod
    def read(cls, path: Path) -> JournalContents | None:
        """The header and every complete record of the journal at ``path``; None if there is
        no journal or its header was never completely written. Raises ResumeError if the file
        is not a journal."""
        from benchmark.core.errors import ResumeError

        path = Path(path)
        try:
            data = path.read_bytes()
        except FileNotFoundError:
            return None
        except OSError as exc:
            raise ResumeError(f"resume: cannot read the checkpoint {path}: {exc}") from None
        if len(data) < len(cls.MAGIC) + 4:
            return None if cls.MAGIC.startswith(data[: len(cls.MAGIC)]) else cls._not_a_journal(path)
        if not data.startswith(cls.MAGIC):
            cls._not_a_journal(path)
        k = len(cls.MAGIC)
        (hlen,) = struct.unpack_from("<I", data, k)
        k += 4
        if k + hlen + 4 > len(data):
            return None
        body = data[k:k + hlen]
        (crc,) = struct.unpack_from("<I", data, k + hlen)
        if zlib.crc32(body) != crc:
            return None
        try:
            header = json.loads(body)
        except ValueError:
            return None
        k += hlen + 4
        n_var = int(header.get("n_var", -1))
        records = []
        rsize = cls.RECORD.size
        while k + rsize <= len(data):
            tag, kind, _, _, n, nv = cls.RECORD.unpack_from(data, k)
            payload = n * nv * 8 + n * 8
            end = k + rsize + payload + 4
            if tag != cls.TAG or nv != n_var or n < 1 or kind not in (KIND_EVALUATE, KIND_RESIDUALS) \
                    or end > len(data):
                break
            (crc,) = struct.unpack_from("<I", data, end - 4)
            if zlib.crc32(data[k:end - 4]) != crc:
                break
            X = np.frombuffer(data, dtype="<f8", count=n * nv, offset=k + rsize).reshape(n, nv).astype(float)
            cost = np.frombuffer(data, dtype="<f8", count=n, offset=k + rsize + n * nv * 8).astype(float)
            records.append(JournalRecord(kind=kind, X=X, cost=cost, offset=k, end=end))
            k = end
        return JournalContents(header=header, records=records, valid_end=k, ignored_bytes=len(data) - k)

    @staticmethod
    def _not_a_journal(path):
        from benchmark.core.errors import ResumeError

        raise ResumeError(f"resume: {path} is not an imbench checkpoint journal")
