"""Calibration of the diagnosis's selection share on development data and form variants.

    python -m benchmark.studies.calibration [n=30] [seed=101] [sources=own,plant] [target=0.05]
        [workdir=outputs/calibration] [out=results/calibration.md]    # (hours)

Sources (``sources=a,b,...``; ``a:SEED`` draws source ``a`` with its own seed, else the k-th
source draws ``seed + k``):

* ``own``: the project's own plant, every effect of ``conf/effect/`` in the forms its
  ``random_form`` draws;
* ``plant``: the independent plant's development forms (its blind draws: motors, scenarios,
  forms and sizes of its own);
* ``plant_variants``: form variants. The independent plant's forms that made the catalogue
  extend its own (:data:`synthetic.independent.forms.VARIANTS`: a tachometer's ripple or
  filter, a coupling's free play or hardening, deep bars, a two-body heating, a DC machine's or
  an eddy-current brake's load), diagnosed with the injected effect fitted in the catalogue's
  first form (:attr:`benchmark.core.effects.Effect.FIRST_FORM`): the right effect leaves what
  its form cannot fit, as on a real machine's record, and a rule that lets another effect take
  that makes false selections here.

Each is drawn as the blind evaluation draws (``benchmark.analysis.blind_sources``; a fifth
effect-free, three in ten of the others with two effects; the variants none effect-free), each
set's truth moved aside before the diagnosis sees the folder, and diagnosed at every share of
:data:`~benchmark.problems.timedomain.diagnosis.calibration.SHARES` (the base identified once,
the fits shared, :func:`diagnose_at_shares`), with the default configuration otherwise. The
held-out forms of the independent plant and motulator are never drawn here.

The chosen share is the smallest whose false-selection rate (sets whose verdict names an effect
that was not injected) is within ``target`` with its Wilson 95 % interval (its upper end at
most ``target``); the rates carry 95 % bootstrap intervals over the sets too. Per-set verdicts
are kept in ``workdir/<source>_<seed>/sets.jsonl`` (a rerun resumes).
"""

from __future__ import annotations

import functools
import json
import shutil
import sys
import time
from pathlib import Path

from hydra import compose, initialize_config_dir
from hydra.utils import instantiate
from omegaconf import open_dict

from benchmark.analysis.blind import BlindSettings, diagnosis_config
from benchmark.analysis.blind_sources import SOURCES
from benchmark.core.config_files import CONFIG_DIR
from benchmark.core.harness import identify, load_dataset, resolved
from benchmark.core.io import write_text_atomic
from benchmark.problems.timedomain.diagnosis.calibration import (
    SHARES,
    chosen_share,
    diagnose_at_shares,
    fewest_false,
    rates,
)
from synthetic.independent.forms import VARIANTS

CONF = str(CONFIG_DIR)


def parse(argv: list[str]) -> dict:
    opts = {"n": 30, "seed": 101, "sources": "own,plant", "target": 0.05, "workdir": "outputs/calibration",
            "out": "results/calibration.md"}
    for a in argv:
        k, _, v = a.partition("=")
        if k not in opts:
            raise SystemExit(f"unknown option {k!r}; known: {sorted(opts)}")
        opts[k] = type(opts[k])(v)
    return opts


#: Calibration sources that are form variants: the blind source they draw from and the overrides
#: that make them (the forms of :data:`synthetic.independent.forms.VARIANTS`, their effects only).
VARIANT_SOURCES = {"plant_variants": ("plant", ["forms=variants", "free_share=0.0",
                                                "only_effects=[" + ",".join(sorted(VARIANTS)) + "]"])}


def source_settings(source: str, n: int, seed: int, workdir: Path) -> BlindSettings:
    blind_source, extra = VARIANT_SOURCES.get(source, (source, []))
    with initialize_config_dir(config_dir=CONF, version_base="1.3"):
        cfg = compose("blind", overrides=[f"source={blind_source}", f"n={n}", f"seed={seed}", "free_share=0.2",
                                          "two_share=0.3", f"workdir={workdir}", *extra])
    with open_dict(cfg):
        cfg.hydra = None
    return BlindSettings.from_run(cfg)


def calibrate_source(source: str, n: int, seed: int, workdir: Path) -> list[dict]:
    """Every set of one source diagnosed at every share (resumed from ``sets.jsonl``)."""
    settings = source_settings(source, n, seed, workdir)
    draws, make = SOURCES[settings.source](settings)
    variants = source in VARIANT_SOURCES  # the injected effects fitted in their first forms
    work = workdir / f"{source}_{seed}"
    work.mkdir(parents=True, exist_ok=True)
    store = work / "sets.jsonl"
    done = {}
    if store.exists():
        done = {r["index"]: r for r in map(json.loads, store.read_text().splitlines())}
    out = []
    for d in draws:
        if d["index"] in done:
            out.append(done[d["index"]])
            continue
        folder = work / "sets" / f"set_{d['index']:03d}"
        if folder.exists():
            shutil.rmtree(folder)
        make(d, folder)
        (folder / "truth.yaml").replace(work / f"truth_{d['index']:03d}.yaml")
        cfg = diagnosis_config(settings, folder)
        dataset, _ = load_dataset(cfg, with_truth=False)
        base = functools.partial(identify, plugin=instantiate(cfg.optimizer.plugin), budget=int(cfg.budget),
                                 seed=int(cfg.seed), name=str(cfg.optimizer.name), polish_budget=int(cfg.polish_budget))
        t0, c0 = time.perf_counter(), time.process_time()
        verdicts = diagnose_at_shares(resolved(cfg), dataset, base, first_form=d["effects"] if variants else ())
        row = {"source": source, "seed": seed, "index": d["index"], "injected": list(d["effects"]),
               "skew_candidate": d.get("channel_skew") is not None, "verdicts": verdicts,
               "wall_s": time.perf_counter() - t0, "cpu_s": time.process_time() - c0}
        with open(store, "a") as fh:
            fh.write(json.dumps(row, default=float) + "\n")
        shutil.rmtree(folder, ignore_errors=True)
        print(f"[{source}] set {d['index']}: {'+'.join(d['effects']) or 'none'} -> "
              + "; ".join(f"{v['share']:g}: {'+'.join(v['effects']) or v['status']}" for v in verdicts), flush=True)
        out.append(row)
    return out


def _pct(x) -> str:
    return f"{100 * x:.0f} %"


def _ci(r: dict, key: str) -> str:
    lo, hi = r[key + "_wilson95"]
    return f"{round(r[key] * r['sets'])}/{r['sets']} | {_pct(r[key])} ({_pct(lo)}-{_pct(hi)})"


def _by_source(sets: list[dict]) -> list[str]:
    """Per source: false selections and exact sets at each share (``k/n``)."""
    lines = ["| source | " + " | ".join(f"tau {s:g}: false, exact" for s in SHARES) + " |",
             "|---|" + "---|" * len(SHARES)]
    for source in sorted({r["source"] for r in sets}):
        part = rates([r for r in sets if r["source"] == source])
        cells = [f"{round(r['false_selection'] * r['sets'])}/{r['sets']}, {round(r['exact'] * r['sets'])}/{r['sets']}"
                 for r in part]
        lines.append(f"| {source} | " + " | ".join(cells) + " |")
    return lines


def render(sets: list[dict], table: list[dict], target: float, chosen: float | None, command: str) -> str:
    counts = ", ".join(f"{s}: {sum(1 for r in sets if r['source'] == s)}" for s in sorted({r["source"] for r in sets}))
    lines = ["# Calibration of the diagnosis's selection share (development data and form variants)", "",
             f"Command: `{command}`", "",
             "An effect earns its place when the model without it is above the noise band and it removes at least "
             "the share `tau` of the excess held-out chi^2 that model leaves (docs/diagnosis.md). Each set below "
             "was diagnosed at every share (base identified once, fits shared); a false selection is a verdict "
             "naming an effect that was not injected. Intervals: Wilson 95 %; the chosen share is the smallest whose "
             "false-selection rate is within the target with its interval.", "",
             f"Sets: {len(sets)} ({counts}); target false-selection rate {_pct(target)}.", "",
             "| share tau | false selections | rate (95 % CI) | named exactly | rate (95 % CI) "
             "| channel_delay named, not injected (of sets where it was a candidate) |",
             "|---|---|---|---|---|---|"]
    for r in table:
        lines.append(f"| {r['share']:g} | {_ci(r, 'false_selection')} | {_ci(r, 'exact')} | "
                     f"{r['channel_delay_named_not_injected']}/{r['channel_delay_candidate_not_injected']} |")
    lines += ["", f"Chosen share: **{chosen:g}**" if chosen is not None else
              f"No share meets the target; the fewest false selections: **{fewest_false(table):g}**.", ""]
    lines += _by_source(sets) + [""]
    lines += ["| source | seed | set | injected | " + " | ".join(f"tau {s:g}" for s in SHARES) + " |",
              "|---|---|---|---|" + "---|" * len(SHARES)]
    for s in sets:
        cells = [("+".join(v["effects"]) or v["status"]) + f" ({v['gap_before']:.2f} -> {v['gap_after']:.2f})"
                 for v in s["verdicts"]]
        injected = "+".join(s["injected"]) or "none"
        lines.append(f"| {s['source']} | {s.get('seed', '')} | {s['index']} | {injected} | " + " | ".join(cells) + " |")
    cpu = sum(s.get("cpu_s", 0.0) for s in sets)
    lines += ["", f"CPU time of the diagnoses at all shares: {cpu / 3600:.1f} h.", ""]
    return "\n".join(lines)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    opts = parse(argv)
    workdir = Path(opts["workdir"])
    sets = []
    for k, entry in enumerate(opts["sources"].split(",")):
        source, _, own_seed = entry.partition(":")  # source:seed, else the k-th source draws seed + k
        sets += calibrate_source(source, opts["n"], int(own_seed) if own_seed else opts["seed"] + k, workdir)
    table = rates(sets)
    chosen = chosen_share(table, opts["target"])
    text = render(sets, table, opts["target"], chosen, "python -m benchmark.studies.calibration " + " ".join(argv))
    write_text_atomic(Path(opts["out"]), text)
    write_text_atomic(workdir / "calibration.json", json.dumps({"rates": table, "chosen": chosen}, indent=1) + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
