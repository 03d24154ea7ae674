"""Choosing the effects (step 6 of :mod:`.pipeline`): fold fits of effect sets, the forward
selection with its pair step, and the backward check, all decided by :class:`.rule.Rule`.

**Fits.** A set of effects is fitted on each fold (base parameters and the set's extras) from
several starts: the set it grew from or shrank from (its fitted parameters, the new effect's own
starting values, the starts that move part of the base into it, an instant chosen on a grid),
and for a drop-one model also the base identification's point with the other effects' fitted
extras (not only parameters co-adapted to the effect that was dropped). Every start is fitted
briefly (``DiagnosisSettings.screen_iterations``), the one that ends lowest on the fold's own
samples on to convergence (``max_iterations`` is a safety cap). A fold that cannot place an
instant (an effect's grid parameter) takes the other fold's (:meth:`Selector.agreed`). Then each fold
is refitted from the other fold's point where that point fits it better
(:meth:`Selector.cross_start`: both folds minimise the same model's residuals, and a fold left
in a worse basin would charge its misfit to the model).

Fits are kept by set (:attr:`Selector.memo`): a set reached again starts from its earlier fit
too and keeps the better, so that a set's score does not hang on the path that reached it. A set
that enters is cross-started also from its fit on all data (:meth:`Selector.with_full_fit`) before
the next round is fitted beside it: fold fits left in a worse basin would have the next round
search for what that basin leaves (the perf study's motulator battery charger: the load's fold
fits at 46.4 held out, from all data 1.02, within the band).

**Decisions** (:mod:`.rule`): forward, every remaining candidate is first screened beside the
current set by a linearised score test (:meth:`Selector.screen_singles`, from the starts its full
fit would take); the one screened best, every one the screening says may earn its place and
every one it could not assess (screened no lower than the current set, or seen in one shape
only: :meth:`Screening.seen_in_one_shape`) are fitted fully, and
the lowest held-out chi^2 among those enters when it earns its place
(:meth:`Selector.round_fits`; a linear step under-rates an effect far from linear at its start, a
leakage inductance that falls with current, an inverter's drop; one it places below the current
set but under-rates is not fitted where another earns: there the screening decides which
enters). Where none of them earns, every candidate is fitted fully; when none earns then, a
pair enters when each of its two effects earns its place beside the other. Pairs are screened
first by linearised score tests (:mod:`.score_tests`: one effect added to the other's single fit
on fold A, a Gauss-Newton step scored on fold B); as for the singles, the best screened and every
one the screening says both may earn are fitted fully, best screened first. Backward (after
every entry that leaves two effects or more, and when none enters), every
chosen effect must earn its place beside the others (each drop-one model refitted from several
starts), and its size on all data must reach a
tenth of its smallest realistic size, and where the record measures the effect itself (an
offset, on the steady tail) the fit must agree with that measurement (:meth:`Selector.refused`, in :mod:`.backward`);
the least needed effect that does not is dropped (``pruned``) and the check repeats; a dropped
effect leaves the candidates and the forward selection resumes. An effect that states its size
or is measured directly is checked already on entry (:meth:`Selector.refused_on_entry`), alone or
as a member of a pair: refused on all data, it leaves the candidates before any round is fitted
beside it.
"""

from __future__ import annotations

import itertools

import numpy as np

from benchmark.problems.timedomain.diagnosis.backward import NEGLIGIBLE_SHARE, BackwardCheck
from benchmark.problems.timedomain.diagnosis.engine import side_by_side
from benchmark.problems.timedomain.diagnosis.fit import DiagnosisData, JointModel
from benchmark.problems.timedomain.diagnosis.grid import on_grid
from benchmark.problems.timedomain.diagnosis.instants import Instants
from benchmark.problems.timedomain.diagnosis.rule import Rule, score_difference, share_removed
from benchmark.problems.timedomain.diagnosis.screening import Screening
from benchmark.problems.timedomain.diagnosis.set_fit import FOLDS, SetFit

__all__ = ["FOLDS", "NEGLIGIBLE_SHARE", "Selector", "SetFit"]

#: What :meth:`Selector.pair_step` returns when a member of the pair that earns is refused on entry.
REFUSED = "refused on entry"


class Selector(Screening, BackwardCheck, Instants):
    """The fits and decisions of the selection on one data set (module docstring)."""

    def __init__(self, data: DiagnosisData, settings, ctx, centre, fc_scale, masks, rule: Rule,
                 order: dict[str, int] | None = None):
        self.data, self.settings, self.ctx = data, settings, ctx
        self.centre, self.fc_scale, self.masks, self.rule = centre, fc_scale, masks, rule
        self.order = dict(order or {})  # effect name -> place in the catalogue (a model's parameter order)
        self.memo: dict[frozenset, SetFit] = {}
        self.grids: dict = {}  # (model's effects, fold mask) -> its start grids' best rows (:func:`.grid.on_grid`)
        self.screened_beside: dict = {}  # fit screened beside -> {candidate: its :class:`.screening.Screened`}
        self.refitted: set = set()  # (set, its sources' sets) already refitted: a refit from them again is the same
        self.full_fits: dict = {}  # set -> (fit cross-started from all data, the fit it came from, x on all data)
        self.base_full: np.ndarray | None = None  # the base fitted on all data (set by the pipeline)
        self.input_noise = None  # what the measured voltage's noise adds to each channel (the pipeline's)
        self.removal_fits: dict = {}  # (removal, set) -> selector of the record with it put back (conditioning_check)
        self.refused_names: set[str] = set()  # out of this selection: refused on entry (:meth:`forward`)
        labels = data.channel_labels()
        used = masks["A"] | masks["B"]
        lab = labels[used]
        self.groups = [np.flatnonzero(lab == k) for k in np.unique(lab)]

    # ------------------------------------------------------------------ fits
    def model(self, effects) -> JointModel:
        effects = sorted(effects, key=lambda e: (self.order.get(e.name, len(self.order)), e.name))
        return JointModel(self.data, self.settings.base_case, effects, self.ctx, self.centre, self.fc_scale,
                          self.settings.base_span)

    def fit(self, effects, sources, refit: bool = False, progress=None) -> SetFit:
        """Base + ``effects`` fitted on each fold (module docstring). ``sources``: pairs
        ``(base_from, extras_from)`` of :class:`SetFit` (a start takes the base parameters of
        ``base_from`` and each effect's extras from the first of ``extras_from`` that holds it;
        effects none holds take their own starts). A set already fitted is returned as it is,
        unless ``refit``: then it is fitted again from ``sources`` and its earlier fit, the better
        kept per fold (once per set of sources: again, the earlier refit is returned)."""
        return self.fits([(effects, sources, refit)], progress)[0]

    def fits(self, jobs, progress=None) -> list[SetFit]:
        """:meth:`fit` of each ``(effects, sources, refit)`` of ``jobs`` (distinct sets), every
        fold fit of every set side by side (a set's two folds need not wait for another set's),
        then each set's folds agreed and cross-started. A job may hold a fourth item, more
        starts by fold (``{fold: [{parameter name: value}, ...]}``), which makes it a refit of its own."""
        plans = [self._plan(*job[:3], progress, *job[3:]) for job in jobs]
        todo = [(p, f) for p in plans if not isinstance(p, SetFit) for f in FOLDS]
        done = side_by_side(lambda item: item[0]["fold_fit"](item[1]), todo)
        xs: dict = {}
        for (p, f), x in zip(todo, done, strict=True):
            xs.setdefault(id(p), {})[f] = x

        def finish(p):
            sf = self.cross_start(SetFit(p["model"], self.agreed(p["model"], xs[id(p)]), self.masks))
            self.memo[p["key"]] = sf
            return sf

        pending = [p for p in plans if not isinstance(p, SetFit)]
        finished = dict(zip(map(id, pending), side_by_side(finish, pending), strict=True))
        return [p if isinstance(p, SetFit) else finished[id(p)] for p in plans]

    def _plan(self, effects, sources, refit: bool, progress=None, more=None):
        """The memo's fit of ``effects`` where :meth:`fit` returns it as it is, else what its
        fold fits need: ``model``, ``key`` and ``fold_fit(fold)``; ``more``: further starts by
        fold, each a mapping of parameter names to values (:meth:`fits`)."""
        model = self.model(effects)
        key = frozenset(model.effect_names)
        old = self.memo.get(key)
        tried = (key, tuple((frozenset(b.names), tuple(frozenset(e.names) for e in x)) for b, x in sources),
                 more is not None)
        if old is not None and (not refit or tried in self.refitted):
            return old
        self.refitted.add(tried)
        if progress:
            progress(" + ".join(model.effect_names) or "base")
        known = {n for _, extras_from in sources for sf in extras_from for n in sf.names}
        new = [j for j, e in enumerate(model.effects) if e.name not in known]

        def fold_fit(f):
            starts = [x for base_from, extras_from in sources
                      for x in self.composed(model, base_from, extras_from, f)]
            starts = self.profiled(model, starts, self.masks[f], new)
            if old is not None:
                starts.append(old.xs[f])
            starts += [np.clip([p[n] for n in model.names], model.lower, model.upper) for p in (more or {}).get(f, [])]
            return self.best(model, starts, self.masks[f])

        return {"model": model, "key": key, "fold_fit": fold_fit}

    def best(self, model: JointModel, starts, mask, held: dict[int, float] | None = None) -> np.ndarray:
        """Every start fitted briefly (``screen_iterations``); the one that ends lowest on
        ``mask``'s samples fitted on to convergence (``held``: parameters held, as
        :meth:`JointModel.fit`)."""
        starts = _distinct(starts)
        if len(starts) > 1:
            legs = [model.fit(x0, mask, self.settings.screen_iterations, held=held) for x0 in starts]
            starts = [min(legs, key=lambda x: model.ssr(x, mask))]
        return model.fit(starts[0], mask, self.settings.max_iterations, held=held)

    def composed(self, model: JointModel, base_from: SetFit, extras_from, fold: str) -> list[np.ndarray]:
        """Starts of ``model`` on ``fold``: ``base_from``'s base parameters, each effect's extras
        from the first of ``extras_from`` that holds it. An effect none holds takes its own
        starting values (every start of the last such effect, the first of the others) and, for
        each, the starts that move part of the base into it (:meth:`Effect.starts_from_base`)."""
        k_base = len(model.base_names)
        x = np.empty(len(model.names))
        x[:k_base] = base_from.xs[fold][:k_base]
        missing = []
        for j, eff in enumerate(model.effects):
            src = next((sf for sf in extras_from if eff.name in sf.names), None)
            if src is None:
                missing.append(j)
                continue
            k = src.names.index(eff.name)
            x[model.slices[j]] = src.xs[fold][src.model.slices[k]]
        for j in missing[:-1]:
            x[model.slices[j]] = model.effects[j].extra_starts(self.ctx)[0]
        if not missing:
            return [np.clip(x, model.lower, model.upper)]
        last = missing[-1]
        starts = []
        for s in model.effects[last].extra_starts(self.ctx):
            y = x.copy()
            y[model.slices[last]] = s
            starts.append(y)
        base = dict(zip(model.base_names, map(float, x[:k_base]), strict=True))
        for j in missing:
            for setting, extras in model.effects[j].starts_from_base(base, self.ctx):
                y = starts[0].copy()
                for name, value in setting.items():
                    if name in model.base_names:
                        y[model.base_names.index(name)] = value
                y[model.slices[j]] = extras
                starts.append(y)
        return [np.clip(y, model.lower, model.upper) for y in starts]

    def profiled(self, model: JointModel, starts, mask, effects) -> list[np.ndarray]:
        """``starts`` with the grid parameter of each of ``effects`` (indices into
        ``model.effects``) that has one (:meth:`Effect.start_grid`) set to the grid value that
        fits ``mask`` best (:func:`.grid.on_grid`, its grids kept in :attr:`grids`: a round's
        screening and its fits profile the same starts), followed by the starts as they were."""
        effects = [j for j in effects if model.effects[j].start_grid(self.ctx) is not None]
        cache = self.grids.setdefault((tuple(model.effect_names), id(mask)), {}) if effects else None
        moved = [on_grid(model, x0, mask, effects, self.ctx, cache=cache) for x0 in starts] if effects else []
        return _distinct(moved + [np.asarray(x0, float) for x0 in starts])

    def cross_start(self, sf: SetFit, points=()) -> SetFit:
        """Each fold's fit refitted from the other fold's (and from ``points``, e.g. the fit on
        all data) where that point fits this fold's own samples better, until neither changes
        (every change lowers a fold's own SSR, so it ends); where one changed, its instants
        agreed again (:meth:`agreed`)."""
        model, xs, changed = sf.model, dict(sf.xs), False
        while True:
            moved = False
            for f, other in (("A", "B"), ("B", "A")):
                mask = self.masks[f]
                best, best_ssr = xs[f], model.ssr(xs[f], mask)
                for p in (xs[other], *points):
                    ssr_p = model.ssr(p, mask)
                    if ssr_p < best_ssr:
                        x = model.fit(p, mask, self.settings.max_iterations)
                        for cand, s in ((x, model.ssr(x, mask)), (p, ssr_p)):
                            if s < best_ssr:
                                best, best_ssr, moved = cand, s, True
                xs[f] = best
            changed |= moved
            if not moved:
                break
        return SetFit(model, self.agreed(model, xs), self.masks) if changed else sf

    def with_full_fit(self, sf: SetFit) -> tuple[SetFit, np.ndarray]:
        """``sf`` cross-started from the fit on all data (also returned: the reported parameters);
        the same fit again (or what it returned) is not fitted again."""
        key = frozenset(sf.names)
        done = self.full_fits.get(key)
        if done is not None and any(sf is f for f in done[:2]):
            return done[0], done[2]
        x = sf.model.fit(0.5 * (sf.xs["A"] + sf.xs["B"]), None, self.settings.max_iterations)
        out = self.cross_start(sf, [x])
        self.memo[key] = out
        self.full_fits[key] = (out, sf, x)
        return out, x

    # ------------------------------------------------------------------ decisions
    def row(self, name: str, cur: SetFit, sf: SetFit, band: float) -> dict:
        """One trial of the forward selection: ``sf`` is ``cur`` plus ``name``."""
        return {"effect": name, "heldout_chi2": sf.chi2, "excess_reduction": share_removed(cur.chi2, sf.chi2),
                "in_sample_reduction": share_removed(cur.in_sample_chi2, sf.in_sample_chi2),
                "earns": self.rule.earns_fit(cur, sf, band)}

    def indistinguishable(self, best: SetFit, others: list[tuple[str, SetFit]], z: float) -> list[str]:
        """Names of ``others`` whose held-out score is within ``z`` standard errors of ``best``'s."""
        out = []
        for name, sf in others:
            mean, se = score_difference(sf.held_used, best.held_used, self.groups)
            if mean <= z * se:
                out.append(name)
        return out

    def forward(self, candidates, cur: SetFit, band: float, order: list[str], rounds: list, progress=None,
                check_from: int | None = None) -> SetFit:
        """Greedy forward selection from ``cur`` (module docstring); appends the names chosen to
        ``order`` and each round's table to ``rounds``. ``check_from``: return as soon as an
        entry leaves at least that many effects (:meth:`select` checks them before going on)."""
        cap = self.settings.max_effects
        start = len(cur.names)
        while True:
            chosen = cur.effects
            if check_from is not None and len(chosen) > start and len(chosen) >= check_from:
                return cur
            pool = [e for e in candidates if e.name not in cur.names and e.name not in self.refused_names]
            if not pool or cur.chi2 <= band**2 or (cap is not None and len(chosen) >= cap):
                return cur
            trials, screened, refitted = self.round_fits(cur, pool, band, progress)
            rows = sorted((self.row(n, cur, sf, band) for n, sf in trials.items()), key=lambda r: r["heldout_chi2"])
            best = rows[0]
            rnd = {"round": sum(1 for r in rounds if "candidates" in r) + 1, "from": [e.name for e in chosen],
                   "heldout_chi2_from": cur.chi2, "candidates": rows, "chosen": None, "indistinguishable": [],
                   "screening": [{"effect": n, "screened_heldout_chi2": v, "fitted": n in trials,
                                  "seen_in_one_shape": self.seen_in_one_shape(cur, n)}
                                 for n, v in sorted(screened.items(), key=lambda kv: kv[1])]}
            if refitted:
                rnd["refitted_from_screening"] = refitted
            rounds.append(rnd)
            out = self.refused_on_entry(trials[best["effect"]], [best["effect"]]) if best["earns"] else None
            if out:
                rnd["refused"] = {"effect": out[0], "why": out[1]}  # out now, not after the rounds beside it
                self.refused_names.add(out[0])
                continue
            if best["earns"]:
                sf = trials[best["effect"]]
                rnd["chosen"] = best["effect"]
                rnd["indistinguishable"] = self.indistinguishable(
                    sf, [(r["effect"], trials[r["effect"]]) for r in rows[1:] if r["earns"]], self.settings.band_k)
                order.append(best["effect"])
                cur, _ = self.with_full_fit(sf)  # the next round starts from the set's best fit
                continue
            pair = self.pair_step(cur, pool, trials, band, rounds, progress)
            if pair is None:
                return cur
            if pair is REFUSED:  # a member out on entry: the round again from the same set without it
                continue
            names, cur = pair
            cur, _ = self.with_full_fit(cur)
            order += names

    def round_fits(self, cur: SetFit, pool, band: float, progress=None) -> tuple[dict, dict, list[str]]:
        """The fits of one forward round (module docstring): every candidate of ``pool`` screened
        beside ``cur`` (:meth:`screen_singles`); fitted fully, the one screened best, every one the
        screening says may earn its place, and every one it could not assess (screened no lower
        than ``cur``: the step from its starts found nothing, as for an inverter's drop whose
        start is far from its fit, development plant set 12 of the calibration: screened at 73
        beside the base's 12.5, fitted to 99.9 % of the excess; or seen in one shape only,
        :meth:`seen_in_one_shape`: a load linearised at no torque, motulator held-out seed 455
        set 8, screened 0.02 below the base's 144.47, fitted to 29.97); where none of those earns, every
        candidate; then the fits that missed their screening's basin (:meth:`missed_basins`). Returns
        (fits by name, screened held-out chi^2 by name, the names refitted from their screening)."""
        screened = self.screen_singles(cur, pool)
        ranked = sorted(pool, key=lambda e: (screened[e.name], e.name))
        first = ranked[:1] + [e for e in ranked[1:] if self.rule.earns(cur.chi2, screened[e.name], band)
                              or screened[e.name] >= cur.chi2  # not assessed: the step found no gain
                              or self.seen_in_one_shape(cur, e.name)]  # ... or saw one shape of it

        def fits_of(effects):
            done = self.fits([(cur.effects + [e], [(cur, [cur])], False) for e in effects], progress)
            return {e.name: sf for e, sf in zip(effects, done, strict=True)}

        fits = fits_of(first)
        if not any(self.rule.earns_fit(cur, sf, band) for sf in fits.values()):
            fits |= fits_of([e for e in ranked if e.name not in fits])
        refits = self.missed_basins(cur, ranked, fits, screened, band, progress)
        return fits | refits, screened, list(refits)

    def pair_step(self, cur: SetFit, pool, singles: dict, band: float, rounds: list, progress=None):
        """Two candidates that each earn their place beside the other, or None (module
        docstring); appends its round. Returns (names in entering order, the pair's fit), or
        :data:`REFUSED` where the first pair that earns has a member refused on entry
        (:meth:`refused_on_entry`: it leaves the candidates, and no round is fitted beside it)."""
        cap = self.settings.max_effects
        if len(pool) < 2 or (cap is not None and len(cur.names) + 2 > cap):
            return None

        def target(a, b):  # the largest fold-B chi^2 at which both would earn their place
            sa, sb = self.fold_b(singles[a.name]), self.fold_b(singles[b.name])
            if min(sa, sb) <= band**2:
                return -np.inf
            return min(sa - self.rule.share * (sa - 1.0), sb - self.rule.share * (sb - 1.0))

        pairs = list(itertools.combinations(pool, 2))
        if progress:
            progress(f"score tests of {len(pairs)} pairs beside {' + '.join(cur.names) or 'the base'}")
        predicted = self.screen_pairs(pool, singles)
        screened = []
        for a, b in pairs:
            chi2 = predicted[frozenset((a.name, b.name))]
            screened.append({"effect": f"{a.name}+{b.name}", "heldout_chi2_fold_B": chi2,
                             "may_earn": chi2 <= target(a, b), "pair": (a, b)})
        screened.sort(key=lambda r: r["heldout_chi2_fold_B"])
        rnd = {"round": sum(1 for r in rounds if "candidates" in r) + 1, "from": cur.names, "pairs": True,
               "screening": [{k: v for k, v in r.items() if k != "pair"} for r in screened],
               "heldout_chi2_from": cur.chi2, "candidates": [], "chosen": None, "indistinguishable": []}
        rounds.append(rnd)
        for r in screened:
            if not r["may_earn"] and r is not screened[0]:  # the best screened is fitted whatever
                continue
            a, b = r["pair"]
            sf = self.fit(cur.effects + [a, b], [(singles[a.name], [singles[a.name]]),
                                                 (singles[b.name], [singles[b.name]])], progress=progress)
            sa, sb = singles[a.name].chi2, singles[b.name].chi2
            without = {a.name: singles[b.name], b.name: singles[a.name]}  # each effect's model without it
            row = self.row(r["effect"], cur, sf, band)  # the pair's shares against the current set
            row |= {"shares_beside_each_other": {n: share_removed(w.chi2, sf.chi2) for n, w in without.items()},
                    "in_sample_shares_beside_each_other": {n: share_removed(w.in_sample_chi2, sf.in_sample_chi2)
                                                           for n, w in without.items()},
                    "earns": all(self.rule.earns_fit(w, sf, band) for w in without.values())}
            rnd["candidates"].append(row)
            earns = row["earns"]
            if earns:
                out = self.refused_on_entry(sf, [a.name, b.name])  # checked on entry as a single is
                if out:
                    rnd["refused"] = {"effect": out[0], "why": out[1], "pair": r["effect"]}
                    self.refused_names.add(out[0])
                    return REFUSED
                names = [a.name, b.name] if sa <= sb else [b.name, a.name]  # the stronger alone first
                rnd["chosen"] = "+".join(names)
                return names, sf
        return None

    def select(self, candidates, base_fit: SetFit, band: float, progress=None):
        """Forward selection with the backward check after every entry that leaves two effects
        or more (an effect a later one makes redundant goes before rounds are fitted beside the
        two; it stays a candidate, to enter again beside an effect that masks it, until it is
        dropped a second time) and when no candidate enters (what it drops then leaves the
        candidates), until a forward round adds nothing and the check drops nothing. Returns
        (final fit, its fit on all data or None, the drop-one fits by name, the chosen names in
        order of selection, names pruned, rounds)."""
        rounds, order, pruned = [], [], []
        cur, pool = base_fit, list(candidates)
        self.refused_names = set()
        full_x, withouts, checked = None, {}, None
        while True:
            done = len(rounds)
            cur = self.forward(pool, cur, band, order, rounds, progress, check_from=2)
            # returned right after an entry (a check is due), not after a round where none entered
            grew = len(rounds) > done and rounds[-1]["chosen"] is not None
            if pruned:
                for r in rounds[done:]:
                    r["resumed_after_pruning"] = list(pruned)
            if not cur.names:
                return cur, None, {}, [], pruned, rounds
            if frozenset(cur.names) == checked:  # nothing entered since the last check passed
                break
            cur, full_x = self.with_full_fit(cur)
            cur, withouts, dropped = self.backward(cur, self.memo.get(frozenset(), base_fit), band, progress, full_x)
            pruned += dropped
            checked = frozenset(cur.names)
            if not dropped and not grew:
                break
            if not dropped:
                continue
            # dropped where the forward selection ended, or a second time: out of the candidates;
            # dropped right after an entry: still a candidate (its masking partner may yet enter)
            gone = {n for n in dropped if not grew or pruned.count(n) > 1}
            pool = [e for e in pool if e.name not in gone]
            if cur.names:
                cur, full_x = self.with_full_fit(cur)
        order = list(reversed(dict.fromkeys(n for n in reversed(order) if n in cur.names)))  # its last entry
        return cur, full_x, withouts, order, pruned, rounds


def _distinct(xs) -> list[np.ndarray]:
    out = []
    for x in xs:
        x = np.asarray(x, float)
        if not any(np.array_equal(x, y) for y in out):
            out.append(x)
    return out
