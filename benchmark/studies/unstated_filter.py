"""A speed filter the record does not state: does the diagnosis's base identification ask for it,
and does it stay silent where the speed has none?

The sets are blind draws (``python -m benchmark.blind``'s sources, the independent plant and
motulator, held-out forms: a slip clutch, a battery charger, a probe with a knee, ...). A draw
whose speed channel has a filter (a tachometer's RC filter, an encoder's gate, a healthy channel's
own) states it in ``meta.yaml``; here every statement is removed, and each set's base model is
identified as the diagnosis identifies it (:func:`~benchmark.problems.timedomain.diagnosis.run.
identify_base`, the diagnosis's default optimiser and budgets). The table gives, per set, the
filter it has, the one the identification asks for (``unstated_speed_filter``) and the speed's
misfit over its noise without and with it; the summary, how often a filter is asked for where
there is none (a coupling's lag, a load, a tachometer's gain may look like one) and where there
is one.

    python -m benchmark.studies.unstated_filter OUTDIR [n=16] [seed=474] [sources=plant,motulator]

Source ``s`` of ``sources`` takes seed ``seed + s`` (its place in the list).
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import yaml

from benchmark.core.uncertainty import wilson


def blind_settings(source: str, n: int, seed: int, work: Path):
    """The blind run's settings of ``source`` (held-out forms, sets made in ``work``)."""
    from hydra import compose, initialize_config_dir

    from benchmark.analysis.blind import BlindSettings
    from benchmark.core.config_files import CONFIG_DIR

    with initialize_config_dir(version_base="1.3", config_dir=str(CONFIG_DIR)):
        cfg = compose("blind", overrides=[f"source={source}", f"n={n}", f"seed={seed}", "forms=heldout",
                                          f"workdir={work}", f"out={work}"])
    return BlindSettings.from_run(cfg)


def base_identification(settings, folder: Path) -> dict:
    """The diagnosis's base identification of ``folder`` (its default configuration): what it
    ended at, with ``unstated_speed_filter``."""
    from benchmark.analysis.blind import diagnosis_config
    from benchmark.core.harness import base_identify, load_dataset, resolved
    from benchmark.problems.timedomain.diagnosis.run import diagnosis_settings, identify_base
    from benchmark.problems.timedomain.settings import TimeDomainSettings

    cfg = diagnosis_config(settings, folder)
    run = resolved(cfg)
    dataset, _ = load_dataset(cfg, with_truth=False)
    _, _, record = identify_base(TimeDomainSettings.from_run(run), dataset, diagnosis_settings(run).base_case,
                                 base_identify(cfg), seed=int(run.get("seed", 0) or 0))
    return record


def run_source(source: str, n: int, seed: int, out: Path, indices=None) -> list[dict]:
    """Every set of ``source`` (of the ``n`` drawn, those of ``indices`` when given) made, its
    filter's statement removed, its base identified."""
    from benchmark.analysis.blind import make_set
    from benchmark.analysis.blind_sources import SOURCES

    settings = blind_settings(source, n, seed, out / source)
    draws, make = SOURCES[source](settings)
    rows = []
    for d in draws if indices is None else [d for d in draws if d["index"] in indices]:
        folder = make_set(d, make, out / source)
        unstate_filter(folder)
        t0 = time.perf_counter()
        record = base_identification(settings, folder)
        hint = record.get("unstated_speed_filter")
        rows.append({"source": source, "index": d["index"], "effects": d["effects"],
                     "speed_filter": d["speed_filter"], "speed_misfit": record.get("speed_misfit"),
                     "asked": None if hint is None else hint["time_constant"],
                     "misfit_with": None if hint is None else hint["misfit_with"], "wall_s": time.perf_counter() - t0})
        r = rows[-1]
        print(f"[{source}] set {d['index']:3d} {'+'.join(d['effects']) or 'none':<40} filter "
              f"{_ms(r['speed_filter'])} asked {_ms(r['asked'])} ({r['wall_s']:.0f} s)", flush=True)
    return rows


def unstate_filter(folder: Path) -> None:
    """``folder/meta.yaml`` without its ``speed_filter`` (the other keys as they were)."""
    meta = folder / "meta.yaml"
    doc = yaml.safe_load(meta.read_text()) or {}
    if doc.pop("speed_filter", None) is not None:
        meta.write_text(yaml.safe_dump(doc, sort_keys=False))


def _ms(tau: float | None) -> str:
    return "-" if tau is None else f"{1e3 * tau:.2f} ms"


def summary(rows: list[dict]) -> str:
    """Per source: filters asked for where the speed has none, and where it has one."""
    lines = ["| source | sets without a filter: asked | sets with one: asked | asked within 30 % of it |",
             "|---|---|---|---|"]
    for source in dict.fromkeys(r["source"] for r in rows):
        mine = [r for r in rows if r["source"] == source]
        free = [r for r in mine if r["speed_filter"] is None]
        filt = [r for r in mine if r["speed_filter"] is not None]
        false = sum(r["asked"] is not None for r in free)
        hit = sum(r["asked"] is not None for r in filt)
        close = sum(r["asked"] is not None and abs(r["asked"] / r["speed_filter"] - 1.0) <= 0.3 for r in filt)
        lo, hi = wilson(false, len(free))
        lines.append(f"| {source} | {false}/{len(free)} ({100 * lo:.0f}-{100 * hi:.0f} %) | {hit}/{len(filt)} "
                     f"| {close}/{len(filt)} |")
    return "\n".join(lines)


def table(rows: list[dict]) -> str:
    """Every set: its effects, the filter it has, the one asked for, the speed's misfit."""
    lines = ["| source | set | effects | filter it has | asked for | speed misfit over noise (without, with) | "
             "wall s |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        mis = "-" if r["speed_misfit"] is None else f"{r['speed_misfit']:.3g}"
        mis += "" if r["misfit_with"] is None else f", {r['misfit_with']:.3g}"
        lines.append(f"| {r['source']} | {r['index']} | {'+'.join(r['effects']) or 'none'} | {_ms(r['speed_filter'])} "
                     f"| {_ms(r['asked'])} | {mis} | {r['wall_s']:.0f} |")
    return "\n".join(lines)


def main(argv: list[str]) -> None:
    if not argv or "=" in argv[0]:
        raise SystemExit(__doc__)
    out = Path(argv[0])
    opts = {"n": "16", "seed": "474", "sources": "plant,motulator", **dict(a.split("=", 1) for a in argv[1:])}
    rows = []
    for k, source in enumerate(opts["sources"].split(",")):
        rows += run_source(source, int(opts["n"]), int(opts["seed"]) + k, out)
        (out / "rows.json").write_text(json.dumps(rows, indent=1))
    print(table(rows) + "\n\n" + summary(rows))


if __name__ == "__main__":
    main(sys.argv[1:])
