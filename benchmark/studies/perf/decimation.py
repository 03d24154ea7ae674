"""A start-up sampled at 48 kHz, read as recorded and one sample in four (``decimate: 4`` in
meta.yaml, :mod:`benchmark.problems.timedomain.decimation`), timed in one run.

    python -m benchmark.studies.perf.decimation OUT_DIR [diagnose=true] [effects=double_cage] [rate_khz=48]

Writes a 1 s noisy direct-on-line start of the paper's motor (``effects`` injected) sampled at
``rate_khz``, then runs ``python -m benchmark`` on it as recorded and read at about 12 kHz (and,
with ``diagnose=true``, ``python -m benchmark.diagnose``), each in a fresh interpreter, the full
record first (the compile cache warmed by a run before), and prints the wall and CPU seconds with
their ratio (full over read), each estimate's difference from the full record's in the full
record's standard errors, the standard errors' ratio (read over full), the fit quality and the
verdicts. A ratio compares two runs made on the same machine one after the other.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import yaml

from benchmark.studies.perf.common import ROOT, md_table, run_timed

NAMES = ("Rs", "Ls", "Le", "Rr", "J")


def timed(module: str, overrides: list[str]) -> tuple[float, float]:
    """(wall s, CPU s) of ``python -m module overrides`` from this checkout, figures off."""
    wall, cpu, proc = run_timed(ROOT, module, [*overrides, "figures=false"])
    proc.check_returncode()
    return wall, cpu


def main(argv: list[str]) -> int:
    if not argv or "=" in argv[0]:
        raise SystemExit(__doc__)
    out = Path(argv[0]).resolve()
    opts = {"diagnose": "false", "effects": "", "rate_khz": "48"}
    for a in argv[1:]:
        key, _, value = a.partition("=")
        if key not in opts:
            raise SystemExit(f"unknown option {key!r}; known: {sorted(opts)}")
        opts[key] = value
    rate = float(opts["rate_khz"]) * 1e3
    k = max(1, round(rate / 12e3))
    full, read = out / "full", out / "read"
    shutil.rmtree(out, ignore_errors=True)
    subprocess.run([sys.executable, "-m", "synthetic", "noise=noisy", "motor.test.waveform=sinusoidal",
                    f"motor.test.sample_time={1 / rate!r}", f"motor.test.samples_per_state={round(rate / 300)}",
                    f"effects=[{opts['effects']}]", f"out={full}"], cwd=str(ROOT), check=True, capture_output=True)
    shutil.copytree(full, read)
    meta = yaml.safe_load((read / "meta.yaml").read_text())
    (read / "meta.yaml").write_text(yaml.safe_dump({**meta, "decimate": k}))
    timed("benchmark", [f"data.path={read}", f"hydra.run.dir={out / 'warm-up'}"])  # compiles the kernels
    if opts["diagnose"] == "true":
        timed("benchmark.diagnose", [f"data.path={read}", f"hydra.run.dir={out / 'warm-up-diagnosis'}"])
    rows, docs = [], {}
    for label, folder in (("full", full), ("read", read)):
        wall, cpu = timed("benchmark", [f"data.path={folder}", f"hydra.run.dir={out / ('id-' + label)}"])
        docs[label] = json.loads((out / f"id-{label}" / "result.json").read_text())
        rows.append([f"identification, {label}", f"{wall:.1f}", f"{cpu:.1f}"])
    if opts["diagnose"] == "true":
        for label, folder in (("full", full), ("read", read)):
            wall, cpu = timed("benchmark.diagnose", [f"data.path={folder}", f"hydra.run.dir={out / ('dg-' + label)}"])
            doc = json.loads((out / f"dg-{label}" / "diagnosis.json").read_text())
            rows.append([f"diagnosis, {label}: {doc['verdict']} ({doc['status']}), gap "
                         f"{doc['gap_before']['heldout_rms_over_noise']:.3f} -> "
                         f"{doc['gap_after']['heldout_rms_over_noise']:.3f}", f"{wall:.1f}", f"{cpu:.1f}"])
    for a, b in zip(rows[::2], rows[1::2], strict=True):
        b.append(f"{float(a[1]) / float(b[1]):.1f} / {float(a[2]) / float(b[2]):.1f}")
        a.append("")
    print(f"A 1 s start at {rate / 1e3:g} kHz, read one sample in {k} ({rate / k / 1e3:g} kHz); effects: "
          f"{opts['effects'] or 'none'}\n")
    print(md_table(["run", "wall s", "CPU s", "full / read (wall / CPU)"], rows) + "\n")
    f, r = docs["full"], docs["read"]
    print(md_table(["parameter", "(read - full) / s.e. of full", "s.e. read / full", "full: error / s.e.",
                    "read: error / s.e."],
                   [[n, f"{(r['estimate'][n] - f['estimate'][n]) / f['standard_error'][n]:+.2f}",
                     f"{r['standard_error'][n] / f['standard_error'][n]:.2f}",
                     f"{(f['estimate'][n] - f['truth'][n]) / f['standard_error'][n]:+.2f}",
                     f"{(r['estimate'][n] - r['truth'][n]) / r['standard_error'][n]:+.2f}"] for n in NAMES]))
    print("\nfit quality (RMS misfit / noise): full " + ", ".join(f"{c} {q['ratio']:.3f}" for c, q in
                                                                 f["fit_quality"].items())
          + "; read " + ", ".join(f"{c} {q['ratio']:.3f}" for c, q in r["fit_quality"].items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
