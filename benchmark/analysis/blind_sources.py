"""The data sources of the blind evaluation (:mod:`benchmark.analysis.blind`).

Each source is a function of the :class:`~benchmark.analysis.blind.BlindSettings` returning
``(draws, make)``: the list of drawn sets (each a dict with ``index`` and the injected
``effects``) and ``make(draw, folder)``, which writes that set's data folder (with its
``truth.yaml``, which the loop moves away before the diagnosis sees the folder).

* ``own``: the project's synthetic plant with the effects of ``conf/effect/``;
* ``plant``: the independent flux-linkage plant (:mod:`synthetic.independent`);
* ``motulator``: the third-party simulator (effects ``main_saturation``, ``two_mass``,
  ``load_torque``).

The plant and motulator draw their forms from ``settings.forms`` (development, held-out or
all: :mod:`synthetic.independent.forms`); with ``development`` every draw is the one it was
before the held-out forms existed. The own plant has no held-out forms.
"""

from __future__ import annotations

import copy
import json
import shutil
from pathlib import Path

import numpy as np
import yaml
from omegaconf import open_dict

from benchmark.analysis.blind import (
    MOTOR_KEYS,
    BlindSettings,
    cycled,
    diagnosis_config,
    draw_sets,
    generator_config,
    n_effects_of,
)
from benchmark.core.effects import load_effects

#: Share of the sets without an injected channel skew whose meta.yaml still states one (a
#: multiplexed card whose acquisition software aligned the channels): ``channel_delay`` is a
#: candidate there and must not be named.
STATED_SKEW_WITHOUT = 0.3


def stated_skew(settings: BlindSettings, d: dict, injected: float | None) -> float | None:
    """The channel skew (samples) draw ``d``'s ``meta.yaml`` states: the injected one (a card's
    documented sequence), else with probability :data:`STATED_SKEW_WITHOUT` one of the same
    range the record does not carry, else none. Drawn from the set's own stream (so that the
    other draws do not change)."""
    if injected is not None:
        return injected if isinstance(injected, dict) else float(injected)
    rng = np.random.default_rng([int(settings.seed), int(d["index"]), 7])
    if rng.random() >= STATED_SKEW_WITHOUT:
        return None
    return float(rng.choice([-1.0, 1.0]) * rng.uniform(0.1, 2.0))


#: Share of the sets without a tachometer effect whose speed channel has a filter of its own,
#: stated in ``meta.yaml`` as an injected one is (a tachogenerator's RC filter is common on a
#: healthy bench): a statement then says nothing of the truth.
STATED_FILTER_WITHOUT = 0.3


def stated_filter(settings: BlindSettings, d: dict, injected: float | None) -> float | None:
    """The speed filter (s) draw ``d``'s speed channel has and ``meta.yaml`` states
    (``speed_filter``): the injected tachometer's (``injected``), else with probability
    :data:`STATED_FILTER_WITHOUT` an RC filter of 1-5 ms of the channel's own, else none.
    Drawn from the set's own stream (the other draws do not change)."""
    if injected:
        return float(injected)
    rng = np.random.default_rng([int(settings.seed), int(d["index"]), 8])
    if rng.random() >= STATED_FILTER_WITHOUT:
        return None
    return float(rng.uniform(1e-3, 5e-3))


def coloured_speed_noise(settings: BlindSettings, d: dict, white: float) -> float:
    """The std (rad/s) of a filtered speed sensor's own noise as it leaves its filter (a
    tachogenerator's brushes and commutation, coloured by its RC filter), beside the
    acquisition's ``white``: 0.5-2 times it, from the set's own stream (the other draws do not
    change)."""
    return float(white * np.random.default_rng([int(settings.seed), int(d["index"]), 9]).uniform(0.5, 2.0))


def plant_speed_filter(spec: dict) -> float | None:
    """The filter (s) the plant's tachometer effect puts on the speed (:mod:`synthetic.independent.sensor_effects`),
    as ``meta.yaml`` states it: an RC filter's time constant, half an encoder's gate time."""
    tach = next((e for e in spec["effects"] if e["name"] == "speed_sensor_gain"), {})
    if tach.get("time_constant"):
        return float(tach["time_constant"])
    return 0.5 * float(tach["gate_time"]) if tach.get("gate_time") else None


def state_filter(folder: Path, tau: float | None) -> None:
    """Write ``speed_filter`` (s) into ``folder/meta.yaml`` (nothing when ``tau`` is None)."""
    if tau is not None:
        _set_meta(folder, "speed_filter", float(tau))


def card_sequence(skew: dict, kind: str) -> dict:
    """The ``channel_skew`` mapping a multiplexed card's documentation gives for the plant's
    ``mux_skew`` draw ``skew`` (its channels ``order`` converted ``size`` samples apart); an
    inverter's voltages come from its gates, not from the card, and have none."""
    seq = {c: k * float(skew["size"]) for k, c in enumerate(skew["order"])}
    return {c: v for c, v in seq.items() if kind == "dol" or c.startswith("i_")}


def blind_description(folder: Path, text: str) -> None:
    """Replace ``folder/meta.yaml``'s description (a simulator's names the effects it injected)
    by ``text``: a blind set's files say nothing of its truth."""
    _set_meta(folder, "description", text)


def _set_meta(folder: Path, key: str, value) -> None:
    """Set ``key`` of ``folder/meta.yaml`` to ``value``, the other keys as they were."""
    meta = Path(folder) / "meta.yaml"
    doc = yaml.safe_load(meta.read_text()) or {}
    doc[key] = value
    meta.write_text(yaml.safe_dump(doc, sort_keys=False))


def state_skew(folder: Path, skew: float | None) -> None:
    """Write ``channel_skew`` (samples) into ``folder/meta.yaml`` (nothing when ``skew`` is None)."""
    if skew is None:
        return
    _set_meta(folder, "channel_skew", {k: float(v) for k, v in skew.items()} if isinstance(skew, dict) else float(skew))


def own_source(settings: BlindSettings):
    """(draws, make(d, folder)) of the project's own synthetic plant."""
    from synthetic.timedomain import generate

    if settings.forms == "heldout":
        from benchmark.core.errors import ConfigError

        raise ConfigError("forms=heldout: the own plant's forms are the diagnosis's own effect models, it has no "
                          "held-out forms; use source=plant or source=motulator")
    draws = draw_sets(settings, exclude=settings.in_base)
    lag = load_effects("timedomain")["channel_delay"].form.get("lag", "current")
    for d in draws:
        injected = None
        if "channel_delay" in d["effects"]:
            sign = -1.0 if d["form"].get("channel_delay", {}).get("lag", lag) == "voltage" else 1.0
            injected = sign * d["size"]["channel_delay"]
        d["channel_skew"] = stated_skew(settings, d, injected)

    def make(d, folder):
        generate(generator_config(settings, d), folder)
        state_skew(folder, d.get("channel_skew"))

    return draws, make


def plant_source(settings: BlindSettings):
    """(draws, make) of the independent plant: its own motors, scenarios, sizes, forms, noise."""
    from synthetic.independent import EFFECTS, draw_blind_set, make_dataset, write_dataset
    from synthetic.independent.dataset import scenario_with_duration

    ours = set(load_effects("timedomain"))
    allowed = sorted(e for e in EFFECTS if e in ours and e not in settings.in_base and settings.may_inject(e))
    seeds = np.random.SeedSequence(settings.seed).spawn(settings.n)
    draws = []
    for i, ss in enumerate(seeds):
        rng = np.random.default_rng(ss)
        k = n_effects_of(i, settings)
        kind = str(rng.choice(["dol", "six_step", "pwm"], p=[0.4, 0.35, 0.25]))
        pool = [e for e in allowed if not (EFFECTS[e].inverter_only and kind == "dol")]
        chosen = sorted(str(e) for e in rng.choice(pool, size=k, replace=False)) if k else []
        if settings.cycle_effects and k == 1:
            chosen = [cycled(i, settings, allowed)]
            if EFFECTS[chosen[0]].inverter_only and kind == "dol":
                kind = str(rng.choice(["six_step", "pwm"]))
        spec = draw_blind_set(rng, effects=chosen, scenario=kind, forms=settings.forms)
        if settings.plant_duration:  # default: the plant's own draw (0.8-1.5 s: big motors need it)
            spec["scenario"] = scenario_with_duration(spec["scenario"], settings.plant_duration, spec["sample_rate"])
        if not settings.plant_stop:
            spec["stop"] = None
        d = {"index": i, "effects": chosen, "spec": spec, "scenario": kind, "motor": spec["motor"]}
        skew = next((e for e in spec["effects"] if e["name"] == "channel_delay"), None)
        injected = None if skew is None else (-1.0 if skew["form"] == "voltage_lag" else 1.0) * float(skew["size"])
        if skew is not None and skew["form"] == "mux_skew":
            injected = card_sequence(skew, kind)
        d["channel_skew"] = stated_skew(settings, d, injected)
        d["speed_filter"] = None
        if spec["sensors"].get("has_speed", True):
            tau = plant_speed_filter(spec)
            d["speed_filter"] = stated_filter(settings, d, tau)
            if tau is None and "speed_sensor_gain" not in chosen and d["speed_filter"] is not None:
                spec["sensors"]["speed_lag"] = d["speed_filter"]  # the plant's own RC filter on a healthy channel
        draws.append(d)

    def make(d, folder):
        made = make_dataset(d["spec"])
        write_dataset(made, folder)
        skew = d.get("channel_skew")
        if isinstance(skew, dict):  # the card's sequence at its realised slot (a card's timing is documented)
            eff = next(e for e in made.truth["effects"] if e["name"] == "channel_delay")
            skew = card_sequence({**eff, "size": eff.get("achieved_size", eff["size"])}, d["scenario"])
        state_skew(folder, skew)
        state_filter(folder, d.get("speed_filter"))

    return draws, make


MOTULATOR_EFFECTS = ("main_saturation", "two_mass", "load_torque")
#: Saturation exponents of motulator's magnetising curve ``L_u/(1 + (psi/psi_k)**S)`` the draws take
#: (7 is that of motulator's own saturated 2.2 kW example machine).
MOTULATOR_SATURATION_EXPONENTS = (2.0, 4.0, 6.0, 7.0)


def motulator_motor(settings: BlindSettings, name: str) -> tuple[dict, float]:
    """Motor ``name`` of the motulator source: ``preset`` (the run's motor, its DC link and
    ``settings.rated_power``) or a zoo motor (:mod:`synthetic.zoo`, e.g. ``motulator_2p2kw``,
    motulator's own 2.2 kW, 400 V, 4-pole example machine), as ``make_motulator_dataset`` takes
    it; and the scale of its current noise against the preset's (the ratio of rated power over
    voltage, so that the noise is the same fraction of the rated current)."""
    base = copy.deepcopy(dict(settings.run["motor"]))
    preset_volts = float(np.sqrt(1.5) * 2.0 * float(base["test"]["dc_link_voltage"]) / np.pi)
    if name == "preset":
        return ({"parameters": dict(base["parameters"]), "pole_pairs": int(base["pole_pairs"]), "frequency": 50.0,
                 "dc_link_voltage": float(base["test"]["dc_link_voltage"]), "rated_power": settings.rated_power},
                1.0)
    from synthetic.zoo import get_motor, motor_description

    try:
        motor = motor_description(get_motor(name))
    except KeyError as exc:
        from benchmark.core.errors import ConfigError

        raise ConfigError(f"motulator_motors: {exc.args[0]} (or 'preset')") from None
    scale = (motor["rated_power"] / motor["voltage"]) / (float(settings.rated_power) / preset_volts)
    return motor, float(scale)


def motulator_options(rng: np.random.Generator, name: str, forms: str, duration: float) -> dict:
    """The options of effect ``name`` of a motulator draw, its form from the form set ``forms``
    (:func:`synthetic.independent.forms.motulator_forms_of`; a single development form takes
    no draw, so that ``development`` draws are the ones made before the split)."""
    from synthetic.independent.forms import SWITCHED_LOADS, motulator_forms_of

    pool = motulator_forms_of(name, forms)
    form = pool[0] if len(pool) == 1 else str(rng.choice(pool))
    if name == "main_saturation":
        if form == "steel_gap":
            return {"form": form, "size": float(rng.uniform(0.15, 0.5)),
                    "iron_ratio": float(np.exp(rng.uniform(np.log(150.0), np.log(500.0))))}
        return {"size": float(rng.uniform(0.15, 0.5)), "exponent": float(rng.choice(MOTULATOR_SATURATION_EXPONENTS))}
    if name == "two_mass":
        opts = {"size": float(rng.uniform(0.3, 0.6)), "resonance_hz": float(rng.uniform(15, 40)),
                "damping_ratio": float(rng.uniform(0.05, 0.2))}
        if form == "elastomer":
            opts.update(form=form, hardening=float(rng.uniform(1.5, 3.0)))
        if form == "slip_clutch":
            opts.update(form=form, slip_share=float(rng.uniform(0.7, 1.8)))
        return opts
    opts = {"form": form, "size": float(rng.uniform(0.2, 0.6))}
    if form == "step":
        opts["time"] = float(rng.uniform(0.3, 0.6) * duration)
    if form in SWITCHED_LOADS:  # switched on at the start or later, with equal odds
        opts["time"] = 0.0 if rng.random() < 0.5 else float(rng.uniform(0.3, 0.6) * duration)
    if form == "dc_generator":
        opts.update(armature_time_constant=float(np.exp(rng.uniform(np.log(2e-3), np.log(2e-2)))),
                    emf=float(rng.uniform(100.0, 250.0)), brush_drop=float(rng.uniform(1.0, 2.0)))
    if form == "eddy_brake":
        opts.update(critical_speed_ratio=float(np.exp(rng.uniform(np.log(0.2), np.log(2.0)))),
                    field_time_constant=float(np.exp(rng.uniform(np.log(0.02), np.log(0.2)))))
    if form == "battery_charger":
        opts["cut_in_ratio"] = float(rng.uniform(0.3, 0.8))
    return opts


def motulator_source(settings: BlindSettings):
    """(draws, make) of motulator: a motor of ``settings.motulator_motors`` (:func:`motulator_motor`)
    spread, dol or six-step, its three effects (forms from ``settings.forms``)."""
    from synthetic.motulator_source import make_motulator_dataset

    motors = {name: motulator_motor(settings, name) for name in settings.motulator_motors}
    spread = settings.vary_motor
    seeds = np.random.SeedSequence(settings.seed).spawn(settings.n)
    draws = []
    for i, ss in enumerate(seeds):
        rng = np.random.default_rng(ss)
        k = n_effects_of(i, settings)
        chosen = sorted(str(e) for e in rng.choice(MOTULATOR_EFFECTS, size=k, replace=False)) if k else []
        factors = {m: float(np.exp(rng.uniform(-spread, spread))) for m in MOTOR_KEYS}
        opts = {e: motulator_options(rng, e, settings.forms, settings.duration) for e in chosen}
        scenario = str(rng.choice(["dol", "six_step"]))
        noise = {"current_std": float(rng.uniform(0.02, 0.08)), "current_colored_std": float(rng.uniform(0.0, 0.05)),
                 "speed_std": float(rng.uniform(0.05, 0.2)), "speed_quantum": float(rng.choice([0.0, 0.1, 0.5]))}
        seed = int(rng.integers(2**31 - 1))
        name = str(rng.choice(list(motors))) if len(motors) > 1 else next(iter(motors))
        motor, current_scale = copy.deepcopy(motors[name])
        motor["parameters"] = {k: float(v) * factors.get(k, 1.0) for k, v in motor["parameters"].items()}
        noise["current_std"] *= current_scale
        noise["current_colored_std"] *= current_scale
        draws.append({"index": i, "effects": chosen, "options": opts, "scenario": scenario, "motor": motor,
                      "motor_name": name, "noise": noise, "seed": seed})
        draws[-1]["speed_filter"] = stated_filter(settings, draws[-1], None)
        if draws[-1]["speed_filter"]:  # motulator's speed sensor behind an RC filter, before its noise
            noise["speed_filter"] = draws[-1]["speed_filter"]
            noise["speed_coloured_std"] = coloured_speed_noise(settings, draws[-1], noise["speed_std"])

    def make(d, folder):
        make_motulator_dataset(d["motor"], d["scenario"], d["options"] or None, d["noise"], d["seed"], Path(folder),
                               settings.duration, settings.sample_rate, settings.motulator_stop)
        blind_description(Path(folder), f"motulator simulation: {d['scenario']} start")
        state_filter(Path(folder), d.get("speed_filter"))

    return draws, make


SOURCES = {"own": own_source, "plant": plant_source, "motulator": motulator_source}


def with_only(source: str, d: dict, keep: str) -> dict:
    """Draw ``d`` of ``source`` with only its injected effect ``keep`` (same motor, scenario,
    size and form of that effect, noise seed): the data on which that effect's own base-model
    gap is measured (:func:`effect_alone_gaps`)."""
    d = copy.deepcopy(d)
    d["effects"] = [keep]
    if source == "own":
        d["size"] = {keep: d["size"][keep]}
        d["form"] = {k: v for k, v in d["form"].items() if k == keep}
        d["effect"] = keep
    elif source == "plant":
        d["spec"]["effects"] = [e for e in d["spec"]["effects"] if e["name"] == keep]
    else:
        d["options"] = {keep: d["options"][keep]}
    return d


def effect_alone_gaps(settings: BlindSettings, d: dict, make, work: Path) -> dict[str, dict]:
    """Each injected effect's own base-model gap in a two-effect set ``d``: the set made again with
    that effect alone (:func:`with_only`: same motor, scenario, size, form and noise seed), its
    truth moved away, and diagnosed with no effect chosen (``diagnosis.max_effects=0``); per
    effect ``{"gap": held-out RMS over noise, "no_gap": bool}`` (``no_gap``: within the noise
    band). Kept in ``work/alone.jsonl``; the data folders go once measured."""
    store = work / "alone.jsonl"
    known = {}
    if store.exists():
        for line in store.read_text().splitlines():
            r = json.loads(line)
            known[(r["index"], r["effect"])] = r
    out = {}
    for e in d["effects"]:
        if (d["index"], e) not in known:
            one = with_only(settings.source, d, e)
            folder = work / "alone" / f"set_{d['index']:03d}_{e}"
            if folder.exists():
                shutil.rmtree(folder)
            make(one, folder)
            (folder / "truth.yaml").unlink(missing_ok=True)
            c = diagnosis_config(settings, folder)
            with open_dict(c):
                c.diagnosis.max_effects = 0
            from benchmark.core.harness import run_diagnosis

            doc = run_diagnosis(c, work / "alone" / f"diagnosis_{d['index']:03d}_{e}")
            r = {"index": d["index"], "effect": e, "gap": float(doc["gap_before"]["heldout_rms_over_noise"]),
                 "no_gap": doc["status"] == "no_gap"}
            with open(store, "a") as fh:
                fh.write(json.dumps(r) + "\n")
            shutil.rmtree(folder, ignore_errors=True)
            known[(d["index"], e)] = r
        out[e] = {k: known[(d["index"], e)][k] for k in ("gap", "no_gap")}
    return out
