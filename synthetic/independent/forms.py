"""The split of every effect's forms into development and held-out forms, in one place.

*Development* forms are the ones the project's diagnosis was developed and tuned on: every
form this plant had before the held-out forms were written. *Held-out* forms are second
physical forms written from the physics afterwards (``docs/effect_forms.md``): they exist to
score the diagnosis on data it was not developed on. A rule, threshold or prior of the
diagnosis may be calibrated on development forms only; held-out forms are for the final
scoring, and their scores are not to be looked at while the diagnosis is being changed.

Form sets (the ``forms`` key of ``python -m benchmark.blind`` and of ``python -m
synthetic.independent``): ``development`` (the default: the plant's behaviour before the
split, draw for draw), ``heldout``, ``all`` and ``variants`` (:data:`VARIANTS`: the forms that
made the catalogue extend its own, for the calibration of the rule; development forms for the
other effects).

A held-out form may be limited to some scenarios (:data:`SCENARIOS`): a current transformer
cannot measure the near-DC currents of a V/f ramp from standstill, so it is drawn only for
the fixed-frequency starts (``dol``, ``six_step``).
"""

from __future__ import annotations

FORM_SETS = ("development", "heldout", "all", "variants")

#: Forms the diagnosis was developed on (the draw order of :meth:`Effect.draw` is this order).
DEVELOPMENT = {
    "coulomb_friction": ("coulomb",),
    "double_cage": ("double_cage", "deep_bar"),
    "main_saturation": ("frohlich", "arctan", "table"),
    "iron_loss": ("eddy_winding", "shunt"),
    "leakage_saturation": ("lorentzian", "frohlich"),
    "load_torque": ("constant", "quadratic", "step"),
    "two_mass": ("spring", "backlash"),
    "temperature_drift": ("one_body", "two_body"),
    "inverter_drop": ("igbt", "mosfet"),
    "current_sensor_saturation": ("tanh", "knee", "clip"),
    "speed_sensor_gain": ("gain", "gain_ripple"),
    "sensor_offset": ("both", "current", "voltage"),
    "channel_delay": ("current_lag", "voltage_lag"),
}

#: Second physical forms, for scoring only (see the module docstring).
HELDOUT = {
    "coulomb_friction": ("bearing",),
    "double_cage": ("tapered_bar",),
    "main_saturation": ("steel_gap", "langevin"),
    "iron_loss": ("steinmetz",),
    "leakage_saturation": ("closed_slot_bridge",),
    "load_torque": ("battery_charger",),
    "two_mass": ("slip_clutch",),
    "temperature_drift": ("three_body",),
    "inverter_drop": ("mosfet_capacitive",),
    "current_sensor_saturation": ("hall_core", "current_transformer"),
    "speed_sensor_gain": ("encoder_window",),
    "sensor_offset": ("thermal_drift",),
    "channel_delay": ("anti_alias",),
}

#: Held-out forms the diagnosis has since been developed on (a blind draw showed what the
#: catalogue's form left of them and the catalogue's form was extended to them): drawable by
#: name and in ``all``, in no random pool (development draws stay draw for draw; held-out
#: draws take the second forms written in their place).
RETIRED = {
    "speed_sensor_gain": ("tacho_filter",),  # a fact in meta.yaml now (speed_filter); tach_lag before
    "two_mass": ("elastomer",),  # the catalogue's hardening coupling, tm_hardening
    "channel_delay": ("mux_skew",),  # a card's sequence in meta.yaml (channel_skew mapping), per-phase skews
    # the catalogue's DC machine's armature lag (the speed share's state); the brake's law (r_crit)
    "load_torque": ("dc_generator", "eddy_brake"),
}

#: Forms the catalogue's first form of an effect cannot fit (:attr:`benchmark.core.effects.Effect.FIRST_FORM`):
#: development forms and retired held-out forms that made it extend its form. Diagnosed with the
#: injected effect reduced to its first form, they are form variants for the calibration of the
#: rule (``python -m benchmark.studies.calibration sources=plant_variants``): a form the catalogue
#: does not have, as a real machine's may be, none of them a held-out form kept for the scoring.
VARIANTS = {
    "speed_sensor_gain": ("gain_ripple", "tacho_filter"),
    "two_mass": ("backlash", "elastomer"),
    "double_cage": ("deep_bar",),
    "temperature_drift": ("two_body",),
    "load_torque": ("dc_generator", "eddy_brake"),
}

#: The motulator source (``synthetic/motulator_source.py``) injects three effects; development
#: forms are motulator's own models, held-out forms are in ``synthetic/motulator_effects.py``.
#: It has no form (and injects nothing) for the other effects.
MOTULATOR_DEVELOPMENT = {
    "main_saturation": ("power_law",),
    "two_mass": ("spring",),
    "load_torque": ("step", "constant", "quadratic"),
}
MOTULATOR_HELDOUT = {
    "main_saturation": ("steel_gap",),
    "two_mass": ("slip_clutch",),
    "load_torque": ("battery_charger",),
}
#: motulator's held-out forms the diagnosis has since been developed on (as :data:`RETIRED`).
MOTULATOR_RETIRED = {
    "two_mass": ("elastomer",),  # the catalogue's hardening coupling, tm_hardening
    "load_torque": ("dc_generator", "eddy_brake"),  # the DC machine's armature lag; the brake's law
}

#: ``load_torque`` forms switched on at the start or later in the record, with equal odds (both sources).
SWITCHED_LOADS = ("dc_generator", "eddy_brake", "battery_charger")

#: Held-out forms drawn only for some scenario kinds (all others: every scenario).
SCENARIOS = {"current_transformer": ("dol", "six_step")}


def motulator_forms_of(name: str, which: str = "development") -> tuple[str, ...]:
    """The motulator source's forms of effect ``name`` in form set ``which``."""
    dev, held = MOTULATOR_DEVELOPMENT[name], MOTULATOR_HELDOUT[name]
    return {"development": dev, "heldout": held, "all": dev + MOTULATOR_RETIRED.get(name, ()) + held,
            "variants": MOTULATOR_RETIRED.get(name, dev)}[check_form_set(which)]


def check_form_set(which: str) -> str:
    if which not in FORM_SETS:
        raise ValueError(f"forms must be one of {FORM_SETS}, got {which!r}")
    return which


def all_forms(name: str) -> tuple[str, ...]:
    """Every form of effect ``name``: development first, then retired (:data:`RETIRED`), then
    held-out."""
    return DEVELOPMENT[name] + RETIRED.get(name, ()) + HELDOUT[name]


def forms_of(name: str, which: str = "development", scenario: str | None = None) -> tuple[str, ...]:
    """The forms of effect ``name`` in form set ``which`` that may occur in a ``scenario``
    kind (None: any)."""
    pool = {"development": DEVELOPMENT[name], "heldout": HELDOUT[name], "all": all_forms(name),
            "variants": VARIANTS.get(name, DEVELOPMENT[name])}[check_form_set(which)]
    return tuple(f for f in pool if scenario is None or scenario in SCENARIOS.get(f, (scenario,)))


def form_set_of(name: str, form: str) -> str:
    """``development`` or ``heldout``: which set form ``form`` of effect ``name`` is in (a
    retired form is a development form)."""
    return "development" if form in DEVELOPMENT[name] + RETIRED.get(name, ()) else "heldout"
