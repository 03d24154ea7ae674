"""The rotor cage as a set of short-circuited loops linked by the main flux.

A cage rotor is ``n`` loops (bar slices of a deep bar, or the two cages of a double cage),
all referred to the stator and all linked by the magnetising flux ``psi_m``. Loop ``k`` has
the resistance ``R_k`` and links, besides ``psi_m``, the slot leakage flux of the layers above
it: with layer permeances ``l_1 .. l_n`` (top = next to the air gap), the leakage matrix is
``L[j, k] = sum_{m <= min(j, k)} l_m``, so the bottom loop links the most leakage and, at high
rotor frequency, the current crowds into the top loop (skin effect). A leakage path carrying
the total rotor current (end ring, slot opening, tooth tips) is in series with all loops: the
``common`` :class:`~synthetic.independent.curves.LeakageCurve`, the path that saturates.

Port impedance at rotor angular frequency ``w`` (rad/s), per phase:
``Z(w) = 1 / (1' (R + jwL)^-1 1) + jw L_common``. At low rotor frequency
``Z = R_eq + jw L_eq + O(w^2)`` with ``R_eq = 1/y0``, ``L_eq = y1/y0^2 + L_common``,
``y0 = 1' R^-1 1``, ``y1 = 1' R^-1 L R^-1 1``: these are the single-cage ``Rr``, ``Llr`` a
low-slip (steady running) test sees; the identification's truth uses them.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from synthetic.independent.curves import LeakageCurve

#: Shapes for :func:`design`: loop resistances (normalised to a parallel value of 1) and layer
#: permeances (normalised). ``double_cage``: outer (top) cage of high resistance (brass or thin
#: bars) linking little slot leakage, inner cage of low resistance behind a leakage slit.
#: ``deep_bar``: equal slices of one rectangular bar. ``tapered_bar`` (held-out form): equal
#: slices of a trapezoidal bar whose width goes linearly from ``b_top`` to ``taper * b_top``;
#: a slice of width ``b`` has the resistance ``~ 1/b`` and its layer the slot-leakage
#: permeance ``~ 1/b`` (the multilayer method of Babb and Williams, AIEE Trans. 70, 1951,
#: for bars of any shape; see also Boldea and Nasar, The Induction Machine Handbook,
#: the chapter on skin effect). ``taper < 1``: the rotor slot of parallel-sided teeth,
#: narrowing towards the shaft; ``taper > 1``: a bottle-shaped bar, wide at the bottom.
SHAPES = ("double_cage", "deep_bar", "tapered_bar")


def ladder_matrix(layers) -> np.ndarray:
    """Leakage matrix ``L[j,k] = sum_{m <= min(j,k)} l_m`` from layer permeances (H)."""
    layers = np.asarray(layers, float)
    c = np.cumsum(layers)
    n = len(layers)
    idx = np.minimum.outer(np.arange(n), np.arange(n))
    return c[idx]


@dataclass(frozen=True)
class RotorCage:
    """Rotor loops referred to the stator (amplitude-invariant, per phase).

    Parameters
    ----------
    R : loop resistances, ohm, at the machine's reference temperature.
    L : loop leakage matrix (n x n, symmetric positive definite), H.
    common : leakage path carrying the total rotor current (may saturate), H.
    """

    R: tuple
    L: tuple
    common: LeakageCurve = field(default_factory=lambda: LeakageCurve("none", 0.0, 0.0))

    def __post_init__(self):
        R = np.asarray(self.R, float)
        L = np.asarray(self.L, float)
        if R.ndim != 1 or L.shape != (len(R), len(R)) or np.any(R <= 0):
            raise ValueError("rotor: R must be n positive resistances and L an n x n matrix")
        if not np.allclose(L, L.T) or np.any(np.linalg.eigvalsh(L) <= 0):
            raise ValueError("rotor: the leakage matrix must be symmetric positive definite")

    @property
    def n(self) -> int:
        return len(self.R)

    @property
    def R_array(self) -> np.ndarray:
        return np.asarray(self.R, float)

    @property
    def L_array(self) -> np.ndarray:
        return np.asarray(self.L, float)

    @classmethod
    def single(cls, Rr: float, Llr: float) -> RotorCage:
        """A single cage: one loop of resistance ``Rr`` (ohm) and leakage ``Llr`` (H)."""
        return cls((float(Rr),), ((float(Llr),),))

    def impedance(self, w) -> np.ndarray:
        """Port impedance (ohm) at rotor angular frequency ``w`` (rad/s), unsaturated."""
        w = np.atleast_1d(np.asarray(w, float))
        ones = np.ones(self.n)
        out = np.empty(len(w), complex)
        for k, wk in enumerate(w):
            y = ones @ np.linalg.solve(np.diag(self.R_array) + 1j * wk * self.L_array, ones)
            out[k] = 1.0 / y + 1j * wk * self.common.L0
        return out

    def low_slip(self) -> tuple[float, float]:
        """``(R_eq, L_eq)``: the single-cage resistance (ohm) and leakage (H) at rotor
        frequency -> 0, common path unsaturated."""
        Rinv = 1.0 / self.R_array
        y0 = Rinv.sum()
        y1 = Rinv @ self.L_array @ Rinv
        return 1.0 / y0, y1 / y0**2 + self.common.L0

    def resistance_ratio(self, w: float) -> float:
        """Rotor resistance at rotor angular frequency ``w`` over its low-slip value."""
        return float(self.impedance(w)[0].real / self.low_slip()[0])

    def scaled_resistance(self, factor: float) -> RotorCage:
        return replace(self, R=tuple(float(r) * factor for r in self.R))


def _shape(kind: str, n: int, taper: float = 1.0):
    if kind == "double_cage":
        r = np.array([6.0, 1.2])
        layers = np.array([0.1, 1.0])
    elif kind in ("deep_bar", "tapered_bar"):
        if n < 3:
            raise ValueError(f"a deep bar needs at least 3 slices, got {n}")
        width = np.linspace(1.0, taper, n) if kind == "tapered_bar" else np.ones(n)
        r = float(n) / width
        layers = 1.0 / width
    else:
        raise ValueError(f"rotor shape must be one of {SHAPES}, got {kind!r}")
    return r, ladder_matrix(layers)


def design(kind: str, Rr: float, Llr: float, w: float, ratio: float, n: int = 4,
           max_growth: float = 2.5, taper: float = 1.0) -> tuple[RotorCage, float]:
    """A multi-loop rotor with the low-slip resistance ``Rr`` (ohm), the resistance ratio
    ``R(w)/R(0)`` at rotor angular frequency ``w`` (rad/s; the supply's, i.e. at standstill)
    and, when possible, the low-slip leakage ``Llr`` (H).

    The loop resistances are the shape's scaled to give ``Rr``; the ladder leakage is the
    shape's scaled by ``s``, found by bisection for the ratio; the rest of ``Llr`` goes to the
    common path. When even all of ``Llr`` in the ladder cannot give the ratio (a motor whose
    ``w Llr/Rr`` is small), the ladder leakage grows, up to ``max_growth`` times ``Llr``: a
    rotor built for a high starting resistance has a higher running leakage too. The truth
    must then use the rotor's own low-slip values (:meth:`RotorCage.low_slip`). Returns the
    rotor and the achieved ratio. ``taper``: bottom over top width of a ``tapered_bar``.
    """
    r_shape, L_shape = _shape(kind, n, taper)
    R = Rr * r_shape / (1.0 / np.sum(1.0 / r_shape))  # parallel value = Rr

    def rotor(s: float, common: float) -> RotorCage:
        return RotorCage(tuple(R), tuple(map(tuple, s * L_shape)), LeakageCurve("none", max(common, 0.0), 0.0))

    def ratio_at(s: float) -> float:
        return rotor(s, 0.0).resistance_ratio(w)

    L_unit = rotor(1.0, 0.0).low_slip()[1]
    s_fit = Llr / L_unit
    lo, hi = 1e-6 * s_fit, s_fit
    if ratio_at(s_fit) < ratio:
        lo, hi = s_fit, max_growth * s_fit
    if ratio_at(hi) <= ratio:
        s = hi
    else:
        for _ in range(80):
            mid = np.sqrt(lo * hi)
            if ratio_at(mid) < ratio:
                lo = mid
            else:
                hi = mid
        s = np.sqrt(lo * hi)
    cage = rotor(s, Llr - s * L_unit)
    return cage, cage.resistance_ratio(w)
