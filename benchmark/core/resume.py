"""Checkpoints and resume: the fingerprint of what determines a run's trajectory, the journal
header, reading a checkpoint back, and finding a run already finished in its folder."""

from __future__ import annotations

import copy
import hashlib
import json
import time
from pathlib import Path

import numpy as np

from benchmark.core.errors import ResumeError
from benchmark.core.journal import EvaluationJournal
from benchmark.core.mappings import flatten
from benchmark.core.problem import Problem

JOURNAL_NAME = "journal.bin"
#: Keys that do not change a run's trajectory (left out of its fingerprint).
VOLATILE_KEYS = ("resume", "checkpoint", "time_limit_s", "progress", "figures")


def run_fingerprint(conf: dict, problem: Problem) -> str:
    """SHA-256 of what determines a run's trajectory: the resolved config (less
    :data:`VOLATILE_KEYS` and ``data.max_file_mib``), the searched names and bounds, and the
    contents of the data folder's tables and YAML files."""
    return hashlib.sha256(json.dumps(_fingerprint_doc(conf, problem), sort_keys=True, default=str).encode()
                          ).hexdigest()


def _fingerprint_doc(conf: dict, problem: Problem) -> dict:
    data_path = (conf.get("data") or {}).get("path")
    conf = copy.deepcopy(conf)
    for k in VOLATILE_KEYS:
        conf.pop(k, None)
    if isinstance(conf.get("data"), dict):
        conf["data"].pop("max_file_mib", None)
    return {
        "config": conf,
        "parameter_names": list(problem.parameter_names),
        "lower": [float(v).hex() for v in np.asarray(problem.lower, float)],
        "upper": [float(v).hex() for v in np.asarray(problem.upper, float)],
        "data": _data_digest(data_path),
    }


def _data_digest(path) -> str | None:
    if path is None:
        return None
    folder = Path(str(path))
    h = hashlib.sha256()
    for f in sorted(folder.iterdir()) if folder.is_dir() else []:
        if f.is_file() and f.suffix.lower() in (".csv", ".mat", ".yaml", ".yml"):
            h.update(f.name.encode() + b"\0")
            with open(f, "rb") as fh:
                for chunk in iter(lambda fh=fh: fh.read(1 << 20), b""):
                    h.update(chunk)
    return h.hexdigest()


def journal_header(conf: dict, problem: Problem, budget: int, fingerprint: str) -> dict:
    return {"fingerprint": fingerprint, "n_var": problem.n_var,
            "parameter_names": list(problem.parameter_names), "budget": budget,
            "created": time.strftime("%Y-%m-%dT%H:%M:%S"),
            "config": _fingerprint_doc(conf, problem)["config"]}


def read_checkpoint(outdir: Path, fingerprint: str, problem: Problem, conf: dict):
    """(journal contents or None, resume info) for ``resume=true``; ResumeError if the journal
    belongs to another configuration."""
    path = outdir / JOURNAL_NAME
    contents = EvaluationJournal.read(path)
    info = {"journal": str(path), "replayed_batches": 0, "replayed_evaluations": 0, "ignored_bytes": 0}
    if contents is None:
        info["note"] = (f"no checkpoint in {outdir} (is hydra.run.dir the folder of the interrupted run?): "
                        "starting from the beginning")
        return None, info
    header = contents.header
    if header.get("fingerprint") != fingerprint:
        raise ResumeError(
            f"resume: the checkpoint {path} was written by a different run configuration or data "
            f"({_config_difference(header.get('config'), _fingerprint_doc(conf, problem)['config'])}); "
            "resume with the same overrides "
            "as the interrupted run, or start afresh with resume=false"
        )
    if header.get("n_var") != problem.n_var:
        raise ResumeError(f"resume: the checkpoint {path} is for {header.get('n_var')} parameters, "
                          f"this problem has {problem.n_var}")
    info["ignored_bytes"] = contents.ignored_bytes
    info["journaled_batches"] = len(contents.records)
    if contents.ignored_bytes:
        info["note"] = (f"ignored {contents.ignored_bytes} bytes at the end of the checkpoint (a record cut "
                        "short when the run was killed)")
    return contents, info


def _config_difference(old, now) -> str:
    """'seed: 1 then, 2 now; ...' for the first differing config keys."""
    a, b = flatten(old or {}), flatten(now or {})
    keys = sorted(k for k in set(a) | set(b) if a.get(k, "<unset>") != b.get(k, "<unset>"))
    if not keys:
        return "same configuration, but the data files or the derived bounds differ"
    shown = "; ".join(f"{k}: {a.get(k, '<unset>')!r} then, {b.get(k, '<unset>')!r} now" for k in keys[:5])
    return shown + (f"; and {len(keys) - 5} more" if len(keys) > 5 else "")


def finished_run(outdir: Path, fingerprint: str) -> dict | None:
    """The record of a run already finished in ``outdir`` with the same fingerprint, if its
    checkpoint is gone (the run completed)."""
    path = outdir / "result.json"
    if (outdir / JOURNAL_NAME).exists() or not path.is_file():
        return None
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(record, dict) or record.get("fingerprint") != fingerprint:
        return None
    return record
