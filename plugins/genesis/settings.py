"""GENESIS's settings (the ``in`` file), its template of genes and the constants of the clone."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from benchmark.core.errors import UserError

#: Finite stand-in for a +inf (or NaN) cost, see the module docstring.
INF_COST = 1e300
#: The paper's (and GENESIS's default) RANDU seed.
DEFAULT_SEED = 123456789
_MASK31 = 2147483647
_MASK64 = (1 << 64) - 1


class GenesisInputError(UserError):
    """An ``in``/``template`` file or a setting is unusable; the message names the file and line."""


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
