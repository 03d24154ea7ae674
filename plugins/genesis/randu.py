"""RANDU, the original's random numbers, and the seed it takes from the benchmark's."""

from __future__ import annotations

from plugins.genesis.settings import _MASK31, _MASK64, DEFAULT_SEED


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
