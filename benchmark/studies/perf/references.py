"""Reference implementations of the start-up cost, written independently of the compiled kernel:
SciPy's solve_ivp one candidate at a time, and a plain NumPy RK4 vectorised over the population."""

from __future__ import annotations

import math

import numpy as np


# -- the reference implementations -------------------------------------------------------------
def _motor_terms(theta: np.ndarray, p: float):
    """Model coefficients from physical parameters (the model), written out here."""
    Rs, Ls, Le, Rr, J, fv, fc = (np.asarray(theta, float)[:, i] for i in range(7))
    Lr = Ls
    Lm = np.sqrt(Lr * (Ls - Le))
    k = Lm / Lr
    return {
        "a11": (Rs + k * k * Rr) / Le,
        "a13": Rr / Lr * Lm / (Le * Lr),
        "c1": 1.0 / Le,
        "c2": Lm / (Le * Lr),
        "a31": Rr * Lm / Lr,
        "a33": Rr / Lr,
        "kt": 1.5 * p * k,
        "inv_tau": fv / J,
        "b_m": p / J,
        "fc": fc,
    }


def _electrical(m, i_a, i_b, psi_a, psi_b, w, va, vb) -> tuple:
    """d/dt of (i_a, i_b, psi_a, psi_b) for ``m = (a11, a13, c1, c2, a31, a33)``; scalars or
    arrays over the candidates alike."""
    a11, a13, c1, c2, a31, a33 = m
    return (
        -a11 * i_a + a13 * psi_a + c2 * w * psi_b + c1 * va,
        -a11 * i_b + a13 * psi_b - c2 * w * psi_a + c1 * vb,
        a31 * i_a - a33 * psi_a - w * psi_b,
        a31 * i_b - a33 * psi_b + w * psi_a,
    )


def solve_ivp_outputs(
    theta_row: np.ndarray,
    p: float,
    t: np.ndarray,
    v_a: np.ndarray,
    v_b: np.ndarray,
    rtol: float = 1e-6,
    atol: float = 1e-8,
) -> np.ndarray:
    """(3, N): i_a, i_b, mechanical speed at the sample instants, by ``solve_ivp`` RK45 over each
    run of constant (zero-order-held) voltage; see the module docstring."""
    from scipy.integrate import solve_ivp

    c = {k: float(v[0]) for k, v in _motor_terms(theta_row[None], p).items()}
    m = tuple(c[k] for k in ("a11", "a13", "c1", "c2", "a31", "a33"))
    kt, inv_tau, b_m, fc = c["kt"], c["inv_tau"], c["b_m"], c["fc"]
    volt = [0.0, 0.0]

    def rhs(_t, x):
        i_a, i_b, psi_a, psi_b, w = x
        va, vb = volt
        t_m = kt * (psi_a * i_b - psi_b * i_a)
        if w > 0.0:
            dw = -w * inv_tau + b_m * (t_m - fc)
        elif w < 0.0:
            dw = -w * inv_tau + b_m * (t_m + fc)
        elif abs(t_m) <= fc:
            dw = 0.0
        else:
            dw = b_m * (t_m - math.copysign(fc, t_m))
        return [*_electrical(m, i_a, i_b, psi_a, psi_b, w, va, vb), dw]

    n = len(t)
    change = np.flatnonzero((np.diff(v_a) != 0) | (np.diff(v_b) != 0)) + 1
    starts = np.concatenate([[0], change])
    ends = np.concatenate([change, [n - 1]])
    x = np.zeros(5)
    out = np.empty((5, n))
    out[:, 0] = x
    for k0, k1 in zip(starts, ends, strict=True):
        if k1 <= k0:
            continue
        volt[0], volt[1] = float(v_a[k0]), float(v_b[k0])
        sol = solve_ivp(rhs, (t[k0], t[k1]), x, method="RK45", rtol=rtol, atol=atol, t_eval=t[k0 + 1 : k1 + 1])
        if not sol.success:
            out[:, k0 + 1 :] = np.nan
            break
        out[:, k0 + 1 : k1 + 1] = sol.y
        x = sol.y[:, -1]
    return np.stack([out[0], out[1], out[4] / p])


def eq15_cost(sim: np.ndarray, meas: np.ndarray, weights, exponent: int) -> float:
    e = meas - sim
    e = np.abs(e) if exponent == 1 else e * e
    total = float(np.asarray(weights, float) @ e.sum(axis=1))
    return total if math.isfinite(total) else math.inf


def numpy_rk4_cost(
    theta: np.ndarray,
    p: float,
    v_a: np.ndarray,
    v_b: np.ndarray,
    h: float,
    meas: np.ndarray,
    weights,
    exponent: int,
) -> np.ndarray:
    """The fixed-step RK4 cost (zero-order hold) vectorised over the population with NumPy:
    every operation is an array operation over the candidates; loop over the samples."""
    c = _motor_terms(theta, p)
    m = tuple(c[k] for k in ("a11", "a13", "c1", "c2", "a31", "a33"))
    kt, inv_tau, b_m, fc = c["kt"], c["inv_tau"], c["b_m"], c["fc"]
    ka, kb, kw = (float(x) for x in weights)
    n_pop = len(theta)
    ia, ib, pa, pb, w = (np.zeros(n_pop) for _ in range(5))
    total = np.zeros(n_pop)
    bad = ~np.all(np.isfinite(np.stack(list(c.values()))), axis=0) | ~(theta[:, 2] < theta[:, 1])

    def f(ia, ib, pa, pb, w, va, vb, d):
        t_m = kt * (pa * ib - pb * ia)
        s = np.where(d != 0.0, d, np.where(t_m > fc, 1.0, np.where(t_m < -fc, -1.0, 0.0)))
        dw = np.where(s != 0.0, -w * inv_tau + b_m * (t_m - fc * s), 0.0)
        return (*_electrical(m, ia, ib, pa, pb, w, va, vb), dw)

    n = len(v_a)
    with np.errstate(all="ignore"):
        for k in range(n):
            ea, eb, ew = meas[0, k] - ia, meas[1, k] - ib, meas[2, k] - w / p
            if exponent == 2:
                total += ka * ea * ea + kb * eb * eb + kw * ew * ew
            else:
                total += ka * np.abs(ea) + kb * np.abs(eb) + kw * np.abs(ew)
            if k == n - 1:
                break
            va, vb = v_a[k], v_b[k]
            d = np.sign(w)
            k1 = f(ia, ib, pa, pb, w, va, vb, d)
            x = (ia, ib, pa, pb, w)
            k2 = f(*(xi + 0.5 * h * ki for xi, ki in zip(x, k1, strict=True)), va, vb, d)
            k3 = f(*(xi + 0.5 * h * ki for xi, ki in zip(x, k2, strict=True)), va, vb, d)
            k4 = f(*(xi + h * ki for xi, ki in zip(x, k3, strict=True)), va, vb, d)
            h6 = h / 6.0
            ia_n = ia + h6 * (k1[0] + 2.0 * (k2[0] + k3[0]) + k4[0])
            ib_n = ib + h6 * (k1[1] + 2.0 * (k2[1] + k3[1]) + k4[1])
            pa_n = pa + h6 * (k1[2] + 2.0 * (k2[2] + k3[2]) + k4[2])
            pb_n = pb + h6 * (k1[3] + 2.0 * (k2[3] + k3[3]) + k4[3])
            w_n = w + h6 * (k1[4] + 2.0 * (k2[4] + k3[4]) + k4[4])
            t_m = kt * (pa_n * ib_n - pb_n * ia_n)  # friction cannot reverse the rotor
            w_n = np.where((fc > 0.0) & (w != 0.0) & (w_n * w <= 0.0) & (np.abs(t_m) <= fc), 0.0, w_n)
            ia, ib, pa, pb, w = ia_n, ib_n, pa_n, pb_n, w_n
            bad |= ~(np.maximum.reduce([np.abs(ia), np.abs(ib), np.abs(pa), np.abs(pb), np.abs(w)]) < 1e9)
    return np.where(bad | ~np.isfinite(total), np.inf, total)
