"""IOHprofiler export of a sweep's runs (the Analyzer-logger format), for IOHanalyzer."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np

from benchmark.analysis.fmt import _slug
from benchmark.analysis.targets import Row

IOH_DAT_HEADER = "evaluations raw_y"
IOH_FORMAT_VERSION = "0.3.22"  # the IOHexperimenter Analyzer-logger format written here


# -- IOHprofiler export ---------------------------------------------------------------------------
def write_ioh(rows: list[Row], out: Path, y_note: str | None = None) -> Path:
    """Runs in the format of IOHexperimenter's Analyzer logger (what IOHanalyzer loads): per
    optimiser a folder with ``IOHprofiler_f<id>_<problem>.json`` (meta-data: function, algorithm,
    one scenario per dimension with each run's instance, evaluations and best point) and
    ``data_f<id>_<problem>/IOHprofiler_f<id>_DIM<n>.dat`` (per run a header line
    ``evaluations raw_y``, then one line per improvement of the best cost and one at the last
    evaluation). Minimisation. Zipped as ``ioh.zip`` for IOHanalyzer's upload page.

    Readers (IOHanalyzer, iohinspector) start a new run at the line of evaluation 1, which
    IOHexperimenter always writes. The harness's history has one row per batch that improved
    the best cost, at the evaluation that did it, so when the first row is later than 1 a line
    ``1 <first best cost>`` is written: optimistic by less than one population."""
    root = out / "ioh"
    if root.exists():
        shutil.rmtree(root)
    groups = sorted({r.group for r in rows})
    fids = {g: k + 1 for k, g in enumerate(groups)}
    for row in rows:
        runs = [r for r in row.runs if len(r.evals)]
        if not runs:
            continue
        fid, fname = fids[row.group], _slug(row.group)
        folder = root / _slug(row.algorithm)
        scenarios = []
        for dim in sorted({len(r.rec.get("parameter_names") or []) for r in runs}):
            rel = f"data_f{fid}_{fname}/IOHprofiler_f{fid}_DIM{dim}.dat"
            lines, meta = [], []
            for r in runs:
                if len(r.rec.get("parameter_names") or []) != dim:
                    continue
                lines.append(IOH_DAT_HEADER)
                if int(r.evals[0]) > 1:
                    # readers split runs at evaluation 1; the history holds the best of each batch
                    lines.append(f"1 {r.best[0]:.10g}")
                for e, c in zip(r.evals, r.best, strict=True):
                    lines.append(f"{int(e)} {c:.10g}")
                last = max(r.total_evals, int(r.evals[-1]))
                if last > int(r.evals[-1]):
                    lines.append(f"{last} {r.best[-1]:.10g}")
                k = int(np.argmin(r.best))
                x = [float(v) for v in (r.rec.get("searched") or {}).values()]
                meta.append(
                    {
                        "instance": _instance_id(r.instance),
                        "evals": last,
                        "best": {"evals": int(r.evals[k]), "y": float(r.best[k]), "x": x},
                    }
                )
            (folder / rel).parent.mkdir(parents=True, exist_ok=True)
            (folder / rel).write_text("\n".join(lines) + "\n")
            scenarios.append({"dimension": dim, "path": rel, "runs": meta})
        budgets = sorted({int(r.rec.get("budget") or 0) for r in runs})
        doc = {
            "version": IOH_FORMAT_VERSION,
            "suite": "imbench",
            "function_id": fid,
            "function_name": fname,
            "maximization": False,
            "algorithm": {
                "name": row.algorithm,
                "info": f"imbench plugin {row.values['optimizer']}, budget {'/'.join(map(str, budgets))}",
            },
            "attributes": ["evaluations", "raw_y"],
            "scenarios": scenarios,
        }
        (folder / f"IOHprofiler_f{fid}_{fname}.json").write_text(json.dumps(doc, indent=1) + "\n")
    (root / "README.txt").write_text(
        "Runs exported by python -m benchmark.report in IOHexperimenter's Analyzer format "
        f"(version {IOH_FORMAT_VERSION}): load this folder, or ioh.zip, in IOHanalyzer.\n"
        "Function ids: " + "; ".join(f"f{fids[g]} = {g}" for g in groups) + ".\n"
        "Rows are the harness's history (one per improvement of the best cost) plus the last evaluation, "
        + (y_note or "so raw_y is the best cost so far; a first row at evaluation 1 carries the best cost of "
                     "the first batch (readers split runs there). Instances are noise.seed + 1.") + "\n"
    )
    shutil.make_archive(str(out / "ioh"), "zip", root_dir=root)
    return root


def _instance_id(instance: str) -> int:
    try:
        return int(float(instance)) + 1
    except ValueError:
        return 1
