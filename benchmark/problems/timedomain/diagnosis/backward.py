"""The backward check of the selection (:mod:`.selection`): every chosen effect must earn its place
beside the others (each drop-one model refitted from several starts, :meth:`BackwardCheck.backward`),
its size on all data must reach a tenth of its smallest realistic size, and where the record
measures the effect itself (an offset, on the steady tail) the fit must agree with that
measurement (:meth:`BackwardCheck.refused`); an effect that states its size or is measured
directly is checked already on entry (:meth:`BackwardCheck.refused_on_entry`)."""

from __future__ import annotations

import numpy as np

from benchmark.problems.timedomain.diagnosis.set_fit import SetFit

#: An effect whose size on all data is below this share of the smallest realistic size
#: (:attr:`Effect.realistic`) is not named: nothing a real machine or instrument has (a
#: tachometer's 0.03 % gain and offset, fitted beside a DC generator's load on motulator blind
#: seed 399 set 18, where it took 36 % of what the load's form left in one fold; an iron loss of
#: 0.033 % of the magnetising conductance, R_fe/X_M = 3000 where real cores have 20-100, fitted
#: beside an eddy-current brake's load on held-out plant seed 430 set 11 with a tachometer, the
#: pair taking 41 % and 37 % of what the load's form left).
NEGLIGIBLE_SHARE = 0.1


class BackwardCheck:
    """The backward part of :class:`.selection.Selector` (it provides ``ctx``, ``rule``,
    :meth:`fits` and :meth:`with_full_fit`)."""

    def refused(self, sf: SetFit, full_x: np.ndarray) -> dict[str, str]:
        """``sf``'s effects the data cannot support whatever share they take, each with why: its
        size on all data (``full_x``, :meth:`Effect.realistic_share`) below :data:`NEGLIGIBLE_SHARE` of
        the smallest realistic one, or its parameters fitted on all data excluded by the record's
        own direct measurement of them (:meth:`Effect.contradicted`: an offset the steady tail measures)."""
        model, out, se = sf.model, {}, None
        for j, eff in enumerate(model.effects):
            x = full_x[model.slices[j]]
            share = eff.realistic_share(x, self.ctx)
            if share is not None and share < NEGLIGIBLE_SHARE:
                out[eff.name] = "fitted on all data its size is negligible (below a tenth of the smallest realistic)"
            elif eff.measured_directly(self.ctx):
                se = model.standard_errors(full_x) if se is None else se
                why = eff.contradicted(x, se[model.slices[j]], self.ctx)
                if why:
                    out[eff.name] = f"fitted on all data {why}"
        return out

    def refused_on_entry(self, sf: SetFit, names) -> tuple[str, str] | None:
        """The first of ``names``, about to enter with ``sf``, that is refused on all data, with
        why (:meth:`refused` of ``sf`` fitted on all data once, as the backward check would find
        it), or None: checked on entry for effects that state their fitted size or are measured
        directly, so that no rounds are fitted beside it."""
        def checked(name):
            j = sf.model.effect_names.index(name)
            eff = sf.model.effects[j]
            return (eff.realistic_share(sf.xs["A"][sf.model.slices[j]], self.ctx) is not None
                    or eff.measured_directly(self.ctx))

        names = [n for n in names if checked(n)]
        if not names:
            return None
        full, x = self.with_full_fit(sf)
        why = self.refused(full, x)
        return next(((n, why[n]) for n in names if n in why), None)

    def backward(self, cur: SetFit, base_fit: SetFit, band: float, progress=None, full_x=None):
        """The backward check (module docstring): an effect that does not earn its place against
        the model without it, or that its fit on all data (``full_x``, the fit of ``cur``)
        refuses (:meth:`refused`), is dropped. Returns (the set kept, each kept effect's
        drop-one fit by name, names dropped in turn)."""
        pruned = []
        unsupported = list(self.refused(cur, full_x)) if full_x is not None else []
        while cur.names:
            fits = self.fits([([x for x in cur.effects if x is not e], [(cur, [cur]), (base_fit, [cur])], True)
                              for e in cur.effects], progress)
            withouts = {e.name: w for e, w in zip(cur.effects, fits, strict=True)}
            failing = [n for n, w in withouts.items() if not self.rule.earns_fit(w, cur, band) or n in unsupported]
            if not failing:
                return cur, withouts, pruned
            least = min(failing, key=lambda n: withouts[n].chi2)  # the model does best without it
            pruned.append(least)
            cur, unsupported = withouts[least], [n for n in unsupported if n != least]
        return cur, {}, pruned
