"""The GA itself: one run of GENESIS 5.0 on settings, a template and an objective, bit for bit."""

from __future__ import annotations

import math
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from benchmark.core.errors import ConfigError
from plugins.genesis.files import format_out_line
from plugins.genesis.randu import Randu
from plugins.genesis.settings import INF_COST, Settings, Template


@dataclass
class SavedEntry:
    """One slot of the saved list: the string, its cost, and generation/trial when first found."""

    bits: np.ndarray
    cost: float
    gen: int
    trial: int


@dataclass
class RunResult:
    out_lines: list[str]
    saved: list[SavedEntry]
    generations: int  # populations evaluated in the last experiment (generation 0 included)
    trials: int
    best_cost: float
    best_bits: np.ndarray | None
    stop_reason: str
    files: list[Path] = field(default_factory=list)  # written by :func:`run_dir`


def sum_of_squares(X: np.ndarray) -> np.ndarray:
    """Row-wise ``x1^2 + x2^2 + ...``, accumulated left to right from 0.0 like a C loop."""
    X = np.atleast_2d(np.asarray(X, float))
    s = np.zeros(X.shape[0])
    for j in range(X.shape[1]):
        s = s + X[:, j] * X[:, j]
    return s


class Genesis:
    """The GA engine. ``objective(X)`` takes the decoded rows to evaluate (all marked structures
    of one generation, in index order) and returns their costs."""

    def __init__(
        self,
        settings: Settings,
        template: Template | None,
        objective: Callable[[np.ndarray], np.ndarray],
        rng: Randu | None = None,
    ):
        bad = settings.check()
        if bad:
            raise ConfigError("; ".join(f"{k}: {m}" for k, m in bad))
        self.s = settings
        self.floating = settings.flag("f") and template is not None
        self.gray = self.floating and settings.flag("g")
        self.template = template
        if self.floating and template.length != settings.structure_length:
            raise ConfigError(
                f"structure_length: {settings.structure_length} bits, but the template's genes take {template.length}"
            )
        self.L = settings.structure_length
        self.N = settings.population_size
        self.objective = objective
        self.rng = rng if rng is not None else Randu(settings.random_seed)
        self.maximise = settings.flag("M")
        self.out_lines: list[str] = []

    # ---- helpers -----------------------------------------------------------------------------

    def decode(self, bits: np.ndarray) -> np.ndarray:
        if self.floating:
            return self.template.decode(bits, self.gray)
        return np.atleast_2d(bits).astype(float)

    def _better(self, a: float, b: float) -> bool:
        return a > b if self.maximise else a < b

    def _gap(self) -> int:
        """Distance to the next mutation (one draw)."""
        mr = self.s.mutation_rate
        if mr >= 1.0:
            return 1
        r = self.rng.rand()
        if mr <= 0.0:
            return sys.maxsize
        return math.ceil(math.log(r) / self._log1m)

    def _sanitise(self, c: np.ndarray) -> np.ndarray:
        c = np.asarray(c, dtype=float).reshape(-1)
        bad_high = -INF_COST if self.maximise else INF_COST
        c = np.where(np.isnan(c), bad_high, c)
        return np.clip(c, -INF_COST, INF_COST)

    # ---- one experiment ----------------------------------------------------------------------

    def run(self) -> RunResult:
        result = None
        for _ in range(self.s.experiments):
            result = self._experiment()
        result.out_lines = self.out_lines
        return result

    def _experiment(self) -> RunResult:
        s, N, L, rng = self.s, self.N, self.L, self.rng
        W = s.scaling_window
        self._log1m = math.log(1.0 - s.mutation_rate) if 0.0 < s.mutation_rate < 1.0 else 0.0
        self.trials = 0
        self.gen = 0
        self.best: float | None = None
        self.best_bits: np.ndarray | None = None
        self.online = 0.0
        self.offline = 0.0
        self.saved: list[SavedEntry] = []
        self._saved_keys: list[bytes] = []
        window = [0.0] * W
        worst = 0.0
        spin = 0
        lost = 0
        plateau = 0
        stop = ""

        mu_next = self._gap()
        pop = np.array([rng.randint(0, 1) for _ in range(N * L)], dtype=np.uint8).reshape(N, L)
        perf = np.zeros(N)
        needs = np.ones(N, dtype=bool)
        avg = 0.0
        best_idx = 0
        old_best_bits = pop[0].copy()
        old_best_perf = 0.0

        while True:
            if self.gen > 0:
                pop, perf, needs = self._select(pop, perf, avg, worst)
                mu_next = self._mutate(pop, needs, mu_next)
                self._crossover(pop, needs)
                if s.flag("e"):
                    self._elitist(pop, perf, needs, old_best_bits, old_best_perf)
                if s.flag("a"):
                    needs[:] = True
            n_eval = self._evaluate(pop, perf, needs)
            spin = 0 if n_eval else spin + 1

            # measure
            total = 0.0
            for c in perf.tolist():
                total += c
            avg = total / N
            if self.maximise:
                best_idx = int(np.argmax(perf))
                w = float(perf.min())
                new_worst = w * 0.9999 if w > 0 else (w * 1.0001 if w < 0 else -1e-4)
            else:
                best_idx = int(np.argmin(perf))
                w = float(perf.max())
                new_worst = w * 1.0001 if w > 0 else (w * 0.9999 if w < 0 else 1e-4)
            if W > 0:
                window[self.gen % W] = new_worst
                worst = min(window) if self.maximise else max(window)
            elif self.gen == 0 or self._better(worst, new_worst):
                worst = new_worst
            old_best_bits = pop[best_idx].copy()
            old_best_perf = float(perf[best_idx])

            # report
            converged = False
            if self.gen == 0 or self.trials >= plateau:
                plateau = (self.trials // s.report_interval + 1) * s.report_interval
                lost, conv, bias = 0, 0, 0.0
                if s.flag("c"):
                    ones = pop.sum(axis=0, dtype=np.int64)
                    lost = int(np.count_nonzero((ones == 0) | (ones == N)))
                    tol = N // 20
                    conv = int(np.count_nonzero((ones <= tol) | (ones >= N - tol)))
                    bias = int(np.maximum(ones, N - ones).sum()) / (N * L)
                    converged = bias > 0.99
                if s.flag("c") or s.flag("C"):
                    stats = (lost, conv, bias, self.online / self.trials, self.offline / self.trials, self.best, avg)
                    self.out_lines.append(format_out_line(self.gen, self.trials, *stats))
                    if converged:
                        self.out_lines.extend(self._padding(stats))

            # termination
            if converged:
                stop = f"converged (bias > 0.99) at generation {self.gen}"
            elif self.trials >= s.total_trials:
                stop = f"Total Trials ({s.total_trials}) reached"
            elif s.flag("c") and lost >= L:
                stop = f"all {L} bit positions lost at generation {self.gen}"
            elif spin >= s.max_gens_without_eval:
                stop = f"{spin} generations without evaluation"
            if stop:
                break
            self.gen += 1

        return RunResult(
            out_lines=self.out_lines,
            saved=self.saved,
            generations=self.gen + 1,
            trials=self.trials,
            best_cost=self.best if self.best is not None else math.nan,
            best_bits=self.best_bits,
            stop_reason=stop,
        )

    def _padding(self, stats: tuple) -> list[str]:
        """The lines the original appends to ``out`` when a run is declared converged.

        ``stats`` are the statistics of the report line just written (Lost ... average). Each
        padding line repeats that line (same trials and statistics) with the generation number
        advanced by ``Report Interval // N`` (at least 1) per line; there is one line per Report
        Interval still missing before Total Trials, i.e. ``ceil((Total Trials - trials) / Report
        Interval)`` lines. At N = 100, Report Interval 1000 and 20000 trials, a run converged at
        generation 169 (17000 trials) gets 179, 189 and 199 (the generation at which it would
        have ended)."""
        s = self.s
        step = max(1, s.report_interval // self.N)
        lines = []
        gen, reached = self.gen, self.trials
        while reached < s.total_trials:
            reached += s.report_interval
            gen += step
            lines.append(format_out_line(gen, self.trials, *stats))
        return lines

    # ---- generation steps --------------------------------------------------------------------

    def _select(self, pop, perf, avg, worst):
        s, N, rng = self.s, self.N, self.rng
        f = perf.tolist()
        if s.flag("R"):
            order = np.argsort(-perf if self.maximise else perf, kind="stable")
            rank = np.empty(N, dtype=np.int64)
            rank[order] = np.arange(N - 1, -1, -1)
            rmin = s.rank_min
            expected = [rmin + r * (2 - 2 * rmin) / (N - 1) for r in rank.tolist()]
        elif self.maximise:
            denom = avg - worst
            expected = [(x - worst) / denom if x > worst else 0.0 for x in f]
        else:
            denom = worst - avg
            expected = [(worst - x) / denom if x < worst else 0.0 for x in f]

        # stochastic universal sampling
        sample: list[int] = []
        ptr = rng.rand()
        acc = 0.0
        for i, e in enumerate(expected):
            acc += e
            while acc > ptr and len(sample) < N:
                sample.append(i)
                ptr += 1.0
        while len(sample) < N:  # only through rounding; the original stops with an error here
            sample.append(N - 1)
        for i in range(N):
            j = rng.randint(i, N - 1)
            sample[i], sample[j] = sample[j], sample[i]
        if s.generation_gap < 1.0:
            perm = list(range(N))
            for i in range(N):
                j = rng.randint(i, N - 1)
                perm[i], perm[j] = perm[j], perm[i]
            k = int(s.generation_gap * N)
            sample = sample[:k] + perm[k:]
        idx = np.asarray(sample, dtype=np.intp)
        return pop[idx], perf[idx], np.zeros(N, dtype=bool)

    def _mutate(self, pop, needs, mu_next):
        s, L, rng = self.s, self.L, self.rng
        nbits = int(s.generation_gap * self.N * L + 0.5)
        while mu_next < nbits:
            i, j = divmod(mu_next, L)
            allele = rng.randint(0, 1)
            if pop[i, j] != allele:
                pop[i, j] = allele
                needs[i] = True
            mu_next += self._gap()
        return mu_next - nbits

    def _crossover(self, pop, needs):
        s, L, rng = self.s, self.L, self.rng
        last = int(s.crossover_rate * self.N * s.generation_gap - 0.5)
        mom = 0
        while mom < last:
            dad = mom + 1
            x1 = rng.randint(0, L)
            x2 = rng.randint(0, L - 1)
            if x2 >= x1:
                x2 += 1
            else:
                x1, x2 = x2, x1
            a, b = pop[mom], pop[dad]
            if not (np.array_equal(a[:x1], b[:x1]) and np.array_equal(a[x2:], b[x2:])):
                if not np.array_equal(a[x1:x2], b[x1:x2]):
                    tmp = a[x1:x2].copy()
                    a[x1:x2] = b[x1:x2]
                    b[x1:x2] = tmp
                    needs[mom] = needs[dad] = True
            mom += 2

    def _elitist(self, pop, perf, needs, best_bits, best_perf):
        if not np.any(np.all(pop == best_bits, axis=1)):
            pop[-1] = best_bits
            perf[-1] = best_perf
            needs[-1] = False

    def _evaluate(self, pop, perf, needs) -> int:
        idx = np.flatnonzero(needs)
        if len(idx) == 0:
            return 0
        costs = self._sanitise(self.objective(self.decode(pop[idx])))
        if costs.shape != (len(idx),):
            raise ValueError(f"objective returned {costs.shape} costs for {len(idx)} structures")
        K = self.s.structures_saved
        for i, c in zip(idx.tolist(), costs.tolist(), strict=True):
            self.trials += 1
            perf[i] = c
            if self.best is None or self._better(c, self.best):
                self.best = c
                self.best_bits = pop[i].copy()
            self.online += c
            self.offline += self.best
            if K:
                self._save(pop[i], c, K)
        needs[:] = False
        return len(idx)

    def _save(self, bits, c, K):
        saved = self.saved
        if len(saved) >= K:
            wk = 0
            for k in range(1, len(saved)):
                if self._better(saved[wk].cost, saved[k].cost):
                    wk = k
            if not self._better(c, saved[wk].cost):
                return
        key = bits.tobytes()
        if key in self._saved_keys:
            return
        entry = SavedEntry(bits.copy(), c, self.gen, self.trials)
        if len(saved) < K:
            saved.append(entry)
            self._saved_keys.append(key)
        else:
            saved[wk] = entry
            self._saved_keys[wk] = key
