"""Timed diagnoses of the perf study's records, each in a fresh interpreter, against a reference.

Each record of :mod:`.diagnosis_records` is diagnosed by the user's command,
``python -m benchmark.diagnose data.path=DIR`` (default configuration, figures included), in a
fresh process whose ``PYTHONPATH`` is the checkout under test; with a reference checkout (an
earlier commit unpacked with ``git archive``) the reference diagnoses the same record right
before, so that both see the same load. One warm-up diagnosis per checkout fills its compile
cache first. Wall time is the process's; CPU time is that of the process and its threads
(``resource.getrusage`` of the children): on a shared machine the wall time is inflated by the
other processes, the CPU time much less, and the ratio reference/new of either compares like
with like. The verdict, shares and gaps of each diagnosis are kept for the before/after check.

    python -m benchmark.studies.perf.diagnosis_runs RECORDS_DIR OUT.json [reference=PATH] [only=a,b]
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from pathlib import Path

from benchmark.studies.perf.common import ROOT, run_timed

#: The warm-up: a short synthetic start-up diagnosed in memory (compiles every kernel the diagnosis uses).
WARM_UP = ["motor.test.cycles=6", "motor.test.stop_duration=2.0", "budget=1500", "polish_budget=300",
           "effects=[sensor_offset]", "figures=false"]


def summary(doc: dict) -> dict:
    """What the before/after check compares, from a diagnosis document."""
    return {"status": doc["status"], "verdict": doc["verdict"], "effects": list(doc["effects"]),
            "explained_share": float(doc["explained_share"]), "pruned": list(doc.get("pruned", [])),
            "drop_one_shares": {p["effect"]: float(p["drop_one_share"]) for p in doc.get("per_effect", [])},
            "gap_before": float(doc["gap_before"]["heldout_rms_over_noise"]),
            "gap_after": float(doc["gap_after"]["heldout_rms_over_noise"]),
            "weak_effects": list(doc.get("weak_effects", [])),
            "rounds": [{"chosen": r.get("chosen"),
                        "candidates": {c["effect"]: float(c["heldout_chi2"]) for c in r.get("candidates", [])}}
                       for r in doc.get("selection", []) if "candidates" in r],
            "inside_wall_s": float(doc.get("wall_time_s", float("nan"))),
            "inside_cpu_s": float(doc.get("cpu_time_s", float("nan")))}


def diagnose(code: Path, overrides: list[str], outdir: Path) -> tuple[float, float, dict | None]:
    """(process wall s, process CPU s, diagnosis document) of one ``python -m benchmark.diagnose``."""
    wall, cpu, proc = run_timed(code, "benchmark.diagnose", [*overrides, f"hydra.run.dir={outdir}"])
    if proc.returncode != 0:
        sys.stderr.write(proc.stdout[-2000:] + proc.stderr[-4000:])
        return wall, cpu, None
    return wall, cpu, json.loads((outdir / "diagnosis.json").read_text())


def _one(code: Path, folder: Path, outdir: Path) -> dict:
    load = os.getloadavg()[0]
    wall, cpu, doc = diagnose(code, [f"data.path={folder}"], outdir)
    return {"wall_s": wall, "cpu_s": cpu, "load_before": load, **(summary(doc) if doc else {"status": "failed"})}


def run_all(records: list[tuple[str, Path]], code: Path, work: Path, reference: Path | None = None,
            say=print) -> dict:
    """Warm-up, then each record (by the reference first, when given); returns
    ``{name: {"new": {...}, "reference": {...}}}`` with wall and CPU seconds and the summary."""
    work.mkdir(parents=True, exist_ok=True)
    codes = {"new": code} if reference is None else {"reference": reference, "new": code}
    for label, path in codes.items():
        diagnose(path, WARM_UP, work / f"warm-up-{label}")
    out = {}
    for name, folder in records:
        out[name] = {label: _one(path, folder, work / f"{name}-{label}") for label, path in codes.items()}
        say(name + ": " + "; ".join(f"{label} {r['wall_s']:.1f} s wall, {r['cpu_s']:.1f} CPU s, {r.get('verdict')}"
                                     for label, r in out[name].items()))
    return out


def main(argv: list[str]) -> None:
    from benchmark.studies.perf.diagnosis_records import make_records

    opts = dict(a.split("=", 1) for a in argv[2:])
    reference = Path(opts["reference"]).resolve() if opts.get("reference") else None
    names = opts["only"].split(",") if opts.get("only") else None
    records = make_records(Path(argv[0]), names)
    work = Path(tempfile.mkdtemp(prefix="imbench-perf-diagnoses-"))
    res = {"code": str(ROOT), "reference": str(reference) if reference else None,
           "runs": run_all(records, ROOT, work, reference, say=lambda s: print(s, flush=True))}
    Path(argv[1]).write_text(json.dumps(res, indent=1) + "\n")


if __name__ == "__main__":
    main(sys.argv[1:])
