"""Selections on given fits (the tests of the selection and of its backward check): a
:class:`~benchmark.problems.timedomain.diagnosis.selection.Selector` whose fits and screenings are
looked up from held-out chi^2 given by the test."""

from __future__ import annotations

from types import SimpleNamespace

from benchmark.problems.timedomain.diagnosis.pipeline import DiagnosisSettings
from benchmark.problems.timedomain.diagnosis.rule import Rule
from benchmark.problems.timedomain.diagnosis.selection import Selector


class Effect(SimpleNamespace):
    def __init__(self, name, k=2):
        super().__init__(name=name, extra_names=tuple(f"p{j}" for j in range(k)))


def given_fit(chi2, effects=(), in_sample=None):
    """A fitted set; its in-sample chi^2 (reported, not decided) the held-out one unless given."""
    return SimpleNamespace(chi2=chi2, in_sample_chi2=chi2 if in_sample is None else in_sample,
                           names=[e.name for e in effects], effects=list(effects),
                           model=SimpleNamespace(effects=list(effects)))


class Given(Selector):
    """A selector whose fits are looked up: ``held[frozenset(names)] = chi2``; a single's or a
    pair's screening gives its full value (``screened`` overrides it); a single's screening saw
    it in more than one shape unless it is in ``one_shape``."""

    def __init__(self, held, share=0.5, settings=None, screened=None, refits=None, negligible=(), in_sample=None,
                 one_shape=()):
        self.one_shape = set(one_shape)
        self.settings = settings or DiagnosisSettings()
        self.rule = Rule(share)
        self.held, self.screened, self.refits = held, screened or {}, refits or {}
        self.in_sample = in_sample or {}  # frozenset(names) -> in-sample chi^2 (default: the held-out one)
        self.fitted, self.memo, self.small, self.refused_names = [], {}, set(negligible), set()

    def fit(self, effects, sources, refit=False, progress=None):
        """``refits``: what a drop-one refit from several starts finds where it beats the first fit."""
        names = frozenset(e.name for e in effects)
        self.fitted.append(sorted(names))
        chi2 = self.held[names]
        if refit:
            chi2 = self.held[names] = min(chi2, self.refits.get(names, chi2))
        return given_fit(chi2, effects, self.in_sample.get(names))

    def fits(self, jobs, progress=None):
        """A job with further starts (the screening's points) is a refit, which ``refits`` answers."""
        self.more = getattr(self, "more", []) + [job[3] for job in jobs if len(job) > 3]
        return [self.fit(effects, sources, refit) for effects, sources, refit, *_ in jobs]

    def screened_points(self, cur, name):
        return {"A": [{"screened": name}], "B": [{"screened": name}]}

    def screen_singles(self, cur, pool):
        """A single's screening gives its full value unless ``screened`` overrides it."""
        return {e.name: self.screened.get(frozenset(cur.names + [e.name]), self.held[frozenset(cur.names + [e.name])])
                for e in pool}

    def seen_in_one_shape(self, cur, name):
        return name in self.one_shape

    def screen_pairs(self, pool, singles):
        cur = next(iter(singles.values())).names[:-1]
        out = {}
        for i, a in enumerate(pool):
            for b in pool[i + 1:]:
                key = frozenset(cur + [a.name, b.name])
                out[frozenset((a.name, b.name))] = self.screened.get(key, self.held[key])
        return out

    def fold_b(self, sf):
        return sf.chi2

    def indistinguishable(self, best, others, z):
        return []

    def with_full_fit(self, sf):
        return sf, None

    def refused_on_entry(self, sf, names):
        return next(((n, "negligible") for n in names if n in self.small), None)


LOAD, GAIN, SKEW = Effect("load_torque", 7), Effect("speed_sensor_gain", 4), Effect("channel_delay", 1)
TWO = Effect("two_mass", 4)
DROP = Effect("inverter_drop", 2)
BAND = 1.1  # the noise band of the held-out RMS over noise: chi^2 1.21
