"""Magnetic characteristics: the magnetising curve and saturable leakage paths.

All curves are isotropic: a flux-linkage vector is parallel to the current vector that drives
it, and only the magnitudes are related by a scalar curve. Magnitudes are amplitude-invariant
alpha-beta values, i.e. phase peak values (A, Wb).

Magnetising curve ``psi_m = F(|i_m|)`` (``MagnetisingCurve``), forms:

``linear``
    ``F = Lm0 i``.
``frohlich``
    Frohlich (Frohlich-Kennelly) knee plus the air-path slope ``Linf``:
    ``F = Linf i + (Lm0 - Linf) i / (1 + i/i_sat)``.
``arctan``
    ``F = Linf i + (Lm0 - Linf) i_k atan(i / i_k)``.
``table``
    A maker's tabulated curve (B-H-like), piecewise linear through normalised points
    ``(i/i_k, psi/(Lm0 i_k))`` of :data:`TABLE_SHAPE`, continued with the slope ``Linf``.
``langevin`` (held-out form)
    ``F = Linf i + (Lm0 - Linf) 3 i_k L(i/i_k)`` with the Langevin function
    ``L(x) = coth x - 1/x``: the anhysteretic magnetisation of Jiles and Atherton (J. Magn.
    Magn. Mater. 61, 1986), ``M = M_s L(H/a)``, as the iron's share of the flux.
``steel_gap`` (held-out form)
    The magnetic circuit of the machine: an air gap in series with an iron path of a
    measured electrical steel (:data:`M400_50A`). At flux density ``B`` the magnetising
    current is ``i = c (B + x mu0 H(B))`` (gap plus iron ampere-turns, ``x`` the iron path
    over the gap length) and the flux ``psi = a B`` (the classical construction of the
    no-load curve, e.g. Pyrhonen, Jokinen, Hrabovcova, Design of Rotating Electrical
    Machines, ch. 3). Tabulated at 48 flux densities (a monotone cubic through the steel's
    points), continued with the air slope beyond the last point.

Every form has the slope ``Lm0`` at zero current, so ``Lm0`` is the unsaturated magnetising
inductance a small-signal test would measure (``steel_gap``: its largest secant inductance,
the slope at zero for a steel without a Rayleigh region such as M400-50A).

Leakage characteristic ``|lambda| = g(|i|) = (L_lin + L_sat phi(|i|)) |i|`` (``LeakageCurve``):
a linear part (slot body, end windings) plus a saturable part (tooth tips, slot bridges):

``none``
    ``phi = 1``: a constant leakage ``L_lin + L_sat``.
``lorentzian``
    ``phi = 1 / (1 + (i/i_k)^2)``; a monotone flux (positive incremental inductance) needs
    ``L_lin / (L_lin + L_sat) > 1/9`` (:meth:`LeakageCurve.monotone`).
``frohlich``
    ``phi = 1 / (1 + i/i_k)``: the saturable path's flux tends to ``L_sat i_k``.
``bridge`` (held-out form)
    ``phi = tanh(i/i_k) / (i/i_k)``: the iron bridge of a closed rotor slot, whose flux is
    limited by the bridge's cross-section (``L_sat i_k`` = saturation flux density times the
    bridge area); it saturates sharply at a low current, its incremental inductance
    ``L_lin + L_sat sech^2(i/i_k)`` stays positive.

The numba functions take a small float array so that the integrator can hold them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

MAG_FORMS = ("linear", "frohlich", "arctan", "table", "langevin", "steel_gap")
LEAK_FORMS = ("none", "lorentzian", "frohlich", "bridge")
MU0 = 4e-7 * math.pi

#: Normalised magnetising table (x = i/i_k, y = psi/(Lm0 i_k)): slope 1 up to 0.5, then
#: falling slopes, like the no-load curve of a small cage motor (concave, so Newton on it
#: converges monotonically). Beyond the last point the slope is Linf/Lm0.
TABLE_SHAPE = np.array([[0.0, 0.0], [0.5, 0.5], [0.8, 0.78], [1.0, 0.93], [1.3, 1.08], [1.7, 1.2],
                        [2.3, 1.31], [3.2, 1.41], [5.0, 1.53], [8.0, 1.65]])
PRM_LEN = 2 * len(TABLE_SHAPE) + 4

#: Magnetisation curve of the non-oriented electrical steel M400-50A (0.5 mm laminations):
#: ``B`` (T) against ``H`` (A/m), as tabulated in the pyleecan material library (Eomys,
#: Apache-2.0, ``Data/Material/M400-50A.json``), every second point up to 1.5 T.
M400_50A = np.array([[0.0, 0.0], [0.5, 100.0], [0.7, 150.0], [0.8, 180.0], [0.9, 200.0], [1.0, 250.0],
                     [1.1, 350.0], [1.2, 550.0], [1.3, 950.0], [1.4, 1550.0], [1.5, 2450.0], [1.6, 4100.0],
                     [1.7, 6700.0], [1.8, 10750.0], [1.9, 19500.0], [2.0, 33000.0], [2.1, 57000.0],
                     [2.2, 96000.0], [2.3, 170000.0]])
STEEL_POINTS = 48


def steel_field(bh: np.ndarray, B) -> np.ndarray:
    """Field strength ``H`` (A/m) of the steel ``bh`` (rows ``B`` T, ``H`` A/m) at flux
    density ``B`` (T): a monotone cubic (PCHIP) through its points."""
    from scipy.interpolate import PchipInterpolator

    return PchipInterpolator(bh[:, 0], bh[:, 1])(B)


def steel_table(bh: np.ndarray, iron_ratio: float, points: int = STEEL_POINTS) -> np.ndarray:
    """Normalised no-load curve of a gap in series with an iron path of the steel ``bh``,
    ``iron_ratio`` = iron path over gap length: rows ``(B + x mu0 H(B), B)`` (T) at
    ``points`` flux densities up to the steel's last point."""
    B = np.linspace(0.0, bh[-1, 0], points)
    return np.column_stack([B + iron_ratio * MU0 * steel_field(bh, B), B])


@dataclass(frozen=True)
class MagnetisingCurve:
    """Magnetising flux linkage as a function of magnetising current (peak values).

    Parameters
    ----------
    form : one of :data:`MAG_FORMS`.
    Lm0 : unsaturated (small-signal) magnetising inductance, H.
    knee : knee current, A peak (``i_sat`` of frohlich, ``i_k`` of arctan, table and
        langevin; ``steel_gap``: the current at the reference flux).
    Linf : slope in deep saturation, H (the air-path inductance), ``0 < Linf < Lm0``.
    table : ``steel_gap`` only: its points ``((i, ...), (psi, ...))``, A and Wb peak.
    """

    form: str = "linear"
    Lm0: float = 0.1
    knee: float = 1.0
    Linf: float = 0.0
    table: tuple = ()

    def __post_init__(self):
        if self.form not in MAG_FORMS:
            raise ValueError(f"magnetising curve form must be one of {MAG_FORMS}, got {self.form!r}")
        if not self.Lm0 > 0:
            raise ValueError(f"Lm0 must be > 0 H, got {self.Lm0}")
        if self.form != "linear" and not (self.knee > 0 and 0 < self.Linf < self.Lm0):
            raise ValueError(f"saturating curve needs knee > 0 and 0 < Linf < Lm0, got knee={self.knee}, "
                             f"Linf={self.Linf}, Lm0={self.Lm0}")

    def params(self) -> np.ndarray:
        """Float array read by :func:`mag_flux`: ``[code, Lm0, knee, Linf, x..., y...]``."""
        if self.form == "steel_gap":
            xs, ys = (np.asarray(v, float) for v in self.table)
            return np.concatenate([[MAG_FORMS.index("table"), self.Lm0, self.knee, self.Linf], xs, ys])
        prm = np.zeros(PRM_LEN)
        prm[0] = MAG_FORMS.index(self.form)
        prm[1], prm[2], prm[3] = self.Lm0, self.knee, self.Linf
        n = len(TABLE_SHAPE)
        prm[4:4 + n] = TABLE_SHAPE[:, 0] * self.knee
        prm[4 + n:4 + 2 * n] = TABLE_SHAPE[:, 1] * self.Lm0 * self.knee
        return prm

    def flux(self, i) -> np.ndarray:
        """Flux magnitude (Wb) for current magnitude(s) ``i`` (A)."""
        prm = self.params()
        return np.array([mag_flux(prm, float(x))[0] for x in np.atleast_1d(np.abs(i))])

    def secant(self, i) -> np.ndarray:
        """Secant inductance ``F(i)/i`` (H); ``Lm0`` at zero."""
        i = np.atleast_1d(np.abs(np.asarray(i, float)))
        f = self.flux(i)
        return np.where(i > 0, f / np.where(i > 0, i, 1.0), self.Lm0)

    @classmethod
    def with_drop(cls, form: str, Lm0: float, psi_ref: float, drop: float, linf_ratio: float = 0.05):
        """The curve of ``form`` whose secant inductance at the flux ``psi_ref`` (Wb peak) is
        ``(1 - drop) Lm0``; the knee current is solved for. ``linf_ratio`` = Linf/Lm0."""
        from scipy.optimize import brentq

        if form == "linear":
            return cls("linear", Lm0)
        if form == "steel_gap":
            return cls.steel_gap(Lm0, psi_ref, drop)
        if not 0 < drop < 1 - linf_ratio:
            raise ValueError(f"drop must be in (0, {1 - linf_ratio}), got {drop}")
        i_ref = psi_ref / ((1 - drop) * Lm0)

        def miss(log_knee):
            return cls(form, Lm0, math.exp(log_knee), linf_ratio * Lm0).flux(i_ref)[0] - psi_ref

        log_knee = brentq(miss, math.log(i_ref) - 12, math.log(i_ref) + 12, xtol=1e-13)
        return cls(form, Lm0, math.exp(log_knee), linf_ratio * Lm0)

    @classmethod
    def steel_gap(cls, Lm0: float, psi_ref: float, drop: float, iron_ratio: float, bh: np.ndarray = M400_50A):
        """The gap-plus-iron curve (form ``steel_gap``) with the iron path ``iron_ratio`` times
        the gap length, whose secant inductance at the flux ``psi_ref`` (Wb peak) is
        ``(1 - drop) Lm0``, ``Lm0`` its largest secant inductance (where the steel's
        permeability ``B/H`` peaks). The flux density at ``psi_ref`` is solved for.

        With ``p(B) = mu0 H(B)/B`` the secant is ``~ 1/(1 + x p(B))``, so ``psi_ref`` sits where
        ``p(B) = ((1 + x min p)/(1 - drop) - 1)/x``, on the rising branch of ``p``. A steel
        whose permeability rises from low fields (a Rayleigh region, as M800-50A's) gives a
        curve whose slope at zero is below ``Lm0``; for M400-50A it is ``Lm0``."""
        from scipy.optimize import brentq

        x = float(iron_ratio)
        B = steel_table(bh, 0.0)[1:, 1]
        p = MU0 * steel_field(bh, B) / B
        k = int(np.argmin(p))
        target = ((1 + x * p[k]) / (1 - drop) - 1) / x
        if not (0 < drop < 1 and p[k] < target < p[-1]):
            raise ValueError(f"steel_gap: a drop of {drop} with an iron path {x} x the gap is beyond the steel's "
                             f"table (up to {bh[-1, 0]} T)")
        b_ref = brentq(lambda b: MU0 * float(steel_field(bh, b)) / b - target, B[k], B[-1], xtol=1e-12)
        pts = steel_table(bh, x)
        a = psi_ref / b_ref  # Wb per T
        c = a / (Lm0 * (1 + x * p[k]))  # A per T
        i, psi = c * pts[:, 0], a * pts[:, 1]
        Linf = a / (c * (1 + x))
        knee = float(np.interp(psi_ref, psi, i))
        return cls("steel_gap", Lm0, knee, Linf, (tuple(map(float, i)), tuple(map(float, psi))))


@dataclass(frozen=True)
class LeakageCurve:
    """Leakage flux magnitude ``(L_lin + L_sat phi(|i|)) |i|`` of one saturable leakage path.

    Parameters
    ----------
    form : one of :data:`LEAK_FORMS`.
    L_lin : non-saturating part, H.
    L_sat : saturable part (its value at zero current), H.
    knee : knee current ``i_k``, A peak.
    """

    form: str = "none"
    L_lin: float = 0.0
    L_sat: float = 0.0
    knee: float = 1.0

    def __post_init__(self):
        if self.form not in LEAK_FORMS:
            raise ValueError(f"leakage curve form must be one of {LEAK_FORMS}, got {self.form!r}")
        if self.L_lin < 0 or self.L_sat < 0 or not self.knee > 0:
            raise ValueError("leakage curve needs L_lin >= 0, L_sat >= 0, knee > 0")

    def monotone(self, series: float = 0.0) -> bool:
        """True when this path plus a linear ``series`` inductance (H) has a rising flux for
        all currents (positive incremental inductance); the lorentzian form needs
        ``(L_lin + series) > (L_lin + series + L_sat)/9``."""
        if self.form != "lorentzian" or self.L_sat == 0:  # frohlich, bridge: dg/dr > L_lin always
            return self.L_lin + series > 0 or self.L_sat > 0
        return self.L_lin + series > (self.L_lin + series + self.L_sat) / 9

    @property
    def L0(self) -> float:
        """Unsaturated leakage inductance, H."""
        return self.L_lin + self.L_sat

    def params(self) -> np.ndarray:
        """``[code, L_lin, L_sat, knee]`` for :func:`leak_flux`."""
        return np.array([LEAK_FORMS.index(self.form), self.L_lin, self.L_sat, self.knee], float)

    def inductance(self, i) -> np.ndarray:
        """Secant leakage inductance (H) at current magnitude(s) ``i`` (A)."""
        prm = self.params()
        i = np.atleast_1d(np.abs(np.asarray(i, float)))
        return np.array([leak_flux(prm, x)[0] / x if x > 0 else self.L0 for x in i])

    @classmethod
    def with_ratio(cls, form: str, L0: float, i_low: float, i_high: float, ratio: float, lin_share: float):
        """The curve of ``form`` with ``L(i_high)/L(i_low) = ratio`` and linear share
        ``lin_share = L_lin/L0``. The knee current is solved for on the branch where the
        path is barely saturated at ``i_low`` (knee above the one of the deepest ratio);
        a ratio below the deepest reachable one gives that deepest one."""
        from scipy.optimize import brentq

        if form == "none":
            return cls("none", L0, 0.0, 1.0)

        def curve(log_knee):
            return cls(form, lin_share * L0, (1 - lin_share) * L0, math.exp(log_knee))

        def miss(log_knee):
            lo, hi = curve(log_knee).inductance([i_low, i_high])
            return hi / lo - ratio

        grid = np.linspace(math.log(i_low) - 3, math.log(i_high) + 8, 400)
        vals = np.array([miss(g) for g in grid])
        k = int(np.argmin(vals))
        if vals[k] >= 0:
            return curve(grid[k])
        return curve(brentq(miss, grid[k], grid[-1], xtol=1e-13))


@njit(cache=True)
def _langevin(x):
    """Langevin function ``coth x - 1/x`` and its derivative ``1/x^2 - 1/sinh^2 x``, ``x >= 0``
    (series below 0.05, asymptotes above 30)."""
    if x < 0.05:
        x2 = x * x
        return x * (1.0 / 3.0 - x2 / 45.0 + 2.0 * x2 * x2 / 945.0), 1.0 / 3.0 - x2 / 15.0 + 2.0 * x2 * x2 / 189.0
    if x > 30.0:
        return 1.0 - 1.0 / x, 1.0 / (x * x)
    s = math.sinh(x)
    return math.cosh(x) / s - 1.0 / x, 1.0 / (x * x) - 1.0 / (s * s)


@njit(cache=True)
def mag_flux(prm, r):
    """Magnetising flux magnitude ``F(r)`` and slope ``dF/dr`` at current magnitude ``r >= 0``."""
    code = int(prm[0])
    Lm0, knee, Linf = prm[1], prm[2], prm[3]
    if code == 0:
        return Lm0 * r, Lm0
    if code == 1:
        d = 1.0 + r / knee
        return Linf * r + (Lm0 - Linf) * r / d, Linf + (Lm0 - Linf) / (d * d)
    if code == 2:
        x = r / knee
        return Linf * r + (Lm0 - Linf) * knee * math.atan(x), Linf + (Lm0 - Linf) / (1.0 + x * x)
    if code == 4:
        L, dL = _langevin(r / knee)
        return Linf * r + (Lm0 - Linf) * 3.0 * knee * L, Linf + (Lm0 - Linf) * 3.0 * dL
    n = (prm.shape[0] - 4) // 2
    xs = prm[4:4 + n]
    ys = prm[4 + n:4 + 2 * n]
    if r >= xs[n - 1]:
        return ys[n - 1] + Linf * (r - xs[n - 1]), Linf
    k = 0
    while r > xs[k + 1]:
        k += 1
    slope = (ys[k + 1] - ys[k]) / (xs[k + 1] - xs[k])
    return ys[k] + slope * (r - xs[k]), slope


@njit(cache=True)
def leak_flux(prm, r):
    """Leakage flux magnitude ``g(r)`` and incremental inductance ``dg/dr``."""
    code = int(prm[0])
    lin, sat, knee = prm[1], prm[2], prm[3]
    if code == 0 or sat == 0.0:
        return (lin + sat) * r, lin + sat
    x = r / knee
    if code == 1:
        q = 1.0 + x * x
        return (lin + sat / q) * r, lin + sat * (1.0 - x * x) / (q * q)
    if code == 3:
        th = math.tanh(x)
        return lin * r + sat * knee * th, lin + sat * (1.0 - th * th)
    q = 1.0 + x
    return (lin + sat / q) * r, lin + sat / (q * q)


@njit(cache=True)
def leak_inverse(prm, y, offset_gain, r0):
    """Solve ``r + offset_gain * g(r) = y`` for ``r >= 0`` when ``offset_gain > 0`` (the rotor
    form), or ``g(r) = y`` when ``offset_gain == 0`` (the stator form). Returns ``(r, dr/dy)``.

    Safeguarded Newton in the bracket that the bounds ``lin <= g(r)/r <= lin + sat`` give,
    started from ``r0`` (the previous solution) when it lies in the bracket.
    """
    lin, sat = prm[1], prm[2]
    if int(prm[0]) == 0 or sat == 0.0:
        total = lin + sat
        if offset_gain > 0.0:
            return y / (1.0 + offset_gain * total), 1.0 / (1.0 + offset_gain * total)
        return y / total, 1.0 / total
    if offset_gain > 0.0:
        lo = y / (1.0 + offset_gain * (lin + sat))
        hi = y / (1.0 + offset_gain * lin)
    else:
        lo = y / (lin + sat)
        hi = y / lin
    if y <= 0.0:
        if offset_gain > 0.0:
            return 0.0, 1.0 / (1.0 + offset_gain * (lin + sat))
        return 0.0, 1.0 / (lin + sat)
    if hi - lo <= 1e-15 * hi:
        g, dg = leak_flux(prm, lo)
        d = 1.0 + offset_gain * dg if offset_gain > 0.0 else dg
        return lo, 1.0 / d
    r = r0 if lo < r0 < hi else 0.5 * (lo + hi)
    d = 1.0
    for _ in range(60):
        g, dg = leak_flux(prm, r)
        if offset_gain > 0.0:
            f = r + offset_gain * g - y
            d = 1.0 + offset_gain * dg
        else:
            f = g - y
            d = dg
        if f > 0.0:
            hi = r
        else:
            lo = r
        step = f / d
        r_new = r - step
        if not (lo < r_new < hi):
            r_new = 0.5 * (lo + hi)
        if abs(r_new - r) <= 1e-14 * (1.0 + r):
            r = r_new
            break
        r = r_new
    g, dg = leak_flux(prm, r)
    d = 1.0 + offset_gain * dg if offset_gain > 0.0 else dg
    return r, 1.0 / d
