"""The diagnosis section of ``results/perf.md`` from :mod:`.diagnosis_runs`' JSON: the distribution
of the diagnosis time over the records, and the before/after check of the verdicts.

    python -m benchmark.studies.perf.diagnosis_report RUNS.json [more RUNS.json ...]  # markdown to stdout

Several files (e.g. records run in separate sessions) are merged, later ones winning.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from benchmark.studies.perf.common import md_table
from benchmark.studies.perf.diagnosis_records import RECORDS

#: The before/after check's tolerance: shares (explained, drop-one) within this, absolute ...
SHARE_TOLERANCE = 0.01
#: ... and held-out RMS over noise (gaps) within this, relative.
GAP_TOLERANCE = 0.005
#: Target of issue 39: every diagnosis of a record up to 1 s at 12 kHz with a 10 s stop, wall s on 2 cores.
TARGET_S = 60.0


def same_verdict(a: dict, b: dict) -> tuple[bool, str]:
    """Whether two diagnoses' summaries agree (effects named, status, pruned; shares and gaps
    within the tolerances), and the largest differences as text."""
    if a.get("status") == "failed" or b.get("status") == "failed":
        return False, "failed"
    same = (a["effects"] == b["effects"] and a["status"] == b["status"] and a["pruned"] == b["pruned"]
            and a["weak_effects"] == b["weak_effects"])
    d_share = max([abs(a["explained_share"] - b["explained_share"])]
                  + [abs(a["drop_one_shares"][k] - b["drop_one_shares"].get(k, np.inf)) for k in a["drop_one_shares"]])
    d_gap = max(abs(a[k] / b[k] - 1.0) for k in ("gap_before", "gap_after"))
    ok = bool(same and d_share <= SHARE_TOLERANCE and d_gap <= GAP_TOLERANCE)
    return ok, f"{d_share:.1e} / {d_gap:.1e}"


#: A summary's keys that time a run rather than say what it computed.
TIMING_KEYS = ("wall_s", "cpu_s", "load_before", "inside_wall_s", "inside_cpu_s")


def identical(a: dict, b: dict) -> bool:
    """Whether two diagnoses' summaries are the same to the last digit, timings apart: then the
    two runs computed the same thing, and their CPU ratio is the machine's own spread."""
    return {k: v for k, v in a.items() if k not in TIMING_KEYS} == {k: v for k, v in b.items() if k not in TIMING_KEYS}


def same_computation_spread(runs: dict) -> tuple[int, float, float] | None:
    """(count, lowest, highest) CPU ratio reference/new over the records whose two runs are
    :func:`identical`; None where fewer than two are. A ratio within that range measures nothing."""
    ratios = [r["reference"]["cpu_s"] / r["new"]["cpu_s"] for r in runs.values()
              if r.get("reference") and identical(r["new"], r["reference"])]
    return (len(ratios), min(ratios), max(ratios)) if len(ratios) >= 2 else None


def _describe(name: str) -> str:
    source, options = next((s, o) for n, s, o in RECORDS if n == name)
    return {"plant": "independent plant", "own": "own plant", "motulator": "motulator"}[source]


def render(runs: dict) -> str:
    rows, walls, cpus, ratios_wall, ratios_cpu, checks = [], [], [], [], [], []
    for name, r in runs.items():
        new, ref = r["new"], r.get("reference")
        walls.append(new["wall_s"])
        cpus.append(new["cpu_s"])
        cells = [name, _describe(name), new.get("verdict", "-"), f"{new['wall_s']:.1f}", f"{new['cpu_s']:.1f}",
                 f"{new['load_before']:.1f}"]
        if ref:
            ok, diff = same_verdict(new, ref)
            checks.append(ok)
            ratios_wall.append(ref["wall_s"] / new["wall_s"])
            ratios_cpu.append(ref["cpu_s"] / new["cpu_s"])
            cells += [f"{ref['wall_s']:.1f}", f"{ref['cpu_s']:.1f}", f"{ratios_cpu[-1]:.2f}",
                      "same" if ok else f"DIFFERENT ({ref.get('verdict')})", diff]
        rows.append(cells)
    header = ["record", "source", "verdict", "wall s", "CPU s", "load before"]
    if checks:
        header += ["reference wall s", "reference CPU s", "CPU ratio (reference / new)", "verdict vs reference",
                   "max |d share| / max |d gap|/gap"]
    met = "met" if max(walls) <= TARGET_S else "NOT met"
    out = [md_table(header, rows), "",
           f"Wall time over the {len(walls)} records: median **{np.median(walls):.1f} s**, maximum "
           f"**{max(walls):.1f} s** (target <= {TARGET_S:.0f} s on 2 cores: {met} on this run's machine and load); "
           "CPU seconds: median "
           f"{np.median(cpus):.1f}, maximum {max(cpus):.1f}."]
    if checks:
        out.append(f"Against the reference in the same run: CPU time {np.median(ratios_cpu):.2f} times less (median; "
                   f"{min(ratios_cpu):.2f}-{max(ratios_cpu):.2f}), wall time {np.median(ratios_wall):.2f} times less "
                   f"(median; {min(ratios_wall):.2f}-{max(ratios_wall):.2f}). Verdicts: {sum(checks)} of {len(checks)} "
                   f"the same (effects named, status, pruned, weak effects; shares within {SHARE_TOLERANCE}, gaps "
                   f"within {100 * GAP_TOLERANCE:.1f} %).")
        spread = same_computation_spread(runs)
        if spread:
            out.append(f"The machine's own spread: on the {spread[0]} records whose two runs computed the same "
                       f"summary to the last digit, CPU ratios {spread[1]:.2f}-{spread[2]:.2f}; a ratio within that "
                       f"range is not a measured difference.")
    return "\n".join(out)


def merged(paths: list[str]) -> dict:
    runs: dict = {}
    for p in paths:
        runs.update(json.loads(Path(p).read_text())["runs"])
    return runs


if __name__ == "__main__":
    print(render(merged(sys.argv[1:])))
