"""GENESIS 5.0 (Grefenstette 1990), a clean-room clone, as an optimiser plugin.

The clone reproduces the trajectory of the original program bit for bit (same ``out`` lines,
same ``min`` list) for the same settings, template, seed and objective. It is checked against the
original's own worked example (``f = x1^2 + x2^2 + x3^2``), kept with its settings, template and
the ``out`` and ``min`` files the original wrote in ``tests/plugins/genesis_vectors/ex1/`` (``ex1``
below) and reproduced byte for byte by ``tests/plugins/test_genesis.py``.

Two ways to use it
------------------
* As the benchmark's optimiser plugin: :func:`minimize` (Hydra config ``conf/optimizer/genesis.yaml``).
  Genes span ``[problem.lower, problem.upper]`` with ``2**bits_per_gene`` values each, Total Trials
  is the harness's budget and the objective is the problem cost (always minimised).
* As a stand-in for the original program::

      python -m plugins.genesis DIR                    # objective: x1^2 + x2^2 + ... (sum of squares)
      python -m plugins.genesis DIR module:function    # objective: module.function(x) -> float
      python -m plugins.genesis DIR --out-dir OUTDIR   # write out/min to OUTDIR instead of DIR

  reads ``DIR/in`` and ``DIR/template`` in the original formats and writes ``out`` and ``min``
  into ``DIR`` as the original does (into ``OUTDIR``, created if missing, with ``--out-dir``),
  then prints one summary line. ``plugins/genesis_example/`` is a small ready-made ``DIR``.
  ``module:function`` is imported with ``importlib`` (the current directory is on the path); the
  function receives the decoded genes as a 1-D float64 numpy vector and returns a float. Bad
  input (missing file, malformed line, bad value, unimportable objective) prints one line naming
  the file and line and exits with status 2.

The original's files
--------------------
``in``: 16 lines ``Label = value``, in this order (the original's defaults in brackets; the
labels are matched ignoring case and repeated blanks, blank lines are skipped)::

           Experiments = 1          [1]
          Total Trials = 1000       [1000]    stop once this many evaluations were made
       Population Size = 50         [50]      N
      Structure Length = 30         [30]      L, bits per structure (= the template's bits)
        Crossover Rate = 0.6        [0.6]
         Mutation Rate = 0.001      [0.001]   per bit; a mutated bit is redrawn, so it flips half the time
        Generation Gap = 1.0        [1.0]     share of the population replaced each generation
        Scaling Window = 5          [5]       generations over which the worst cost is remembered
       Report Interval = 200        [100]     trials between two ``out`` lines
      Structures Saved = 5          [10]      length of the ``min`` list
     Max Gens w/o Eval = 2          [2]       stop after this many generations without a trial
         Dump Interval = 0          [0]       (checkpoints: ignored by the clone)
           Dumps Saved = 0          [0]       (ignored)
               Options = acefgL     [cefgl]   option letters, see below
           Random Seed = 123456789  [123456789]
              Rank Min = 0.75       [0.75]    expected count of the worst structure with ``R``

Options: ``a`` evaluate every structure each generation (unchanged copies cost a trial too);
``c`` collect statistics and convergence measures (``out`` lines with Lost/Conv/Bias, and the
``Bias > 0.99`` stop); ``C`` statistics only; ``e`` elitist; ``f`` floating-point genes from the
``template``; ``g`` Gray code (with ``f``); ``M`` maximise (default: minimise); ``R`` rank
selection (default: proportional). ``l``, ``L``, ``d``, ``o``, ``O``, ``b``, ``D``, ``I``, ``s``,
``t`` and unknown letters are accepted and ignored; ``i`` and ``r`` are refused (see below).

``template`` (read with option ``f``): ``genes: n``, then for each gene a ``gene k`` line and the
lines ``min: x``, ``max: x``, ``values: v`` (a power of two) and ``format: %7.2f`` (the printf
format of the gene in the ``min`` file); blank lines are ignored. A gene takes ``log2(values)``
consecutive bits, most significant first (Gray-decoded first with ``g``), and the integer ``k``
they encode gives ``min + k * (max - min) / (values - 1)``. Example::

    genes: 1

    gene 0
    min: -5.12
    max: 5.11
    values: 1024
    format: %7.2f

``out`` (written with ``c`` or ``C``): one line per report point, in the C format
``"%5d %5d %2d %2d %5.3f %.6e %.6e %.6e %.6e"``: generation, trials, Lost (bit positions where
all N structures agree), Conv (positions where at most ``N // 20`` disagree), Bias (mean share
of the majority allele), online (mean of all costs so far), offline (mean of the best-so-far
after each trial), best cost so far, population average. Report points are generation 0 and
each generation whose trials reach the next multiple of Report Interval. A run declared
converged (``c`` and ``Bias > 0.99``) stops, and the original pads ``out`` with copies of the last
line whose generation number advances by ``Report Interval // N`` per line, one line per Report
Interval still missing before Total Trials (converged at generation 169 with 17000 of 20000
trials at N = 100, Report Interval 1000: lines for 169, 179, 189, 199, all with 17000 trials).

``min``: the best distinct structures found (Structures Saved of them, in slot order), one per
line: each gene in its template format (without ``f``: the string of 0s and 1s), then the cost
as ``"  %11.4e "``, then ``" %4d  %4d"`` the generation and trial at which it was first found.

Random seed of the plugin
-------------------------
``random_seed`` (the RANDU seed) if given, else derived from the harness's integer ``seed``:
``seed == 0`` gives the paper's 123456789; any other seed ``s`` gives
``(splitmix64(s mod 2**64) >> 33) | 1``, a 31-bit odd number, so never 0 (RANDU would stick at 0)
and neighbouring seeds give unrelated RANDU streams.

Non-finite costs
----------------
A cost of ``+inf`` or NaN (a diverging candidate) is replaced by :data:`INF_COST` ``= 1e300``
(``-1e300`` when maximising), ``-inf`` by ``-1e300`` (``+1e300`` when maximising), so the
proportional-selection arithmetic stays finite (``1e300 * 1.0001`` and population sums of up to
~1e8 such values do not overflow). While such a value is the scaling window's ``Worst`` the finite
candidates all get (nearly) the same expected count: that is what the original does with a huge
cost too.

Readings chosen where the description leaves room (the ones ex1 decides are marked [ex1])
----------------------------------------------------------------------------------------
* RANDU: ``seed = seed * 65539 mod 2**31``, advanced first, then scaled:
  ``Rand() = new_seed * 0.4656612875e-9``; ``Randint(lo, hi) = int(lo + (hi - lo + 1) * Rand())``
  [ex1; from 123456789 the first three ``Rand()`` are 0.7746705113383283, 0.13062164053126013,
  0.8116952440327436].
* Gene values: ``min + integer * step`` with ``step = (max - min) / (values - 1)`` in double
  precision, as the original describes it (ex1 does not tell it from ``min + (max - min) * i / (values - 1)``);
  the runner's sum of squares is accumulated left to right from 0.0 like a C loop.
* Mutation positions are 0-based indices into the population's bit array, so the first gap
  (>= 1) never hits bit 0 of structure 0 [ex1].
* Crossover: parents that agree outside ``[x1, x2)`` are left alone; otherwise the segment is
  exchanged and both children are marked if the segments differed [ex1: always exchanging does
  not reproduce it; with ``a`` the marking itself is moot].
* Evaluation: the offline sum adds the best-so-far *after* it is updated with the trial [ex1].
* Saved list (``min``): a string already in the list is skipped; while the list is not full the
  string takes the next free slot; when full it replaces the worst saved entry if strictly
  better [ex1: slot order, not sorted]. Which slot goes on a tie of worst entries (the first
  here) and whether an equal cost replaces (no here) ex1 does not decide.
* Crossover points: ``x1 = Randint(0, L)``, ``x2 = Randint(0, L - 1)`` as the original describes
  [ex1: ``Randint(0, L - 1)``, ``Randint(0, L - 2)`` does not reproduce it].
* Elitist: the copy is made only when no new string equals the old best [ex1: always copying
  does not reproduce it].
* ``out`` best column: the best value ever found (with ``e`` it is also the population's best).
* Report points: generation 0, and every generation whose trial count reaches the next multiple
  of Report Interval above the trials of the previous report (one line even if several multiples
  were passed). No extra line is written at termination unless it is such a point.
* ``Lost``/``Conv``/``Bias`` are computed at report points with option ``c`` only; so the
  ``Lost = L`` stop and the ``Bias > 0.99`` stop are checked there. On ``Bias > 0.99`` the report
  line is written, then the padding lines (see "The original's files" above: same trials and
  statistics, generation advanced by ``Report Interval // N``, at least 1, per line), and the run
  stops. The step is the original's ``Report Interval / Population Size`` in integer arithmetic,
  whatever the Generation Gap (with ``a`` a generation costs N trials at any gap); the number of
  lines is ``ceil((Total Trials - trials) / Report Interval)``. ``RunResult.generations`` counts
  the generations really evaluated, not the padded ones. (ex1 does not converge; the padding is
  checked against the original's documented example, 169, 179, 189, 199.)
* ``C`` without ``c``: ``out`` lines are written with Lost, Conv, Bias = 0, 0, 0.000. Neither
  ``c`` nor ``C``: no ``out`` file is written.
* Rank selection (``R``): the population is sorted best first with a stable sort, so on ties the
  earlier index gets the higher rank.
* ``Max Gens w/o Eval``: a counter of consecutive generations with no trial; the run stops when
  it reaches the setting.
* Scaling Window 0: ``Worst`` is generation 0's ``New_worst``, then replaced by a later
  ``New_worst`` only when that one is worse.
* Mutation Rate 0: the first-gap draw is still made and no bit is ever mutated (the original's
  formula divides by log(1) = 0 there).
* Select must take exactly N structures; the original's description does not say what happens otherwise (only
  possible through rounding of the expected counts). The clone stops taking at N and, if short,
  fills the rest with the last structure, so a long benchmark run is not lost.
* Experiments > 1: the experiments run one after the other on the same RANDU stream; ``out``
  receives the lines of all of them, ``min`` holds the saved list of the last one.
* Options ``i`` (initial structures from a file) and ``r`` (restart from a checkpoint) are refused;
  ``d``, ``L``, ``l``, ``o``, ``O``, ``b``, ``D``, ``I``, ``s``, ``t`` and unknown letters are
  accepted and ignored (no checkpoint, log or trace files are written). Without ``f`` the
  structures are plain bit strings: the objective receives the 0/1 bits as a float vector and the
  ``min`` file prints the string of 0s and 1s in place of the genes.
"""

from __future__ import annotations

import importlib
import math
import os
import re
import sys
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

from benchmark.core.errors import ConfigError, UserError

__all__ = [
    "INF_COST",
    "DEFAULT_SEED",
    "GenesisInputError",
    "Settings",
    "Gene",
    "Template",
    "Randu",
    "Genesis",
    "RunResult",
    "SavedEntry",
    "seed_to_randu",
    "gray_to_binary",
    "read_settings",
    "read_template",
    "format_out_line",
    "format_min_lines",
    "write_out",
    "write_min",
    "sum_of_squares",
    "run_dir",
    "main",
    "minimize",
]

#: Finite stand-in for a +inf (or NaN) cost, see the module docstring.
INF_COST = 1e300
#: The paper's (and GENESIS's default) RANDU seed.
DEFAULT_SEED = 123456789
_MASK31 = 2147483647
_MASK64 = (1 << 64) - 1


class GenesisInputError(UserError):
    """An ``in``/``template`` file or a setting is unusable; the message names the file and line."""


# --------------------------------------------------------------------------------------------
# settings and template
# --------------------------------------------------------------------------------------------


@dataclass
class Settings:
    """The 16 settings of the original ``in`` file, in file order, with the original defaults."""

    experiments: int = 1
    total_trials: int = 1000
    population_size: int = 50
    structure_length: int = 30
    crossover_rate: float = 0.6
    mutation_rate: float = 0.001
    generation_gap: float = 1.0
    scaling_window: int = 5
    report_interval: int = 100
    structures_saved: int = 10
    max_gens_without_eval: int = 2
    dump_interval: int = 0
    dumps_saved: int = 0
    options: str = "cefgl"
    random_seed: int = DEFAULT_SEED
    rank_min: float = 0.75

    def flag(self, letter: str) -> bool:
        return letter in self.options

    def check(self) -> list[tuple[str, str]]:
        """Problems as ``(field name, message)`` pairs; empty when the settings are usable."""
        bad: list[tuple[str, str]] = []
        if self.experiments < 1:
            bad.append(("experiments", "must be >= 1"))
        if self.total_trials < 1:
            bad.append(("total_trials", "must be >= 1"))
        if self.population_size < 2:
            bad.append(("population_size", "must be >= 2"))
        if self.structure_length < 1:
            bad.append(("structure_length", "must be >= 1"))
        if not 0.0 <= self.crossover_rate <= 1.0:
            bad.append(("crossover_rate", "must be in [0, 1]"))
        if not 0.0 <= self.mutation_rate <= 1.0:
            bad.append(("mutation_rate", "must be in [0, 1]"))
        if not 0.0 < self.generation_gap <= 1.0:
            bad.append(("generation_gap", "must be in (0, 1]"))
        if self.scaling_window < 0:
            bad.append(("scaling_window", "must be >= 0"))
        if self.report_interval < 1:
            bad.append(("report_interval", "must be >= 1"))
        if self.structures_saved < 0:
            bad.append(("structures_saved", "must be >= 0"))
        if self.max_gens_without_eval < 1:
            bad.append(("max_gens_without_eval", "must be >= 1"))
        for letter, what in (("i", "initial structures from a file"), ("r", "restart from a checkpoint")):
            if letter in self.options:
                bad.append(("options", f"option '{letter}' ({what}) is not supported by the clone"))
        if (self.random_seed & _MASK31) == 0:
            bad.append(("random_seed", "must not be 0 modulo 2**31 (RANDU would stay at 0)"))
        if self.flag("R") and not 0.0 <= self.rank_min <= 1.0:
            bad.append(("rank_min", "must be in [0, 1]"))
        return bad


_LABELS = {
    "experiments": "Experiments",
    "total_trials": "Total Trials",
    "population_size": "Population Size",
    "structure_length": "Structure Length",
    "crossover_rate": "Crossover Rate",
    "mutation_rate": "Mutation Rate",
    "generation_gap": "Generation Gap",
    "scaling_window": "Scaling Window",
    "report_interval": "Report Interval",
    "structures_saved": "Structures Saved",
    "max_gens_without_eval": "Max Gens w/o Eval",
    "dump_interval": "Dump Interval",
    "dumps_saved": "Dumps Saved",
    "options": "Options",
    "random_seed": "Random Seed",
    "rank_min": "Rank Min",
}


@dataclass
class Gene:
    """One template gene: ``values`` (a power of two) equally spaced values from ``min`` to ``max``."""

    min: float
    max: float
    values: int
    format: str = "%g"

    @property
    def bits(self) -> int:
        return self.values.bit_length() - 1

    @property
    def step(self) -> float:
        return (self.max - self.min) / (self.values - 1)


@dataclass
class Template:
    """The gene template: genes occupy consecutive bit fields, most significant bit first."""

    genes: list[Gene] = field(default_factory=list)

    @property
    def length(self) -> int:
        return sum(g.bits for g in self.genes)

    def decode(self, bits: np.ndarray, gray: bool) -> np.ndarray:
        """Gene values of each row of ``bits`` (``(n, length)`` of 0/1) -> ``(n, n_genes)``."""
        bits = np.atleast_2d(bits)
        out = np.empty((bits.shape[0], len(self.genes)))
        pos = 0
        for k, g in enumerate(self.genes):
            seg = bits[:, pos : pos + g.bits]
            pos += g.bits
            if gray:
                seg = gray_to_binary(seg)
            weights = np.left_shift(np.int64(1), np.arange(g.bits - 1, -1, -1, dtype=np.int64))
            ints = seg.astype(np.int64) @ weights
            out[:, k] = g.min + ints * g.step
        return out


def gray_to_binary(g: np.ndarray) -> np.ndarray:
    """Gray decoding along the last axis: ``b0 = g0``, ``b_i = b_(i-1) XOR g_i``."""
    g = np.asarray(g, dtype=np.uint8)
    return np.bitwise_xor.accumulate(g, axis=-1) if g.shape[-1] else g.copy()


# --------------------------------------------------------------------------------------------
# random numbers
# --------------------------------------------------------------------------------------------


class Randu:
    """The RANDU generator of the original: ``seed = seed * 65539 mod 2**31``."""

    __slots__ = ("seed",)

    def __init__(self, seed: int = DEFAULT_SEED):
        self.seed = int(seed)

    def rand(self) -> float:
        self.seed = (self.seed * 65539) & _MASK31
        return self.seed * 0.4656612875e-9

    def randint(self, lo: int, hi: int) -> int:
        return int(lo + (hi - lo + 1) * self.rand())


def seed_to_randu(seed: int) -> int:
    """RANDU seed for the harness's integer seed: 0 -> 123456789, else an odd 31-bit number."""
    seed = int(seed)
    if seed == 0:
        return DEFAULT_SEED
    z = (seed + 0x9E3779B97F4A7C15) & _MASK64
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & _MASK64
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & _MASK64
    z ^= z >> 31
    return (z >> 33) | 1


# --------------------------------------------------------------------------------------------
# the engine
# --------------------------------------------------------------------------------------------


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


# --------------------------------------------------------------------------------------------
# file formats
# --------------------------------------------------------------------------------------------


# The original's printf formats are kept verbatim (Python's % follows C printf for these).
_OUT_FORMAT = "%5d %5d %2d %2d %5.3f %.6e %.6e %.6e %.6e"
_MIN_COST_FORMAT = "  %11.4e "
_MIN_GEN_FORMAT = " %4d  %4d"


def format_out_line(gen, trials, lost, conv, bias, online, offline, best, avg) -> str:
    return _OUT_FORMAT % (
        gen,
        trials,
        lost,
        conv,
        bias,
        online,
        offline,
        best,
        avg,
    )


def format_min_lines(saved: list[SavedEntry], template: Template | None, gray: bool) -> list[str]:
    lines = []
    for e in saved:
        if template is not None:
            vals = template.decode(e.bits[None, :], gray)[0]
            head = "".join(g.format % v for g, v in zip(template.genes, vals.tolist(), strict=True))
        else:
            head = "".join(str(int(b)) for b in e.bits)
        lines.append(head + _MIN_COST_FORMAT % e.cost + _MIN_GEN_FORMAT % (e.gen, e.trial))
    return lines


def write_out(path, lines: list[str]) -> None:
    Path(path).write_text("".join(line + "\n" for line in lines))


def write_min(path, saved: list[SavedEntry], template: Template | None, gray: bool) -> None:
    Path(path).write_text("".join(line + "\n" for line in format_min_lines(saved, template, gray)))


def _read_lines(path) -> list[str]:
    try:
        return Path(path).read_text().splitlines()
    except OSError as exc:
        raise GenesisInputError(f"{path}: cannot read: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise GenesisInputError(f"{path}: not a text file") from None


def read_settings(path) -> tuple[Settings, dict[str, int]]:
    """Read an ``in`` file (16 ``Label = value`` lines). Returns the settings and the line number
    of each field (for messages)."""
    lines = _read_lines(path)
    values: dict = {}
    where: dict[str, int] = {}
    fl = list(fields(Settings))
    n = 0
    for f in fl:
        label = _LABELS[f.name]
        while n < len(lines) and not lines[n].strip():
            n += 1
        if n >= len(lines):
            raise GenesisInputError(f"{path}: line {n + 1}: missing '{label} = ...' (file ends early)")
        text = lines[n]
        n += 1
        left, eq, right = text.partition("=")
        if not eq or " ".join(left.split()).lower() != label.lower():
            raise GenesisInputError(f"{path}: line {n}: expected '{label} = ...', got {text.strip()!r}")
        right = right.strip()
        kind = f.type if isinstance(f.type, str) else f.type.__name__
        try:
            if kind == "int":
                val = int(right)
            elif kind == "float":
                val = float(right)
                if not math.isfinite(val):
                    raise ValueError
            else:
                if not right or len(right.split()) != 1:
                    raise ValueError
                val = right
        except ValueError:
            want = {"int": "an integer", "float": "a number"}.get(kind, "one word of option letters")
            raise GenesisInputError(f"{path}: line {n}: {label}: expected {want}, got {right!r}") from None
        values[f.name] = val
        where[f.name] = n
    settings = Settings(**values)
    bad = settings.check()
    if bad:
        name, msg = bad[0]
        raise GenesisInputError(f"{path}: line {where[name]}: {_LABELS[name]}: {msg}")
    return settings, where


_FMT_RE = re.compile(r"^[^%]*%[-+ #0]*\d*(?:\.\d+)?[lL]?[eEfFgG][^%]*$")


def read_template(path) -> Template:
    """Read a ``template`` file: ``genes: n`` then per gene ``gene k``, ``min:``, ``max:``,
    ``values:``, ``format:`` lines (blank lines ignored)."""
    raw = _read_lines(path)
    lines = [(k + 1, t.strip()) for k, t in enumerate(raw) if t.strip()]
    pos = 0

    def take(key: str):
        nonlocal pos
        if pos >= len(lines):
            raise GenesisInputError(f"{path}: line {len(raw) + 1}: missing '{key}' (file ends early)")
        no, text = lines[pos]
        pos += 1
        k, colon, v = text.partition(":")
        if key == "gene":
            if text.split()[0].lower() != "gene":
                raise GenesisInputError(f"{path}: line {no}: expected 'gene <k>', got {text!r}")
            return no, text
        if not colon or k.strip().lower() != key:
            raise GenesisInputError(f"{path}: line {no}: expected '{key}: ...', got {text!r}")
        return no, v.strip()

    no, v = take("genes")
    try:
        n_genes = int(v)
        if n_genes < 1:
            raise ValueError
    except ValueError:
        raise GenesisInputError(f"{path}: line {no}: genes: expected a positive integer, got {v!r}") from None
    genes = []
    for _ in range(n_genes):
        take("gene")
        nums = []
        for key in ("min", "max"):
            no, v = take(key)
            try:
                x = float(v)
                if not math.isfinite(x):
                    raise ValueError
            except ValueError:
                raise GenesisInputError(f"{path}: line {no}: {key}: expected a number, got {v!r}") from None
            nums.append(x)
        no, v = take("values")
        try:
            values = int(v)
            if values < 2 or values & (values - 1):
                raise ValueError
        except ValueError:
            raise GenesisInputError(f"{path}: line {no}: values: expected a power of two >= 2, got {v!r}") from None
        no, fmt = take("format")
        fmt = re.sub(r"%([-+ #0]*\d*(?:\.\d+)?)[lL]", r"%\1", fmt)
        if not _FMT_RE.match(fmt):
            raise GenesisInputError(
                f"{path}: line {no}: format: expected one printf float conversion such as %7.2f, got {fmt!r}"
            )
        genes.append(Gene(nums[0], nums[1], values, fmt))
    if pos < len(lines):
        no, text = lines[pos]
        raise GenesisInputError(f"{path}: line {no}: unexpected text after {n_genes} genes: {text!r}")
    return Template(genes)


# --------------------------------------------------------------------------------------------
# the runner
# --------------------------------------------------------------------------------------------


def _load_objective(spec: str) -> Callable[[np.ndarray], np.ndarray]:
    mod_name, colon, func_name = spec.partition(":")
    if not colon or not mod_name or not func_name:
        raise GenesisInputError(f"objective {spec!r}: expected module:function")
    if "" not in sys.path and os.getcwd() not in sys.path:
        sys.path.insert(0, os.getcwd())
    try:
        func = getattr(importlib.import_module(mod_name), func_name)
    except Exception as exc:  # noqa: BLE001 - any import failure is bad input
        raise GenesisInputError(f"objective {spec!r}: cannot load: {type(exc).__name__}: {exc}") from None
    if not callable(func):
        raise GenesisInputError(f"objective {spec!r}: not callable")

    def batch(X: np.ndarray) -> np.ndarray:
        return np.array([float(func(np.array(x))) for x in X], dtype=float)

    return batch


def run_dir(
    directory,
    objective: Callable[[np.ndarray], np.ndarray] | None = None,
    out_dir=None,
) -> RunResult:
    """Read ``directory/in`` and ``directory/template``, run, write ``out`` and ``min``.

    ``objective`` maps decoded rows ``(n, n_genes)`` to costs; default :func:`sum_of_squares`.
    The files go into ``out_dir`` (created if missing) when given, else into ``directory`` as the
    original does; ``out`` only with option ``c`` or ``C``. Their paths are in ``result.files``."""
    d = Path(directory)
    settings, where = read_settings(d / "in")
    template = read_template(d / "template") if settings.flag("f") else None
    if template is not None and template.length != settings.structure_length:
        raise GenesisInputError(
            f"{d / 'in'}: line {where['structure_length']}: Structure Length: "
            f"{settings.structure_length}, but the genes of {d / 'template'} take {template.length} bits"
        )
    dest = d if out_dir is None else Path(out_dir)
    try:
        dest.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise GenesisInputError(f"{dest}: cannot create the output folder: {exc.strerror or exc}") from None
    engine = Genesis(settings, template, objective or sum_of_squares)
    result = engine.run()
    files = []
    try:
        if settings.flag("c") or settings.flag("C"):
            files.append(dest / "out")
            write_out(files[-1], result.out_lines)
        files.append(dest / "min")
        write_min(files[-1], result.saved, template, engine.gray)
    except OSError as exc:
        raise GenesisInputError(f"{files[-1]}: cannot write: {exc.strerror or exc}") from None
    result.files = files
    return result


_USAGE = "usage: python -m plugins.genesis DIR [module:function] [--out-dir OUTDIR]"
_HELP = f"""{_USAGE}

Run the GENESIS 5.0 clone on DIR/in (settings) and DIR/template (genes, with option f), in the
original program's file formats, and write the original's out (option c or C) and min files into
DIR, or into OUTDIR with --out-dir (-o). The objective is the sum of squares of the genes unless
module:function is given (imported from the current directory or PYTHONPATH; it receives the
genes as a 1-D numpy array and returns a float). Example: python -m plugins.genesis plugins/genesis_example
"""


def _parse_args(argv: list[str]) -> tuple[list[str], str | None] | None:
    """``(positionals, out_dir)``, or None when the arguments do not fit the usage."""
    pos: list[str] = []
    out_dir = None
    k = 0
    while k < len(argv):
        a = argv[k]
        if a in ("-o", "--out-dir"):
            if k + 1 >= len(argv) or out_dir is not None:
                return None
            out_dir = argv[k + 1]
            k += 2
            continue
        if a.startswith("--out-dir="):
            if out_dir is not None:
                return None
            out_dir = a.partition("=")[2]
        elif a.startswith("-") and a != "-":
            return None
        else:
            pos.append(a)
        k += 1
    if len(pos) not in (1, 2) or out_dir == "":
        return None
    return pos, out_dir


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if any(a in ("-h", "--help") for a in argv):
        print(_HELP, end="")
        return 0
    parsed = _parse_args(argv)
    if parsed is None:
        print(_USAGE, file=sys.stderr)
        return 2
    (directory, *rest), out_dir = parsed
    try:
        objective = _load_objective(rest[0]) if rest else None
        if not Path(directory).is_dir():
            raise GenesisInputError(f"{directory}: not a directory")
        res = run_dir(directory, objective, out_dir)
    except UserError as exc:
        print(f"genesis: {exc}", file=sys.stderr)
        return 2
    print(
        f"genesis: {res.generations} generations, {res.trials} trials, best {res.best_cost:.6e} "
        f"(stopped: {res.stop_reason}); wrote {', '.join(str(f) for f in res.files)}"
    )
    return 0


# --------------------------------------------------------------------------------------------
# the plugin
# --------------------------------------------------------------------------------------------


def minimize(
    problem,
    *,
    seed: int,
    population_size: int = 100,
    bits_per_gene: int = 11,
    crossover_rate: float = 0.6,
    mutation_rate: float = 0.001,
    generation_gap: float = 1.0,
    scaling_window: int = 5,
    structures_saved: int = 10,
    max_gens_without_eval: int = 2,
    options: str = "acefgl",
    rank_min: float = 0.75,
    random_seed: int | None = None,
    report_interval: int = 100,
):
    """GENESIS 5.0 on a :class:`benchmark.core.problem.SearchProblem` (cost minimised).

    Total Trials is ``problem.budget``; genes span ``[lower, upper]`` with ``2**bits_per_gene``
    values each (option ``f`` is implied, ``g`` selects Gray code). ``report_interval`` only sets
    when the convergence statistics of option ``c`` are taken (and so when the ``Bias > 0.99``
    stop can happen), as in the original. Each generation's marked structures are evaluated in
    one ``problem.evaluate`` call; rows past the budget are trimmed by the harness (they cost
    +inf, i.e. :data:`INF_COST`, and end the run). Returns the best decoded vector found,
    ``nit`` = generations evaluated including generation 0, and a message with the stop reason
    and the RANDU seed used."""
    from benchmark.core.problem import OptimizerOutput

    def key(name):
        return f"optimizer.plugin.{name}"

    if int(bits_per_gene) < 1 or int(bits_per_gene) > 30:
        raise ConfigError(f"{key('bits_per_gene')}: must be in 1..30, got {bits_per_gene}")
    if "M" in str(options):
        raise ConfigError(f"{key('options')}: option 'M' (maximise) makes no sense for a cost; remove it")
    rseed = seed_to_randu(seed) if random_seed is None else int(random_seed)
    n_var = problem.n_var
    opts = str(options) if "f" in str(options) else str(options) + "f"
    settings = Settings(
        experiments=1,
        total_trials=int(problem.budget),
        population_size=int(population_size),
        structure_length=n_var * int(bits_per_gene),
        crossover_rate=float(crossover_rate),
        mutation_rate=float(mutation_rate),
        generation_gap=float(generation_gap),
        scaling_window=int(scaling_window),
        report_interval=int(report_interval),
        structures_saved=int(structures_saved),
        max_gens_without_eval=int(max_gens_without_eval),
        options=opts,
        random_seed=rseed,
        rank_min=float(rank_min),
    )
    bad = settings.check()
    if bad:
        name, msg = bad[0]
        name = "seed" if name == "random_seed" and random_seed is None else name
        raise ConfigError(f"{key(name)}: {msg}")
    values = 1 << int(bits_per_gene)
    lo, hi = problem.lower, problem.upper
    template = Template([Gene(float(a), float(b), values) for a, b in zip(lo, hi, strict=True)])
    engine = Genesis(settings, template, problem.evaluate)
    res = engine.run()
    x = template.decode(res.best_bits[None, :], engine.gray)[0] if res.best_bits is not None else None
    msg = (
        f"GENESIS: {res.generations} generations, {res.trials} trials, best {res.best_cost:.6e}; "
        f"stopped: {res.stop_reason}; RANDU seed {rseed}"
    )
    return OptimizerOutput(x=x, nit=res.generations, message=msg)


if __name__ == "__main__":
    sys.exit(main())
