"""One set of effects fitted on the two folds, and its held-out residual (the unit the
selection's decisions compare: :mod:`.selection`)."""

from __future__ import annotations

import numpy as np

from benchmark.core.effects import Effect
from benchmark.problems.timedomain.diagnosis.fit import JointModel

#: The two folds (:mod:`.folds`): each fitted on its own samples, scored on the other's.
FOLDS = ("A", "B")


class SetFit:
    """Fold fits of the base plus one set of effects, and their held-out residual."""

    def __init__(self, model: JointModel, xs: dict, masks: dict):
        self.model = model
        self.xs = xs
        n = model.data.n_residuals
        # residuals the conditioning masked are in neither fold: 0 here, and left out of chi^2
        self.used = masks["A"] | masks["B"]
        self.held = np.zeros(n)
        self.ssr_fold = {}  # in-sample SSR of each fold's fit on its own fold
        for f, other in (("A", "B"), ("B", "A")):
            r = model.residuals(xs[f][None, :])[0]
            self.held[masks[other]] = r[masks[other]]
            self.ssr_fold[f] = float(np.sum(r[masks[f]] ** 2))
        self.chi2 = float(np.mean(self.held[self.used] ** 2))
        #: What the fits reached on their own samples, per residual (reported beside the held-out score)
        self.in_sample_chi2 = float(sum(self.ssr_fold.values()) / max(int(np.count_nonzero(self.used)), 1))

    @property
    def held_used(self) -> np.ndarray:
        """The held-out residuals of the samples in a fold (the masked ones left out)."""
        return self.held[self.used]

    @property
    def names(self) -> list[str]:
        return self.model.effect_names

    @property
    def effects(self) -> list[Effect]:
        return list(self.model.effects)

