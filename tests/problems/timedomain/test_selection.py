"""The pair look-ahead's rule (benchmark/problems/timedomain/diagnosis/selection.py), on fits
whose held-out chi^2 are given: which pair enters, in which order, and when none may.

The end-to-end case is the README's bench record, where a load step and a tachometer gain error
mask each other once the two-mass coupling is in (the load step alone removes 3 % of the excess,
the gain error alone ranks below six others in the screening, together they remove 86 %); it
takes minutes and is run with the README's commands."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from benchmark.problems.timedomain.diagnosis.pipeline import DiagnosisSettings
from benchmark.problems.timedomain.diagnosis.selection import Selector


class _Effect(SimpleNamespace):
    def __init__(self, name, k=2):
        super().__init__(name=name, extra_names=tuple(f"p{j}" for j in range(k)))


def _fit(chi2, ssr_in, effects=()):
    return SimpleNamespace(chi2=chi2, ssr_in=ssr_in, names=[e.name for e in effects],
                           model=SimpleNamespace(effects=list(effects)), r_in=None, used=None)


class _Given(Selector):
    """A selector whose fits are looked up: ``held[frozenset(names)] = (chi2, ssr_in)``."""

    def __init__(self, held, settings=None):
        self.settings = settings or DiagnosisSettings()
        self.held = held
        self.fitted = []

    def fit_set(self, effects, starts_from, drop=None):
        names = frozenset(e.name for e in effects)
        self.fitted.append([e.name for e in effects])
        chi2, ssr = self.held[names]
        return _fit(chi2, ssr, effects)

    def prescreen(self, chosen, additions, cur, progress=None):
        keyed = [(self.held[frozenset([e.name for e in chosen] + [e.name for e in add])][0], add) for add in additions]
        keyed.sort(key=lambda p: p[0])
        return [a for _, a in keyed], [{"effect": "+".join(e.name for e in a), "heldout_chi2_fold_B": c,
                                        "heldout_chi2_base_fold_B": 0.0} for c, a in keyed]


LOAD, GAIN, SKEW = _Effect("load_torque", 4), _Effect("speed_sensor_gain", 2), _Effect("channel_delay", 1)
BAND = 1.1  # the noise band of the held-out RMS over noise


def _single_rows(sel, cur, n_eff):
    rows = []
    for e in (LOAD, GAIN, SKEW):
        chi2, ssr = sel.held[frozenset([e.name])]
        rows.append(sel.score(e.name, len(e.extra_names), _fit(chi2, ssr), cur, n_eff, BAND, 0.15))
    return rows


def test_two_effects_that_mask_each_other_enter_together_the_stronger_alone_first():
    held = {frozenset(): (1000.0, 1000e3), frozenset(["load_torque"]): (970.0, 970e3),
            frozenset(["speed_sensor_gain"]): (880.0, 880e3), frozenset(["channel_delay"]): (995.0, 995e3),
            frozenset(["load_torque", "speed_sensor_gain"]): (140.0, 140e3),
            frozenset(["load_torque", "channel_delay"]): (960.0, 960e3),
            frozenset(["speed_sensor_gain", "channel_delay"]): (870.0, 870e3)}
    sel = _Given(held)
    cur, n_eff = _fit(1000.0, 1000e3), 500.0
    rows = _single_rows(sel, cur, n_eff)
    assert not any(r["earns"] for r in rows)  # 3 %, 12 % and 0.5 % of the excess: under 15 % each
    rounds = []
    found = sel.pair_lookahead([], [LOAD, GAIN, SKEW], cur, BAND, n_eff, rows, rounds)
    assert found is not None
    pair, sf = found
    assert [e.name for e in pair] == ["speed_sensor_gain", "load_torque"]  # 12 % alone before 3 %
    assert sf.chi2 == 140.0
    rnd = rounds[0]
    assert rnd["pairs"] and rnd["chosen"] == "speed_sensor_gain+load_torque"
    best = next(r for r in rnd["candidates"] if r["effect"] == "speed_sensor_gain+load_torque")
    assert best["earns"] and abs(best["excess_reduction"] - 860.0 / 999.0) < 1e-12
    # the screening looked at all three pairs and fitted only the best two fully
    assert len(rnd["screening"]) == 3 and len(sel.fitted) == 2


def test_a_hitchhiker_does_not_ride_in_with_an_effect_that_nearly_earns_alone():
    """The pair removes 38 % of the excess, the better of its members alone 25 % (it missed the
    single rule on its criterion): the second adds 13 points, fewer than the 15 the rule asks."""
    held = {frozenset(["load_torque"]): (750.0, 1100e3), frozenset(["speed_sensor_gain"]): (990.0, 990e3),
            frozenset(["channel_delay"]): (995.0, 995e3),
            frozenset(["load_torque", "speed_sensor_gain"]): (620.0, 620e3),
            frozenset(["load_torque", "channel_delay"]): (700.0, 1050e3),
            frozenset(["speed_sensor_gain", "channel_delay"]): (985.0, 985e3)}
    sel = _Given(held)
    cur, n_eff = _fit(1000.0, 1000e3), 500.0
    rows = _single_rows(sel, cur, n_eff)
    assert not any(r["earns"] for r in rows)  # load_torque: 25 %, but its in-sample SSR rose
    rounds = []
    assert sel.pair_lookahead([], [LOAD, GAIN, SKEW], cur, BAND, n_eff, rows, rounds) is None
    shares = {r["effect"]: r["excess_reduction"] for r in rounds[0]["candidates"]}
    assert abs(shares["load_torque+speed_sensor_gain"] - 380.0 / 999.0) < 1e-12
    assert rounds[0]["chosen"] is None


def test_no_look_ahead_near_the_noise_or_without_room_or_when_turned_off():
    held = {frozenset(["load_torque", "speed_sensor_gain"]): (1.0, 1.0)}
    rows = [{"effect": "load_torque", "excess_reduction": 0.0}]
    near = _fit(1.3, 1.0)  # RMS 1.14: within twice the band of the noise, the verdict may call it explained
    assert _Given(held).pair_lookahead([], [LOAD, GAIN], near, BAND, 100.0, rows, []) is None
    far = _fit(50.0, 50.0)
    full = DiagnosisSettings(max_effects=2)
    assert _Given(held, full).pair_lookahead([SKEW], [LOAD, GAIN, SKEW], far, BAND, 100.0, rows, []) is None
    off = DiagnosisSettings(pair_keep=0)
    assert _Given(held, off).pair_lookahead([], [LOAD, GAIN], far, BAND, 100.0, rows, []) is None
    assert np.isfinite(far.chi2)


def test_a_coulomb_friction_far_above_a_motors_own_is_reported_as_a_constant_load():
    """A constant passive load torque has Coulomb friction's equation: the case-2 base absorbs it
    (independent plant, 7.5 kW motor, 57 % of rated torque: fitted fc 29.0 N m against the load's
    28.8). The document says so (``held_by_base``), and the blind score counts the load as named."""
    from benchmark.analysis.blind import score_row
    from benchmark.core.effects import EffectContext
    from benchmark.problems.timedomain.diagnosis.pipeline import DiagnosisSettings, estimated_rated_torque, held_by_base

    ctx = EffectContext(w_e=314.16, V1=326.6, I_peak=120.0, w_sync=157.08, dc_link_voltage=0.0, E_cu=1.0,
                        L_M=0.12, L_sigma=0.006, pole_pairs=2, T_acc=60.0)
    names, st = ["Rs", "Ls", "Le", "Rr", "J", "fv", "fc"], DiagnosisSettings()
    x = np.array([0.8, 0.127, 0.0064, 0.75, 0.027, 0.001, 29.0])
    held = held_by_base(names, x, ctx, st)
    assert [(h["effect"], h["form"]) for h in held] == [("load_torque", "constant")]
    # without a nameplate the scale is a third of the pull-out torque, 3 p V1^2 / (4 w_e (Rs + |Rs + j w_e Le|))
    pullout = 3 * 2 * 326.6**2 / (4 * 314.16 * (0.8 + np.hypot(0.8, 314.16 * 0.0064)))
    assert abs(pullout - 171.8) < 0.1
    assert abs(held[0]["share_of_scale"] - 29.0 / (pullout / 3)) < 1e-12
    # with a nameplate the rated torque is the scale (a slow ramped start makes T_acc small)
    from benchmark.problems.timedomain.diagnosis.pipeline import rated_torque

    rated = rated_torque({"rated_power": 7500.0, "speed": 1440.0})
    assert abs(rated - 49.736) < 1e-3
    x_small = x.copy()
    x_small[-1] = 0.015 * rated  # 1.5 % of rated: friction, though 1.2 % of a small T_acc would pass too
    assert held_by_base(names, x_small, ctx, st, rated) == []
    assert held_by_base(names, x, ctx, st, rated)[0]["scale"] == "rated torque"
    x[-1] = 0.02 * pullout / 3  # 2 % of the estimated rated torque: a motor's own friction, nothing to report
    assert held_by_base(names, x, ctx, st) == []
    # a slow inverter ramp (blind plant seed 17, set 3: a 7.5 kW 6-pole motor, 0.63 s ramp, rated
    # torque 61 N m): its own friction, 0.61 N m, was 5 % of T_acc (12.1 N m) and was reported as
    # a load; it is 1 % of the estimated rated torque (62.3 N m)
    slow = EffectContext(w_e=377.0, V1=179.6, I_peak=300.0, w_sync=125.7, dc_link_voltage=297.0, E_cu=1.0,
                         L_M=0.031, L_sigma=0.00185, pole_pairs=3, T_acc=12.06)
    fitz = np.array([0.2778, 0.03278, 0.001853, 0.1457, 0.0844, 0.0038, 0.6121])
    assert held_by_base(names, fitz, slow, st) == []
    assert abs(estimated_rated_torque(dict(zip(names, fitz, strict=True)), slow) - 62.33) < 0.01
    assert held_by_base(names[:-1], x[:-1], ctx, st) == []  # case-1 base: no fc in it
    # without a stop record the friction is loosely determined (independent plant seed 47, set 16:
    # a 7.5 kW six-step start with iron loss and heating, rated torque 49.87 N m, the motor's own
    # friction 0.40 N m): the final model's 2.704 +- 1.299 N m is 5.4 % of rated torque but not
    # two standard errors above 4 %: no load is reported
    x16, se16 = x.copy(), np.full(len(x), 1e-3)
    x16[-1], se16[-1] = 2.704, 1.299
    assert held_by_base(names, x16, ctx, st, 49.87, se16) == []
    assert held_by_base(names, x16, ctx, st, 49.87) != []  # the point value alone is above
    se16[-1] = np.nan  # not determined at all: as uncertain as it is large
    assert held_by_base(names, x16, ctx, st, 49.87, se16) == []
    # a held load without a stop record is well determined (plant seed 40, set 21: 2.695 +- 0.001 N m)
    x21 = np.array([0.8, 0.127, 0.0064, 0.75, 0.027, 0.001, 2.695])
    held21 = held_by_base(names, x21, ctx, st, 2.627, np.r_[np.full(6, 1e-3), 0.001])
    assert [(h["effect"], h["standard_error_Nm"]) for h in held21] == [("load_torque", 0.001)]
    doc = {"status": "no_gap", "verdict": "none", "effects": [], "explained_share": 0.0,
           "gap_before": {"heldout_rms_over_noise": 1.03}, "gap_after": {"heldout_rms_over_noise": 1.03},
           "held_by_base": held}
    assert score_row(2, ["load_torque"], doc)["predicted"] == "load_torque"
    assert score_row(3, [], doc)["predicted"] == "load_torque"  # on an effect-free set it is a miss
    # beside a gap left unexplained it is no diagnosis of a load (blind scoring since 322a9b8)
    doc |= {"status": "unexplained", "verdict": "unexplained", "gap_before": {"heldout_rms_over_noise": 1.13},
            "gap_after": {"heldout_rms_over_noise": 1.13}}
    assert score_row(4, ["load_torque"], doc)["predicted"] == "unexplained"


TWO = _Effect("two_mass", 4)
N = 20000.0  # residuals per fold pair: in-sample SSR = chi^2 N (the criterion's scale)


def _chi(chi2, effects=()):
    return _fit(chi2, chi2 * N, effects)


def test_a_rider_that_soaks_up_a_minority_of_what_is_left_is_pruned_a_real_second_effect_stays():
    """Measured held-out chi^2 of two blind sets. Independent plant, a coupling with free play
    (seed 12, set 17): base + two_mass + load_torque 2.408, without the load torque 2.535, without
    the coupling 26.31; the load torque removes 8 % of the 1.535 left without it: dropped.
    Motulator (seed 2, set 6), a coupling and a load torque, both injected: 2.66 with both, 8.91
    without the load torque, 76.5 without the coupling: both stay."""
    band = 1.071
    rider = _Given({frozenset(["two_mass", "load_torque"]): (2.408, 2.408 * N),
                    frozenset(["two_mass"]): (2.535, 2.535 * N), frozenset(["load_torque"]): (26.31, 26.31 * N)})
    final = _chi(2.408, [TWO, LOAD])
    kept, withouts, pruned = rider.prune(final, _chi(26.31), band)
    assert pruned == ["load_torque"] and kept.names == ["two_mass"]
    # the band part alone (the rule before) keeps it: a rise of 0.127 against 0.5 (1.071^2 - 1) = 0.074
    assert 2.535 - 2.408 >= 0.5 * (band**2 - 1.0)
    loose = _Given(rider.held, DiagnosisSettings(min_final_share=0.0))
    assert loose.prune(final, _chi(26.31), band)[2] == []

    # far from the noise (final held-out RMS over twice the noise) only 5 % is asked: the README
    # bench record on a path that ended at chi^2 1711 (41 times the noise) had a real probe
    # saturation removing 43 % of the 2996 left without it
    far = _Given({frozenset(["two_mass", "current_sensor_saturation"]): (1711.0, 1711.0 * N),
                  frozenset(["two_mass"]): (2997.0, 2997.0 * N),
                  frozenset(["current_sensor_saturation"]): (17000.0, 17000.0 * N)})
    probes = _Effect("current_sensor_saturation", 2)
    assert far.prune(_chi(1711.0, [TWO, probes]), _chi(17831.0), 1.101)[2] == []
    assert (2997.0 - 1711.0) / 2996.0 < 0.6
    tight = _Given(far.held, DiagnosisSettings(final_share_gap=50.0))
    assert tight.prune(_chi(1711.0, [TWO, probes]), _chi(17831.0), 1.101)[2] == ["current_sensor_saturation"]

    real = _Given({frozenset(["two_mass", "load_torque"]): (2.66, 2.66 * N),
                   frozenset(["two_mass"]): (8.91, 8.91 * N), frozenset(["load_torque"]): (76.5, 76.5 * N)})
    final = _chi(2.66, [TWO, LOAD])
    kept, withouts, pruned = real.prune(final, _chi(80.0), 1.08)
    assert pruned == [] and kept is final and [w.chi2 for w in withouts] == [76.5, 8.91]  # without each in turn


def test_far_from_the_noise_an_effect_that_removes_nothing_beside_the_others_is_pruned():
    """The README bench record, on a path where iron loss won its round in a near tie with the
    tachometer (17.1 % against 16.5 % of the excess): the final four-effect model is at chi^2 777
    (28 times the noise), and without the iron loss at 791, a rise of 2 % of what is left; the
    other three raise it by 3100-9600. Far from the noise only ``min_far_share`` (5 %) is asked,
    and the iron loss is dropped; with no floor (the rule before) it stays."""
    loss = _Effect("iron_loss", 2)
    held = {frozenset(["two_mass", "iron_loss", "load_torque", "speed_sensor_gain"]): (776.7, 776.7 * N),
            frozenset(["iron_loss", "load_torque", "speed_sensor_gain"]): (10327.0, 10327.0 * N),
            frozenset(["two_mass", "load_torque", "speed_sensor_gain"]): (791.2, 791.2 * N),
            frozenset(["two_mass", "iron_loss", "speed_sensor_gain"]): (8369.0, 8369.0 * N),
            frozenset(["two_mass", "iron_loss", "load_torque"]): (3902.0, 3902.0 * N),
            frozenset(["load_torque", "speed_sensor_gain"]): (10400.0, 10400.0 * N),
            frozenset(["two_mass", "speed_sensor_gain"]): (8500.0, 8500.0 * N),
            frozenset(["two_mass", "load_torque"]): (3950.0, 3950.0 * N)}
    final = _chi(776.7, [TWO, loss, LOAD, GAIN])
    kept, withouts, pruned = _Given(held).prune(final, _chi(19251.0), 1.101)
    assert pruned == ["iron_loss"] and kept.names == ["two_mass", "load_torque", "speed_sensor_gain"]
    assert [w.chi2 for w in withouts] == [10400.0, 8500.0, 3950.0]
    assert _Given(held, DiagnosisSettings(min_far_share=0.0)).prune(final, _chi(19251.0), 1.101)[2] == []


def test_a_suspect_the_base_holds_is_fitted_fully_whatever_its_screening(monkeypatch):
    """A load torque the base's Coulomb friction holds (``held_by_base``) screens last: its cheap
    fit starts where the friction already carries it (motulator blind seed 64, sets 14 and 17: a
    load step on through the coast-down, screened last of eleven, never fitted fully, verdict
    ``unexplained``). As a suspect it is fitted fully whatever the screening scored."""
    from benchmark.problems.timedomain.diagnosis import selection

    monkeypatch.setattr(selection, "effective_samples", lambda *a: 500.0)
    monkeypatch.setattr(_Given, "data", None, raising=False)
    screened = {"load_torque": 1005.0, "speed_sensor_gain": 900.0, "channel_delay": 990.0}
    full = {frozenset(): (1000.0, 1000e3), frozenset(["load_torque"]): (100.0, 100e3),
            frozenset(["speed_sensor_gain"]): (800.0, 800e3), frozenset(["channel_delay"]): (980.0, 980e3)}

    class _Screened(_Given):
        def prescreen(self, chosen, additions, cur, progress=None):
            keyed = sorted(((screened[a[0].name], a) for a in additions), key=lambda p: p[0])
            return [a for _, a in keyed], [{"effect": a[0].name, "heldout_chi2_fold_B": c} for c, a in keyed]

    settings = DiagnosisSettings(screen_keep=1, max_effects=1)
    base = _fit(1000.0, 1000e3)
    plain = _Screened(full, settings)
    cur, rounds = plain.forward_selection([LOAD, GAIN, SKEW], base, BAND)
    assert cur.names == ["speed_sensor_gain"] and rounds[0]["kept"] == ["speed_sensor_gain"]
    assert ["load_torque"] not in plain.fitted  # screened out: the load is never fitted
    held = _Screened(full, settings)
    cur, rounds = held.forward_selection([LOAD, GAIN, SKEW], base, BAND, suspects=(LOAD,))
    assert rounds[0]["kept"] == ["speed_sensor_gain", "load_torque"]
    assert cur.names == ["load_torque"] and cur.chi2 == 100.0
    assert rounds[1]["chosen"] == "load_torque" and abs(rounds[1]["candidates"][0]["excess_reduction"]
                                                        - 900.0 / 999.0) < 1e-12
