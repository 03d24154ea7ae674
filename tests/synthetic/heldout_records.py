"""Records of the independent plant with one held-out (second physical) form each, at mid-realistic
sizes, for the tests of those forms (the paper's 1-kW motor, 0.4 s at 10 kHz, 8 internal steps per
sample, noise-free unless asked)."""


import math

from synthetic.independent import get_motor, make_dataset, make_spec
from synthetic.independent.dataset import default_noise
from synthetic.independent.forms import HELDOUT, RETIRED

MOTOR = "paper_1kw"
FS = 10000.0
SLOW = 5000.0  # for records that only need their steady end
MO = get_motor(MOTOR)
IN = MO.rated_current_peak
NOISE = default_noise(MO)

#: Mid-realistic sizes (and typical other parameters) of every held-out form.
MID = {
    "bearing": {"size": 0.009 * MO.rated_torque, "breakaway_ratio": 1.6, "stribeck_speed": 2.5,
                "palmgren_share": 1.25},
    "tapered_bar": {"size": 1.4, "loops": 6, "taper": 0.6},
    "steel_gap": {"size": 0.19, "iron_ratio": 180.0},
    "langevin": {"size": 0.19},
    "steinmetz": {"size": 0.04, "hysteresis_share": 0.55, "exponent": 1.9, "time_constant": 6e-4},
    "closed_slot_bridge": {"size": 0.6, "knee_fraction": 0.3},
    "dc_generator": {"size": 0.55, "step_fraction": 0.5, "armature_time_constant": 6e-3, "emf": 175.0,
                     "brush_drop": 1.5},
    "eddy_brake": {"size": 0.55, "step_fraction": 0.5, "critical_speed_ratio": 0.5, "field_time_constant": 0.05},
    "battery_charger": {"size": 0.55, "step_fraction": 0.0, "cut_in_ratio": 0.55},
    "elastomer": {"size": 77.0, "inertia_ratio": 1.0, "damping_ratio": 0.06, "hardening": 2.25},
    "slip_clutch": {"size": 77.0, "inertia_ratio": 1.0, "damping_ratio": 0.06, "slip_share": 1.0},
    "three_body": {"size": 15.0, "rotor_factor": 1.5, "time_constant": 2100.0, "core_time_constant": 4.0,
                   "core_ratio": 10.0},
    "mosfet_capacitive": {"size": 2.0, "r": 2.0 / IN, "dead_time": 3e-6, "transition_fraction": 0.09},
    "hall_core": {"size": 2.25, "exponent": 8.5, "coercive": 0.0065},
    "current_transformer": {"size": 3.0, "exponent": 12.0, "secondary_time_constant": 1.75, "remanence": [0.3, -0.3]},
    "tacho_filter": {"size": 0.03, "offset": 0.0, "time_constant": 3e-3},
    "encoder_window": {"size": 0.03, "offset": 0.0, "gate_time": 3e-3},
    "thermal_drift": {"current_offsets": [0.175, -0.175], "drift": [0.125, -0.125], "time_constant": 1.65},
    "anti_alias": {"size": 1.25},
    "mux_skew": {"size": 0.2, "order": ["i_r", "v_r", "i_s", "v_s", "v_t"]},
}
EFFECT_OF = {f: name for table in (HELDOUT, RETIRED) for name, forms in table.items() for f in forms}
SCENARIO_OF = {"mosfet_capacitive": "pwm"}
_CACHE: dict = {}


def record(effects=(), scenario="dol", forms=None, sizes=None, duration=0.4, stop=None, noise=None, seed=5,
            sample_rate=FS, **kw):
    spec = make_spec(MOTOR, scenario, list(effects), seed=seed, duration=duration, ideal_supply=True,
                     noise={} if noise is None else noise, oversampling=8, sample_rate=sample_rate, forms=forms,
                     stop=stop, **kw)
    for eff in spec["effects"]:
        eff.update((sizes or {}).get(eff["name"], {}))
    return make_dataset(spec)


def held(form: str):
    """The record of held-out form ``form`` at its mid size (cached), with a 2 s stop and torque."""
    if form not in _CACHE:
        name = EFFECT_OF[form]
        _CACHE[form] = record([name], SCENARIO_OF.get(form, "dol"), {name: form}, {name: MID[form]}, stop=2.0,
                               has_torque=True)
    return _CACHE[form]


def base(scenario="dol"):
    key = ("base", scenario)
    if key not in _CACHE:
        _CACHE[key] = record(scenario=scenario, stop=2.0, has_torque=True)
    return _CACHE[key]


def phase_ab(rec, prefix):
    r, s = rec[f"{prefix}_r"], rec[f"{prefix}_s"]
    t = rec[f"{prefix}_t"] if f"{prefix}_t" in rec else -r - s
    return (2 / 3) * (r - 0.5 * (s + t)), (s - t) / math.sqrt(3)
