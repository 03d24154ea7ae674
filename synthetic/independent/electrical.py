"""Electromagnetic equations with flux linkages as states (numba).

Windings, all in the stator-fixed alpha-beta frame and referred to the stator: the stator
(flux ``psi_s``), ``n`` rotor loops (``psi_r[k]``, see :mod:`~synthetic.independent.rotor`) and
an optional stator-fixed iron-loss winding (``psi_fe``). Every winding links the magnetising
flux ``psi_m = F(|i_m|) i_m/|i_m|`` with ``i_m = i_s + sum_k i_r[k] + i_fe``:

    psi_s    = g_s(i_s) + psi_m                 (stator leakage, may saturate)
    psi_r[k] = sum_j L[k,j] i_r[j] + g_0(I_r) + psi_m     (I_r = sum_k i_r[k]; g_0 may saturate)
    psi_fe   = L_fe i_fe + psi_m

Given the fluxes, the currents follow from an algebraic solve: Newton on the 2-vector
``i_m`` (warm-started from the previous call), with the stator and common-rotor leakage
characteristics inverted by a scalar safeguarded Newton each. For linear leakages it is a
single linear step; every curve is monotone, so the solution is unique.

Voltage equations (``w_e = p w_mech``, ``J x = (-x_b, x_a)``):

    d psi_s/dt    = v_s - Rs i_s
    d psi_r[k]/dt = -R_k i_r[k] + w_e J psi_r[k]
    d psi_fe/dt   = -R_fe i_fe              (eddy currents)
    d psi_fe/dt   = -R_fe dz(i_fe, i_h)     (held-out ``steinmetz``: eddy currents and hysteresis)

``dz(i, i_h) = max(0, |i| - i_h) i/|i|`` is a vector dead zone: while the iron-loss current is
below the coercive current ``i_h`` the winding's flux is held (the domain walls are pinned),
beyond it the excess drives the eddy resistance. With the air-gap EMF ``e`` the current is
``i_h + |e|/R_fe`` along ``e``: the loss ``3/2 (i_h |e| + |e|^2/R_fe)`` is a hysteresis term
proportional to frequency plus an eddy term proportional to its square (Steinmetz 1892;
Bertotti, IEEE Trans. Magn. 24(1), 1988, without the excess term); ``i_h ~ |psi_m|^(alpha-1)``
(``psi_m`` the main flux) gives the Steinmetz exponent ``alpha`` of the hysteresis loss per
cycle. A flux left in the
winding when the supply is removed is the iron's remanence.

Torque on the rotor ``T = 3/2 p (psi_m x I_r)`` with the sign convention
``x x y = x_b y_a - x_a y_b`` written out below; without an iron-loss winding it equals
``3/2 p (psi_s x i_s)`` (the stator leakage flux is parallel to ``i_s``).
"""

from __future__ import annotations

import math

from numba import njit

from synthetic.independent.curves import leak_inverse, mag_flux

# layout of the work array filled by solve_currents
W_IS, W_IR, W_IFE, W_PSIM, W_LOOPS = 0, 2, 4, 6, 8


def work_size(n: int) -> int:
    """Length of the work array for ``n`` rotor loops: the solve's values, the loop currents,
    then the applied voltage (2), air-gap and shaft torque, stator and rotor copper loss."""
    return W_LOOPS + 2 * n + 6


@njit(cache=True)
def solve_currents(x, n, open_stator, stat, rot, mag, Linv, wv, c, inv_Lfe, im, cw):
    """Winding currents from the flux states ``x`` (see module docstring).

    ``im`` (4,) holds the magnetising current guess and receives the solution (then the
    stator and rotor leakage current magnitudes, warm starts of the inner solves); ``cw``
    receives ``i_s, I_r, i_fe, psi_m`` and the loop currents. ``open_stator`` forces
    ``i_s = 0`` (no stator current path). Returns the number of Newton iterations
    (-1 when it did not converge).
    """
    b0a = 0.0
    b0b = 0.0
    for k in range(n):
        b0a += wv[k] * x[2 + 2 * k]
        b0b += wv[k] * x[3 + 2 * k]
    fa = x[2 + 2 * n]
    fb = x[3 + 2 * n]
    ima = im[0]
    imb = im[1]
    isa = isb = ira = irb = ifa = ifb = pma = pmb = 0.0
    g0 = 0.0
    ua = 1.0
    ub = 0.0
    status = -1
    for it in range(60):
        r = math.hypot(ima, imb)
        F, dF = mag_flux(mag, r)
        if r > 0.0:
            sig = F / r
            na = ima / r
            nb = imb / r
        else:
            sig = dF
            na = 1.0
            nb = 0.0
        pma = sig * ima
        pmb = sig * imb
        d = dF - sig
        P00 = sig + d * na * na
        P01 = d * na * nb
        P11 = sig + d * nb * nb
        A00 = inv_Lfe
        A01 = 0.0
        A11 = inv_Lfe
        if open_stator:
            isa = 0.0
            isb = 0.0
        else:
            la = x[0] - pma
            lb = x[1] - pmb
            y = math.hypot(la, lb)
            rs, drs = leak_inverse(stat, y, 0.0, im[2])
            im[2] = rs
            if y > 0.0:
                tg = rs / y
                sa = la / y
                sb = lb / y
            else:
                tg = drs
                sa = 1.0
                sb = 0.0
            isa = tg * la
            isb = tg * lb
            A00 += tg + (drs - tg) * sa * sa
            A01 += (drs - tg) * sa * sb
            A11 += tg + (drs - tg) * sb * sb
        ba = b0a - c * pma
        bb = b0b - c * pmb
        yb = math.hypot(ba, bb)
        R, dR = leak_inverse(rot, yb, c, im[3])
        im[3] = R
        if yb > 0.0:
            tg = R / yb
            ua = ba / yb
            ub = bb / yb
        else:
            tg = dR
            ua = 1.0
            ub = 0.0
        g0 = (yb - R) / c if c > 0.0 else 0.0
        ira = tg * ba
        irb = tg * bb
        A00 += c * (tg + (dR - tg) * ua * ua)
        A01 += c * (dR - tg) * ua * ub
        A11 += c * (tg + (dR - tg) * ub * ub)
        ifa = inv_Lfe * (fa - pma)
        ifb = inv_Lfe * (fb - pmb)
        ra = isa + ira + ifa - ima
        rb = isb + irb + ifb - imb
        J00 = -(A00 * P00 + A01 * P01) - 1.0
        J01 = -(A00 * P01 + A01 * P11)
        J10 = -(A01 * P00 + A11 * P01)
        J11 = -(A01 * P01 + A11 * P11) - 1.0
        det = J00 * J11 - J01 * J10
        da = -(J11 * ra - J01 * rb) / det
        db = -(-J10 * ra + J00 * rb) / det
        ima += da
        imb += db
        if math.hypot(da, db) <= 1e-12 * (1.0 + r):
            status = it + 1
            break
    im[0] = ima
    im[1] = imb
    cw[W_IS] = isa
    cw[W_IS + 1] = isb
    cw[W_IR] = ira
    cw[W_IR + 1] = irb
    cw[W_IFE] = ifa
    cw[W_IFE + 1] = ifb
    cw[W_PSIM] = pma
    cw[W_PSIM + 1] = pmb
    # loop currents: i_r = L^-1 (psi_r - psi_m) - (L^-1 1) g_0 u
    for k in range(n):
        sa = 0.0
        sb = 0.0
        for j in range(n):
            sa += Linv[k, j] * (x[2 + 2 * j] - pma)
            sb += Linv[k, j] * (x[3 + 2 * j] - pmb)
        cw[W_LOOPS + 2 * k] = sa - wv[k] * g0 * ua
        cw[W_LOOPS + 2 * k + 1] = sb - wv[k] * g0 * ub
    return status


@njit(cache=True)
def torque(p, cw):
    """Electromagnetic torque on the rotor, N m: ``3/2 p (psi_m,b I_r,a - psi_m,a I_r,b)``."""
    return 1.5 * p * (cw[W_PSIM + 1] * cw[W_IR] - cw[W_PSIM] * cw[W_IR + 1])


@njit(cache=True)
def flux_derivatives(x, n, we, va, vb, Rs, Rr, kr, Rfe, ih, open_stator, cw, dx):
    """Write ``d psi/dt`` of all windings into ``dx`` (stator derivative 0 when open).
    ``Rs`` is the stator resistance now (ohm), ``Rr`` the loop resistances at the reference
    temperature and ``kr`` their temperature factor; ``ih`` the iron's coercive current (A,
    0 = eddy currents only)."""
    if open_stator:
        dx[0] = 0.0
        dx[1] = 0.0
    else:
        dx[0] = va - Rs * cw[W_IS]
        dx[1] = vb - Rs * cw[W_IS + 1]
    for k in range(n):
        a = 2 + 2 * k
        dx[a] = -Rr[k] * kr * cw[W_LOOPS + 2 * k] - we * x[a + 1]
        dx[a + 1] = -Rr[k] * kr * cw[W_LOOPS + 2 * k + 1] + we * x[a]
    if ih > 0.0:
        m = math.hypot(cw[W_IFE], cw[W_IFE + 1])
        g = Rfe * (m - ih) / m if m > ih else 0.0
        dx[2 + 2 * n] = -g * cw[W_IFE]
        dx[3 + 2 * n] = -g * cw[W_IFE + 1]
    else:
        dx[2 + 2 * n] = -Rfe * cw[W_IFE]
        dx[3 + 2 * n] = -Rfe * cw[W_IFE + 1]


@njit(cache=True)
def rotor_loss(n, Rr, kr, cw):
    """Rotor copper loss, W (``3/2 sum R_k |i_r[k]|^2``)."""
    s = 0.0
    for k in range(n):
        s += Rr[k] * (cw[W_LOOPS + 2 * k] ** 2 + cw[W_LOOPS + 2 * k + 1] ** 2)
    return 1.5 * kr * s

