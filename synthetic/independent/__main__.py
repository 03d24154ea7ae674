"""Command line: make one independent data set.

    python -m synthetic.independent --motor paper_1kw --scenario dol \\
        --effects double_cage,main_saturation --seed 3 --out DIR [--duration 1.0] \\
        [--sample-rate 10000] [--stop [SECONDS]] [--forms heldout,double_cage=deep_bar,...] \\
        [--ideal-supply] [--no-speed] [--torque] [--blind]

``--blind`` draws everything (motor spread, scenario, effects, noise) from the seed instead.
``--forms`` takes a form set (``development``, the default, ``heldout`` or ``all``: which forms
the effects' forms are drawn from, :mod:`synthetic.independent.forms`) and ``name=form`` pairs
that fix single forms, comma-separated.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from synthetic.independent.blind import draw_blind_set
from synthetic.independent.dataset import make_dataset, make_spec, write_dataset
from synthetic.independent.effects import EFFECTS
from synthetic.independent.forms import FORM_SETS
from synthetic.independent.motors import PRESETS


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m synthetic.independent",
                                 description="Independent induction-motor plant: write one start-up data set.")
    ap.add_argument("--motor", default="paper_1kw", choices=sorted(PRESETS))
    ap.add_argument("--scenario", default="six_step", choices=["dol", "six_step", "pwm"])
    ap.add_argument("--effects", default="", help=f"comma-separated, from: {', '.join(EFFECTS)}")
    ap.add_argument("--forms", default="", help=f"a form set ({', '.join(FORM_SETS)}; default development) and/or "
                    "name=form pairs, comma-separated")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", required=True, help="output folder")
    ap.add_argument("--duration", type=float, default=1.0, help="start-up record after switch-on, s")
    ap.add_argument("--sample-rate", type=float, default=None, help="Hz (default: the motor's)")
    ap.add_argument("--oversampling", type=int, default=10, help="internal steps per sample (at least)")
    ap.add_argument("--stop", nargs="?", type=float, const=20.0, default=None,
                    help="also record a free stop of this many seconds (default 20)")
    ap.add_argument("--ideal-supply", action="store_true", help="no grid imperfections / fixed PWM ramp")
    ap.add_argument("--no-speed", action="store_true", help="record without a speed column")
    ap.add_argument("--torque", action="store_true", help="record the shaft torque")
    ap.add_argument("--fifth-harmonic", type=float, default=None,
                    help="grid voltage's 5th harmonic, fraction of the fundamental (dol; default: drawn)")
    ap.add_argument("--dc-resistance", action="store_true",
                    help="write the stator's DC resistance into meta.yaml (stator_dc_resistance)")
    ap.add_argument("--blind", action="store_true", help="draw motor spread, scenario, effects and noise from --seed")
    return ap


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    names = [e.strip() for e in args.effects.split(",") if e.strip()]
    unknown = [e for e in names if e not in EFFECTS]
    if unknown:
        print(f"unknown effect(s) {unknown}; known: {list(EFFECTS)}", file=sys.stderr)
        return 2
    items = [x.strip() for x in args.forms.split(",") if x.strip()]
    forms = dict(x.split("=", 1) for x in items if "=" in x)
    sets = [x for x in items if "=" not in x] or ["development"]
    if len(sets) > 1 or sets[0] not in FORM_SETS:
        print(f"--forms: one form set of {FORM_SETS} and name=form pairs, got {args.forms!r}", file=sys.stderr)
        return 2
    try:
        if args.blind:
            spec = draw_blind_set(np.random.default_rng(args.seed), effects=names or None, forms=sets[0])
        else:
            spec = make_spec(args.motor, args.scenario, names, seed=args.seed, duration=args.duration,
                             sample_rate=args.sample_rate, stop=args.stop, forms=forms,
                             ideal_supply=args.ideal_supply, oversampling=args.oversampling,
                             has_speed=not args.no_speed, has_torque=args.torque, form_set=sets[0])
            if args.fifth_harmonic is not None and spec["scenario"]["kind"] == "dol":
                spec["scenario"]["h5"] = float(args.fifth_harmonic)
            if args.dc_resistance:
                spec["meta"]["dc_resistance"] = True
        t0 = time.perf_counter()
        ds = make_dataset(spec)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    folder = write_dataset(ds, args.out)
    eff = ", ".join(f"{e['name']}({e['form']}, {e['size']:.4g} {e['unit']})" for e in ds.truth["effects"]) or "none"
    print(f"{folder}: {spec['motor']} {spec['scenario']['kind']}, {len(ds.startup['t'])} samples, effects: {eff}; "
          f"simulated in {time.perf_counter() - t0:.2f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
