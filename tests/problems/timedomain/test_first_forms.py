"""Form variants for the rule's calibration: each effect's first form (the catalogue's form before
it was extended, :attr:`benchmark.core.effects.Effect.FIRST_FORM`) and the plant forms it cannot
fit (:data:`synthetic.independent.forms.VARIANTS`), none of them a form kept for the scoring."""

from __future__ import annotations

import numpy as np

from benchmark.core.effects import EffectContext, load_effects
from synthetic.independent.forms import DEVELOPMENT, HELDOUT, RETIRED, VARIANTS, forms_of

CTX = EffectContext(w_e=314.16, V1=325.0, I_peak=40.0, w_sync=157.08, dc_link_voltage=540.0, E_cu=500.0,
                    L_M=0.2, L_sigma=0.01, sample_time=1e-4, duration=1.0, pole_pairs=2, J=0.02, T_acc=15.0,
                    T_rated=10.0, I_rated=8.0, I2t=200.0)


def test_a_first_form_holds_its_extras_and_leaves_the_others_free():
    effects = load_effects("timedomain")
    reduced = [name for name, eff in effects.items() if eff.FIRST_FORM]
    assert sorted(reduced) == sorted(VARIANTS)  # every variant form's effect has a first form, and only those
    for name in reduced:
        eff = effects[name]
        lo, hi = (np.asarray(b, float) for b in eff.extra_bounds(CTX))
        assert np.array_equal(eff.fit_bounds(CTX)[0], lo) and np.array_equal(eff.fit_bounds(CTX)[1], hi)  # not held
        flo, fhi = eff.reduce_to_first_form().fit_bounds(CTX)
        for k, extra in enumerate(eff.extra_names):
            if extra in eff.FIRST_FORM:
                assert flo[k] == fhi[k] == np.clip(eff.FIRST_FORM[extra], lo[k], hi[k]), (name, extra)
            else:
                assert (flo[k], fhi[k]) == (lo[k], hi[k]), (name, extra)


def test_the_variants_are_development_or_retired_forms_never_held_out_ones():
    for name, forms in VARIANTS.items():
        assert set(forms) <= set(DEVELOPMENT[name]) | set(RETIRED.get(name, ())), name
        assert not set(forms) & set(HELDOUT[name]), name
        assert forms_of(name, "variants") == forms
    assert forms_of("iron_loss", "variants") == DEVELOPMENT["iron_loss"]  # the others: development forms
