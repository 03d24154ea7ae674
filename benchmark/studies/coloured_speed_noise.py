"""Effect-free starts whose speed sensor's own noise passes its stated filter: is the noise read
right, and is the record called effect-free?

A tachogenerator's brushes and commutation make noise before its RC filter, so the recorded
speed noise is coloured by it, beside the acquisition's white noise. This study draws ``n``
effect-free motulator starts (two motors, direct-on-line and six-step, each with a free stop),
each with a filter of 1-5 ms stated in ``meta.yaml`` (``speed_filter``), white speed noise of
0.05-0.2 rad/s and coloured noise of 0.5-2 times it; beside each, the same record without speed
noise gives the noise really recorded. Every set is diagnosed by the user's command
(``python -m benchmark.diagnose``, default configuration) in a fresh process whose
``PYTHONPATH`` is ``code`` (this checkout by default; an earlier commit unpacked with
``git archive`` for a before/after), and the table gives, per set, the speed's and the stop's
noise as the diagnosis estimated them over the noise recorded, and the verdict.

    python -m benchmark.studies.coloured_speed_noise OUTDIR [n=8] [seed=472] [code=PATH] [tag=NAME]
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import yaml

MOTORS = ("motulator_2p2kw", "alonge_1kw")  #: zoo motors, taken in turn
SCENARIOS = ("dol", "six_step")  #: taken in turn every second set
SAMPLE_RATE, DURATION = 12000.0, 0.6  #: Hz, s of start-up (the blind motulator source's)


def draw(seed: int, n: int) -> list[dict]:
    """The sets' motors, scenarios, filters and noise (one stream per study)."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        white = float(rng.uniform(0.05, 0.2))
        out.append({"index": i, "motor": MOTORS[i % 2], "scenario": SCENARIOS[(i // 2) % 2],
                    "noise": {"current_std": float(rng.uniform(0.02, 0.08)),
                              "current_colored_std": float(rng.uniform(0.0, 0.05)), "speed_std": white,
                              "speed_coloured_std": float(rng.uniform(0.5, 2.0)) * white,
                              "speed_filter": float(rng.uniform(1e-3, 5e-3))},
                    "seed": int(rng.integers(2**31 - 1))})
    return out


def make(d: dict, folder: Path) -> None:
    """Set ``d`` and its twin without speed noise (``folder``/set, ``folder``/clean), the filter stated."""
    from synthetic.motulator_source import make_motulator_dataset
    from synthetic.zoo import get_motor, motor_description

    quiet = {**d["noise"], "speed_std": 0.0, "speed_coloured_std": 0.0}
    for name, noise in (("set", d["noise"]), ("clean", quiet)):
        if (folder / name / "meta.yaml").exists():
            continue
        make_motulator_dataset(motor_description(get_motor(d["motor"])), d["scenario"], None, noise, d["seed"],
                               folder / name, DURATION, SAMPLE_RATE, True)
        meta = yaml.safe_load((folder / name / "meta.yaml").read_text())
        meta["speed_filter"] = d["noise"]["speed_filter"]
        (folder / name / "meta.yaml").write_text(yaml.safe_dump(meta, sort_keys=False))


def recorded_noise(folder: Path) -> tuple[float, float]:
    """The speed noise really recorded (rad/s): over the start-up's last 30 %, over the stop."""
    from benchmark.problems.timedomain.data import load_startup_dataset

    noisy, clean = load_startup_dataset(folder / "set"), load_startup_dataset(folder / "clean")
    start = noisy.startups[0].speed - clean.startups[0].speed
    return float(np.std(start[int(0.7 * len(start)):])), float(np.std(noisy.stops[0].speed - clean.stops[0].speed))


def diagnose(code: Path, data: Path, outdir: Path) -> dict:
    """The diagnosis document of ``python -m benchmark.diagnose`` run with ``code`` on ``data``."""
    env = dict(os.environ, PYTHONPATH=str(code), MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, "-m", "benchmark.diagnose", f"data.path={data}", "figures=false",
                           f"hydra.run.dir={outdir}"], cwd=str(code), env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"diagnosis of {data} failed:\n{proc.stderr[-3000:]}")
    return json.loads((outdir / "diagnosis.json").read_text())


def main(argv: list[str]) -> None:
    if not argv or "=" in argv[0]:
        raise SystemExit(__doc__)
    out = Path(argv[0])
    opts = {"n": "8", "seed": "472", "code": str(Path(__file__).resolve().parents[2]), "tag": "this",
            **dict(a.split("=", 1) for a in argv[1:])}
    rows = []
    for d in draw(int(opts["seed"]), int(opts["n"])):
        folder = out / f"set{d['index']}"
        make(d, folder)
        true_speed, true_stop = recorded_noise(folder)
        doc = diagnose(Path(opts["code"]), folder / "set", out / f"diagnosis_{opts['tag']}" / f"set{d['index']}")
        est = doc["noise"]
        rows.append({**d, "recorded": [true_speed, true_stop], "verdict": doc["status"],
                     "gap": doc["gap_before"]["heldout_rms_over_noise"],
                     "read": [est["speed"]["std"] / true_speed, est["stop_speed"]["std"] / true_stop]})
    (out / f"rows_{opts['tag']}.json").write_text(json.dumps(rows, indent=1))
    print("| set | motor | start | filter ms | white, coloured rad/s | speed noise read | stop noise read | verdict "
          "(gap) |\n|---|---|---|---|---|---|---|---|")
    for r in rows:
        nz = r["noise"]
        print(f"| {r['index']} | {r['motor']} | {r['scenario']} | {1e3 * nz['speed_filter']:.1f} | "
              f"{nz['speed_std']:.3f}, {nz['speed_coloured_std']:.3f} | {r['read'][0]:.2f} | {r['read'][1]:.2f} | "
              f"{r['verdict']} ({r['gap']:.3f}) |")
    read = np.array([r["read"] for r in rows])
    print(f"\n{opts['tag']}: effect-free verdicts {sum(r['verdict'] == 'no_gap' for r in rows)} of {len(rows)}; "
          f"speed noise read {read[:, 0].min():.2f}-{read[:, 0].max():.2f}, stop {read[:, 1].min():.2f}-"
          f"{read[:, 1].max():.2f} of the noise recorded")


if __name__ == "__main__":
    main(sys.argv[1:])
