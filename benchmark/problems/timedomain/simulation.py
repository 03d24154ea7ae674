"""Compiled simulation of the induction-motor model: classical RK4 at the sample time.

The stepper integrates the equations of :func:`benchmark.problems.timedomain.motor.state_derivative`
(through :func:`_derivative_lane`: the same operations with the friction cases written as
selects, one source for the one-candidate plant and the SIMD lanes). The input voltage is given
at the sample instants; between samples it is either held (``zoh``, switch-state voltages: the
same voltage at all four RK4 stages) or interpolated linearly (``linear``, sampled continuous
voltages: stage voltages at ``t_k``, the midpoint and ``t_(k+1)``).

Populations (:func:`startup_cost_batch`, :func:`startup_outputs_batch`)
-----------------------------------------------------------------------
A population is simulated in *chunks* of up to :data:`LANES` candidates that advance together,
time step by time step. A chunk lives in one small contiguous work buffer in
structure-of-arrays layout (row ``r`` of lane ``j`` at ``r*LANES + j``: the ten coefficients,
the five states, the running cost and a divergence flag), so the loop over the lanes of one
step has compile-time strides, no aliasing question and no branches (Coulomb friction,
stiction and the divergence test are selects): LLVM turns it into SIMD code (8 float64 lanes
with AVX-512, 4 with AVX2). Chunks are grouped into one block of nearly equal size per thread
(``numba.get_num_threads()``, set with ``numba.set_num_threads``); the compiled block
functions release the GIL and run on a small thread pool (rather than ``parallel=True``: the
plain ``nogil`` functions compile faster than a ``prange`` driver, and calls from several Python
threads at once are safe).
Nothing is allocated per step, everything is cached on disk (``cache=True``).

Every lane performs exactly the floating-point operations of the one-candidate RK4 step
:func:`_rk4` in the same order, in float64 and without ``fastmath`` (no FMA contraction, no
reassociation), so a candidate's cost is the same bit for bit whatever the chunk width, the
lane it sits in, the number of threads and the rest of the population
(``tests/test_simulation_fast.py`` checks it against the previous one-candidate-per-thread
kernel). Candidates with invalid (NaN) coefficient rows are not simulated; a chunk is padded
to a multiple of the SIMD width by repeating a real candidate, whose result is discarded.

A candidate whose states become non-finite or exceed :data:`DIVERGENCE_LIMIT` at any sample
costs ``+inf`` (never NaN); a chunk whose lanes have all diverged stops early.
"""

from __future__ import annotations

import numba
import numpy as np

from benchmark.problems.timedomain.compiled import compiled
from benchmark.problems.timedomain.kernel_pool import shared_executor
from benchmark.problems.timedomain.motor import N_COEF

#: Any state beyond this magnitude counts as a diverged simulation.
DIVERGENCE_LIMIT = 1e9

HOLDS = ("zoh", "linear")

#: Largest number of candidates advanced together in one chunk (the work buffer's row length).
LANES = 16
#: Blocks are sized in multiples of this (the float64 SIMD width with AVX-512).
VECTOR = 8
#: Rows of the chunk work buffer after the N_COEF coefficient rows.
_R_IA, _R_IB, _R_PA, _R_PB, _R_W, _R_COST, _R_BAD = (N_COEF + r for r in range(7))
_N_ROWS = N_COEF + 7
#: How often (in steps) a chunk checks whether all its lanes have diverged.
_ALIVE_CHECK = 64


# -- the step: one candidate (the plant of simulate_states) and branch-free lanes of a chunk ---------
@compiled()
def _stage_voltages(v_a, v_b, k, linear):
    va0, vb0 = v_a[k], v_b[k]
    if linear:
        va1, vb1 = v_a[k + 1], v_b[k + 1]
        return va0, vb0, 0.5 * (va0 + va1), 0.5 * (vb0 + vb1), va1, vb1
    return va0, vb0, va0, vb0, va0, vb0


@compiled()
def _derivative_lane(a11, a13, c1, c2, a31, a33, kt, inv_tau, b_m, fc,
                     i_a, i_b, psi_a, psi_b, w, v_a, v_b, d):
    """:func:`benchmark.problems.timedomain.motor.state_derivative` with the friction cases as selects.

    Same operations in the same order: with ``s`` the direction of the friction torque
    (``d`` while turning; at rest +1 or -1 when the motor torque breaks away, 0 when stiction
    holds), ``fc*s`` is exactly ``fc``, ``-fc`` or ``fc*direction``, and ``dw = 0`` when held."""
    di_a = -a11 * i_a + a13 * psi_a + c2 * w * psi_b + c1 * v_a
    di_b = -a11 * i_b + a13 * psi_b - c2 * w * psi_a + c1 * v_b
    dpsi_a = a31 * i_a - a33 * psi_a - w * psi_b
    dpsi_b = a31 * i_b - a33 * psi_b + w * psi_a
    t_m = kt * (psi_a * i_b - psi_b * i_a)
    s = d if d != 0.0 else (1.0 if t_m > fc else (-1.0 if t_m < -fc else 0.0))
    dw = -w * inv_tau + b_m * (t_m - fc * s)
    dw = dw if s != 0.0 else 0.0
    return di_a, di_b, dpsi_a, dpsi_b, dw


@compiled()
def _rk4(c, i_a, i_b, psi_a, psi_b, w, va0, vb0, vam, vbm, va1, vb1, h):
    """One RK4 step of one candidate (coefficient row ``c``): the reference plant's step.

    The derivative is :func:`_derivative_lane`, operation for operation
    :func:`benchmark.problems.timedomain.motor.state_derivative` (``tests/test_simulation_fast.py`` checks the
    trajectories bit for bit against a stepper built on ``state_derivative``); it is used here
    because it compiles in a fraction of the time of the ``inline="always"`` original."""
    a11, a13, c1, c2, a31, a33, kt, it, bm, fc = c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], c[8], c[9]
    d = 1.0 if w > 0.0 else (-1.0 if w < 0.0 else 0.0)
    k1 = _derivative_lane(a11, a13, c1, c2, a31, a33, kt, it, bm, fc, i_a, i_b, psi_a, psi_b, w, va0, vb0, d)
    hh = 0.5 * h
    k2 = _derivative_lane(a11, a13, c1, c2, a31, a33, kt, it, bm, fc, i_a + hh * k1[0], i_b + hh * k1[1],
                          psi_a + hh * k1[2], psi_b + hh * k1[3], w + hh * k1[4], vam, vbm, d)
    k3 = _derivative_lane(a11, a13, c1, c2, a31, a33, kt, it, bm, fc, i_a + hh * k2[0], i_b + hh * k2[1],
                          psi_a + hh * k2[2], psi_b + hh * k2[3], w + hh * k2[4], vam, vbm, d)
    k4 = _derivative_lane(a11, a13, c1, c2, a31, a33, kt, it, bm, fc, i_a + h * k3[0], i_b + h * k3[1],
                          psi_a + h * k3[2], psi_b + h * k3[3], w + h * k3[4], va1, vb1, d)
    h6 = h / 6.0
    n_ia = i_a + h6 * (k1[0] + 2.0 * (k2[0] + k3[0]) + k4[0])
    n_ib = i_b + h6 * (k1[1] + 2.0 * (k2[1] + k3[1]) + k4[1])
    n_pa = psi_a + h6 * (k1[2] + 2.0 * (k2[2] + k3[2]) + k4[2])
    n_pb = psi_b + h6 * (k1[3] + 2.0 * (k2[3] + k3[3]) + k4[3])
    n_w = w + h6 * (k1[4] + 2.0 * (k2[4] + k3[4]) + k4[4])
    # Coulomb friction cannot reverse the rotor: a sign change it would cause is a stop.
    if fc > 0.0 and w != 0.0 and n_w * w <= 0.0:
        t_m = kt * (n_pa * n_ib - n_pb * n_ia)
        if abs(t_m) <= fc:
            n_w = 0.0
    return n_ia, n_ib, n_pa, n_pb, n_w


@compiled()
def _rk4_lanes(W, nl, va0, vb0, vam, vbm, va1, vb1, h):
    """One RK4 step of lanes ``0..nl-1`` of work buffer ``W`` (see the module docstring);
    operation for operation the same as :func:`_rk4`. Sets the lane's divergence flag."""
    L = LANES
    hh = 0.5 * h
    h6 = h / 6.0
    for j in range(nl):
        a11 = W[j]
        a13 = W[L + j]
        c1 = W[2 * L + j]
        c2 = W[3 * L + j]
        a31 = W[4 * L + j]
        a33 = W[5 * L + j]
        kt = W[6 * L + j]
        it = W[7 * L + j]
        bm = W[8 * L + j]
        fc = W[9 * L + j]
        i_a = W[_R_IA * L + j]
        i_b = W[_R_IB * L + j]
        psi_a = W[_R_PA * L + j]
        psi_b = W[_R_PB * L + j]
        w = W[_R_W * L + j]
        d = 1.0 if w > 0.0 else (-1.0 if w < 0.0 else 0.0)
        k1 = _derivative_lane(a11, a13, c1, c2, a31, a33, kt, it, bm, fc, i_a, i_b, psi_a, psi_b, w,
                              va0, vb0, d)
        k2 = _derivative_lane(a11, a13, c1, c2, a31, a33, kt, it, bm, fc, i_a + hh * k1[0], i_b + hh * k1[1],
                              psi_a + hh * k1[2], psi_b + hh * k1[3], w + hh * k1[4], vam, vbm, d)
        k3 = _derivative_lane(a11, a13, c1, c2, a31, a33, kt, it, bm, fc, i_a + hh * k2[0], i_b + hh * k2[1],
                              psi_a + hh * k2[2], psi_b + hh * k2[3], w + hh * k2[4], vam, vbm, d)
        k4 = _derivative_lane(a11, a13, c1, c2, a31, a33, kt, it, bm, fc, i_a + h * k3[0], i_b + h * k3[1],
                              psi_a + h * k3[2], psi_b + h * k3[3], w + h * k3[4], va1, vb1, d)
        n_ia = i_a + h6 * (k1[0] + 2.0 * (k2[0] + k3[0]) + k4[0])
        n_ib = i_b + h6 * (k1[1] + 2.0 * (k2[1] + k3[1]) + k4[1])
        n_pa = psi_a + h6 * (k1[2] + 2.0 * (k2[2] + k3[2]) + k4[2])
        n_pb = psi_b + h6 * (k1[3] + 2.0 * (k2[3] + k3[3]) + k4[3])
        n_w = w + h6 * (k1[4] + 2.0 * (k2[4] + k3[4]) + k4[4])
        # Coulomb friction cannot reverse the rotor: a sign change it would cause is a stop.
        t_m = kt * (n_pa * n_ib - n_pb * n_ia)
        stop = (fc > 0.0) & (w != 0.0) & (n_w * w <= 0.0) & (abs(t_m) <= fc)
        n_w = 0.0 if stop else n_w
        W[_R_IA * L + j] = n_ia
        W[_R_IB * L + j] = n_ib
        W[_R_PA * L + j] = n_pa
        W[_R_PB * L + j] = n_pb
        W[_R_W * L + j] = n_w
        ok = ((abs(n_ia) < DIVERGENCE_LIMIT) & (abs(n_ib) < DIVERGENCE_LIMIT) & (abs(n_pa) < DIVERGENCE_LIMIT)
              & (abs(n_pb) < DIVERGENCE_LIMIT) & (abs(n_w) < DIVERGENCE_LIMIT))  # false for NaN too
        W[_R_BAD * L + j] = W[_R_BAD * L + j] if ok else 1.0


@compiled()
def _all_diverged(W, nl):
    for j in range(nl):
        if W[_R_BAD * LANES + j] == 0.0:
            return False
    return True


@compiled()
def _load_chunk(W, coef_t, start, nl):
    """Fill work buffer ``W`` with columns ``start..start+nl-1`` of the transposed coefficients
    ``coef_t`` (N_COEF, n); states, cost and flags zero."""
    for q in range(W.shape[0]):
        W[q] = 0.0
    for r in range(N_COEF):
        for j in range(nl):
            W[r * LANES + j] = coef_t[r, start + j]


@compiled()
def _advance(W, nl, v_a, v_b, k, linear, h):
    """One RK4 step of the lanes of ``W`` from sample ``k`` to ``k+1`` (shared by the cost and
    the output kernels); True when every lane has diverged (checked every :data:`_ALIVE_CHECK`
    steps), so that the chunk may stop."""
    va0, vb0, vam, vbm, va1, vb1 = _stage_voltages(v_a, v_b, k, linear)
    _rk4_lanes(W, nl, va0, vb0, vam, vbm, va1, vb1, h)
    return k % _ALIVE_CHECK == _ALIVE_CHECK - 1 and _all_diverged(W, nl)


@compiled()
def _chunk_cost(W, nl, v_a, v_b, linear, h, i_a_meas, i_b_meas, speed_meas, current_used, inv_p, ka, kb, kw,
                exponent):
    """Run the eq. 13-15 cost of the ``nl`` lanes of ``W`` over the whole record.

    ``current_used[k]`` False: the current samples ``k`` are masked (they add nothing; the
    speed sample still counts); the lanes are simulated through them all the same. Where it is
    True the sum is the one of the unmasked cost, operation for operation."""
    L = LANES
    n = v_a.shape[0]
    for k in range(n):
        ma = i_a_meas[k]
        mb = i_b_meas[k]
        mw = speed_meas[k]
        if current_used[k]:
            if exponent == 2:
                for j in range(nl):
                    ea = ma - W[_R_IA * L + j]
                    eb = mb - W[_R_IB * L + j]
                    ew = mw - W[_R_W * L + j] * inv_p
                    W[_R_COST * L + j] += ka * ea * ea + kb * eb * eb + kw * ew * ew
            else:
                for j in range(nl):
                    ea = ma - W[_R_IA * L + j]
                    eb = mb - W[_R_IB * L + j]
                    ew = mw - W[_R_W * L + j] * inv_p
                    W[_R_COST * L + j] += ka * abs(ea) + kb * abs(eb) + kw * abs(ew)
        elif kw != 0.0:
            for j in range(nl):
                ew = mw - W[_R_W * L + j] * inv_p
                W[_R_COST * L + j] += kw * (ew * ew if exponent == 2 else abs(ew))
        if k == n - 1:
            break
        if _advance(W, nl, v_a, v_b, k, linear, h):
            break


@compiled(nogil=True)
def _cost_block(start, stop, W, coef_t, lanes, res, v_a, v_b, linear, h, i_a_meas, i_b_meas, speed_meas,
                current_used, inv_p, ka, kb, kw, exponent):
    """Costs of the candidates in columns ``start..stop-1`` of ``coef_t`` into ``res[start:stop]``,
    ``lanes`` at a time (+inf where diverged), using the work buffer ``W``. Releases the GIL."""
    s = start
    while s < stop:
        nl = min(lanes, stop - s)
        _load_chunk(W, coef_t, s, nl)
        _chunk_cost(W, nl, v_a, v_b, linear, h, i_a_meas, i_b_meas, speed_meas, current_used, inv_p, ka, kb, kw,
                    exponent)
        for j in range(nl):
            total = W[_R_COST * LANES + j]
            res[s + j] = total if (W[_R_BAD * LANES + j] == 0.0 and abs(total) < np.inf) else np.inf
        s += nl


@compiled()
def _chunk_outputs(W, nl, rows, start, n_real, out, v_a, v_b, linear, h, inv_p):
    """Write i_a, i_b and mechanical speed of the lanes of ``W`` into ``out`` (rows
    ``rows[start + j]``; padding lanes past ``n_real`` are not written) until each diverges."""
    L = LANES
    n = v_a.shape[0]
    nw = min(nl, n_real - start)
    for k in range(n):
        for j in range(nw):
            if W[_R_BAD * L + j] == 0.0:
                m = rows[start + j]
                out[m, 0, k] = W[_R_IA * L + j]
                out[m, 1, k] = W[_R_IB * L + j]
                out[m, 2, k] = W[_R_W * L + j] * inv_p
        if k == n - 1:
            break
        if _advance(W, nl, v_a, v_b, k, linear, h):
            break


@compiled(nogil=True)
def _outputs_block(start, stop, W, coef_t, lanes, rows, n_real, out, v_a, v_b, linear, h, inv_p):
    """Outputs of the candidates in columns ``start..stop-1`` of ``coef_t`` into ``out[rows[.]]``."""
    s = start
    while s < stop:
        nl = min(lanes, stop - s)
        _load_chunk(W, coef_t, s, nl)
        _chunk_outputs(W, nl, rows, s, n_real, out, v_a, v_b, linear, h, inv_p)
        s += nl


# -- population plan and threads ---------------------------------------------------------------------
def _plan(coef: np.ndarray, n_blocks: int):
    """Candidates to simulate and their split into parallel blocks.

    Returns ``rows`` (the valid rows of ``coef``, i.e. with a finite first coefficient),
    ``coef_t`` (their coefficients transposed, (N_COEF, n_pad): padded by repeating the last
    valid row so that the count is a multiple of :data:`VECTOR`, unless only one lane would
    be left over, which is then cheaper to run alone), ``rows_padded`` and the block bounds
    (offsets into the columns: block sizes in multiples of :data:`VECTOR`, as equal as possible)."""
    rows = np.flatnonzero(np.isfinite(coef[:, 0]))
    n_real = len(rows)
    rem = n_real % VECTOR
    n_pad = n_real if rem <= 1 else n_real + VECTOR - rem
    rows_padded = np.concatenate([rows, np.full(n_pad - n_real, rows[-1] if n_real else 0, dtype=rows.dtype)])
    coef_t = np.ascontiguousarray(coef[rows_padded].T)
    n_vec = -(-n_pad // VECTOR)
    nb = max(1, min(int(n_blocks), n_vec))
    bounds = [min(n_pad, (b * n_vec // nb) * VECTOR) for b in range(nb + 1)]
    return rows, coef_t, rows_padded, bounds


def _run_blocks(block_fn, bounds, *args) -> None:
    """Run ``block_fn(start, stop, W, *args)`` for every block with its own work buffer ``W``, in
    parallel (the compiled block functions release the GIL); the calling thread takes the first."""
    nb = len(bounds) - 1
    if nb <= 0:
        return
    futures = []
    if nb > 1:
        pool = shared_executor(nb - 1)
        futures = [pool.submit(block_fn, bounds[b], bounds[b + 1], np.empty(_N_ROWS * LANES), *args)
                   for b in range(1, nb)]
    try:
        block_fn(bounds[0], bounds[1], np.empty(_N_ROWS * LANES), *args)
    finally:
        for f in futures:
            f.result()


def _cost_batch(coef, v_a, v_b, linear, h, i_a_meas, i_b_meas, speed_meas, p, weights, exponent, lanes,
                n_blocks, current_weight=None):
    """:func:`startup_cost_batch` with the chunk width (``1 <= lanes <= LANES``) and the number
    of parallel blocks given (the result depends on neither)."""
    if not 1 <= lanes <= LANES:
        raise ValueError(f"lanes must be in [1, {LANES}], got {lanes}")
    coef = np.asarray(coef, dtype=float)
    out = np.full(coef.shape[0], np.inf)
    if coef.shape[0] == 0:
        return out
    used = current_mask(current_weight, v_a.shape[0])
    rows, coef_t, _, bounds = _plan(coef, n_blocks)
    res = np.empty(coef_t.shape[1])
    _run_blocks(_cost_block, bounds, coef_t, int(lanes), res, v_a, v_b, bool(linear), float(h), i_a_meas,
                i_b_meas, speed_meas, used, 1.0 / p, float(weights[0]), float(weights[1]), float(weights[2]),
                int(exponent))
    out[rows] = res[:len(rows)]
    return out


def current_mask(current_weight, n: int) -> np.ndarray:
    """The per-sample flags the cost kernel reads: True where the current samples count
    (``current_weight`` None: all of them)."""
    if current_weight is None:
        return np.ones(n, dtype=np.bool_)
    used = np.ascontiguousarray(np.asarray(current_weight, dtype=np.bool_))
    if used.shape != (n,):
        raise ValueError(f"current_weight must have shape ({n},), got {used.shape}")
    return used


def startup_cost_batch(coef, v_a, v_b, linear, h, i_a_meas, i_b_meas, speed_meas, p, weights, exponent,
                       current_weight=None):
    """Eqs. 13-15 for a population: ``sum_j ka e(i_a) + kb e(i_b) + kw e(w_M)``.

    ``coef``: (n_pop, N_COEF) coefficient rows (NaN rows are invalid candidates).
    ``v_a, v_b``: stator voltages at the N sample instants, V. ``h``: sample time, s.
    ``*_meas``: measured currents (A) and mechanical speed (rad/s) at the same instants.
    ``weights``: (ka, kb, kw). ``exponent``: 2 (eq. 14, squares) or 1 (eq. 15, absolute).
    ``current_weight``: (N,) bool or None; False masks the current samples of that instant
    (``StartupRecord.weight``: clipped probes, a switching window): they add nothing, whatever
    their value (the speed sample still counts), and the simulation runs through them. None
    (all count) gives the unmasked cost bit for bit.
    The simulation starts from rest with zero flux at the first sample. Returns (n_pop,),
    ``+inf`` for invalid or diverging candidates. Runs on as many threads as numba is set to
    use (``numba.set_num_threads``); the result does not depend on their number.
    """
    return _cost_batch(coef, v_a, v_b, linear, h, i_a_meas, i_b_meas, speed_meas, p, weights, exponent, LANES,
                       numba.get_num_threads(), current_weight)


def _outputs_batch(coef, v_a, v_b, linear, h, p, lanes, n_blocks):
    """:func:`startup_outputs_batch` with the chunk width and number of blocks given."""
    if not 1 <= lanes <= LANES:
        raise ValueError(f"lanes must be in [1, {LANES}], got {lanes}")
    coef = np.asarray(coef, dtype=float)
    out = np.full((coef.shape[0], 3, v_a.shape[0]), np.nan)
    if coef.shape[0] == 0:
        return out
    rows, coef_t, rows_padded, bounds = _plan(coef, n_blocks)
    _run_blocks(_outputs_block, bounds, coef_t, int(lanes), rows_padded, len(rows), out, v_a, v_b,
                bool(linear), float(h), 1.0 / p)
    return out


def startup_outputs_batch(coef, v_a, v_b, linear, h, p):
    """Simulated outputs for a population: (n_pop, 3, N) = i_a (A), i_b (A), mechanical speed
    (rad/s) at the N sample instants, from rest. Diverged candidates are NaN from the sample
    where they diverge. Threads as for :func:`startup_cost_batch`."""
    return _outputs_batch(coef, v_a, v_b, linear, h, p, LANES, numba.get_num_threads())


@compiled(_nrt=False)
def substep_voltages(v_a, v_b, k, linear, j, substeps):
    """Input of sub-step ``j`` of ``substeps`` in the sample interval ``k``: its start fraction
    ``f0`` and the voltages at its start, midpoint and end (held, or interpolated linearly
    between samples ``k`` and ``k+1``). Shared by :func:`simulate_states` and the extended
    model's stepper."""
    va0, vb0 = v_a[k], v_b[k]
    dva = v_a[k + 1] - va0 if linear else 0.0
    dvb = v_b[k + 1] - vb0 if linear else 0.0
    f0 = j / substeps
    fm = (j + 0.5) / substeps
    f1 = (j + 1.0) / substeps
    return (f0, va0 + f0 * dva, vb0 + f0 * dvb, va0 + fm * dva, vb0 + fm * dvb, va0 + f1 * dva,
            vb0 + f1 * dvb)


@compiled()
def simulate_states(c, v_a, v_b, linear, h, substeps, x0):
    """One trajectory with ``substeps`` RK4 steps per sample (the reference plant).

    Returns the five states (i_a, i_b, psi_a, psi_b, w electrical) at the N sample instants,
    shape (N, 5), starting from ``x0``. Between samples the input is held or interpolated
    linearly as for the identification model, so ``substeps = 1`` is that model exactly.
    """
    n = v_a.shape[0]
    out = np.empty((n, 5))
    i_a, i_b, psi_a, psi_b, w = x0[0], x0[1], x0[2], x0[3], x0[4]
    hs = h / substeps
    for k in range(n):
        out[k, 0] = i_a
        out[k, 1] = i_b
        out[k, 2] = psi_a
        out[k, 3] = psi_b
        out[k, 4] = w
        if k == n - 1:
            break
        for j in range(substeps):
            f0, va0, vb0, vam, vbm, va1, vb1 = substep_voltages(v_a, v_b, k, linear, j, substeps)
            i_a, i_b, psi_a, psi_b, w = _rk4(c, i_a, i_b, psi_a, psi_b, w, va0, vb0, vam, vbm, va1, vb1, hs)
    return out


def hold_is_linear(input_hold: str) -> bool:
    if input_hold not in HOLDS:
        raise ValueError(f"input_hold must be one of {HOLDS}, got {input_hold!r}")
    return input_hold == "linear"
