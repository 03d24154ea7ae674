"""Main and leakage saturation at once, on the independent plant.

The augmentation of main saturation places the magnetising curve at the node of a T circuit
(the extended model's T mode), and that mode had no saturating leakage: a model with both
effects lost the leakage's saturation as soon as the main one moved off zero, so the pair fitted
worse than the leakage alone (own blind seed 43, set 17: held-out chi^2 6.19 against 1.29; the
verdict named the leakage only). With a saturating leakage the row now stays in the
inverse-Gamma mode, the magnetising curve at the rotor flux node."""

from __future__ import annotations

import tempfile

import numpy as np

from benchmark.core.effects import load_effects
from benchmark.problems.timedomain.data import load_startup_dataset
from benchmark.problems.timedomain.extended import IDX, base_rows, simulate_extended_batch
from tests.problems.timedomain.test_effects_independent_plant import DURATION, RATE, _excess, _floor, _JointFit

EFFECTS = load_effects("timedomain")


class _Both:
    """Two augmentations side by side: their extras concatenated, applied in turn."""

    def __init__(self, first, second):
        self.parts = (first, second)

    def _split(self, ctx):
        n = len(self.parts[0].extra_bounds(ctx)[0])
        return slice(0, n), slice(n, None)

    def extra_bounds(self, ctx):
        b = [e.extra_bounds(ctx) for e in self.parts]
        return np.concatenate([b[0][0], b[1][0]]), np.concatenate([b[0][1], b[1][1]])

    def extra_starts(self, ctx):
        return [np.concatenate([a, b]) for a in self.parts[0].extra_starts(ctx)
                for b in self.parts[1].extra_starts(ctx)[:2]]

    def augment(self, rows, extras, ctx):
        for e, s in zip(self.parts, self._split(ctx), strict=True):
            rows = e.augment(rows, extras[:, s], ctx)
        return rows

    def measure(self, out, extras, ctx):
        for e, s in zip(self.parts, self._split(ctx), strict=True):
            out = e.measure(out, extras[:, s], ctx)
        return out


def _plant(clean: bool):
    from synthetic.independent import make_dataset, make_spec, write_dataset

    spec = make_spec("paper_1kw", "dol", ["main_saturation", "leakage_saturation"], seed=3, duration=DURATION,
                     sample_rate=RATE, forms={"main_saturation": "frohlich", "leakage_saturation": "frohlich"},
                     ideal_supply=True, noise={"current_white": 0.0} if clean else None)
    for e in spec["effects"]:
        if e["name"] == "main_saturation":
            e["size"] = 0.28
    made = make_dataset(spec)
    made.meta["conditioning"] = False
    with tempfile.TemporaryDirectory() as d:
        write_dataset(made, d)
        return load_startup_dataset(d), made.truth


def test_a_saturating_leakage_keeps_the_inverse_gamma_node():
    rows = base_rows(np.array([[3.0, 0.3, 0.03, 2.0, 0.005, 1e-4, 0.05]]), 2)
    rows[:, IDX["ms_k"]], rows[:, IDX["ms_exp"]], rows[:, IDX["ms_psi"]] = 0.3, 6.0, 0.6
    rows[:, IDX["ls_k"]], rows[:, IDX["ls_exp"]], rows[:, IDX["ls_psi"]] = 0.3, 2.0, 0.2
    t = np.arange(800) / 4000.0
    v = (np.ascontiguousarray(325 * np.cos(314.16 * t)), np.ascontiguousarray(325 * np.sin(314.16 * t)))
    node = rows.copy()
    node[:, IDX["t_split"]] = 1.0
    flat = rows.copy()
    flat[:, IDX["ls_k"]] = 0.0
    flat_node = node.copy()
    flat_node[:, IDX["ls_k"]] = 0.0
    out = [simulate_extended_batch(np.ascontiguousarray(r), *v, True, 1 / 4000.0, 1)
           for r in (rows, node, flat, flat_node)]
    np.testing.assert_array_equal(out[0], out[1])  # the split is ignored while the leakage saturates
    assert np.max(np.abs(out[0] - out[2])) > 1.0  # and the leakage's saturation is there
    assert np.max(np.abs(out[2] - out[3])) > 0.1  # without it, T mode as before


def test_both_saturations_fit_together():
    """Measured: mean squares (noise units) base 8.67, leakage alone 5.95, main alone 5.91, both
    2.30 (5.91 before: the pair was the main saturation alone), the plant's floor without
    effects ~1; each fit to 200 evaluations (at 40, a Zen 5 machine's rounding left the pair at
    27.1, above the base: a fit cut short). The pair removes about 60 % of the excess, not all:
    the plant saturates its magnetising branch between the two leakages, and beside a saturating
    leakage the augmentation's curve sits at the rotor flux node (a third of such a gap is left,
    see MainSaturation)."""
    noisy, truth = _plant(False)
    clean, _ = _plant(True)
    floor = _floor("paper_1kw", "dol", 3)
    fit = _JointFit(noisy, clean, truth)
    _, base = fit.fit(None)
    _, leak = fit.fit(EFFECTS["leakage_saturation"], max_nfev=200)
    _, main = fit.fit(EFFECTS["main_saturation"], max_nfev=200)
    _, both = fit.fit(_Both(EFFECTS["leakage_saturation"], EFFECTS["main_saturation"]), max_nfev=200)
    removed = 1.0 - _excess(both["noisy"], floor["noisy"]) / _excess(base["noisy"], floor["noisy"])
    print({k: round(v["noisy"], 3) for k, v in (("floor", floor), ("base", base), ("leak", leak), ("main", main),
                                                 ("both", both))}, "removed", round(removed, 3))
    assert base["noisy"] > 3.0  # both effects leave a clear gap
    assert both["noisy"] < 0.5 * min(leak["noisy"], main["noisy"])  # the pair beats either alone
    assert removed > 0.5
