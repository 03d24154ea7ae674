"""Start grids of the diagnosis's fits: an effect's parameter a local fit cannot be trusted to find
from afar (:meth:`Effect.start_grid <benchmark.core.effects.Effect.start_grid>`: an instant whose
one-sample edge gives a gradient only close to it) set to the grid value that fits best, all values
of a start evaluated in one batch, each also at its best size (:attr:`Effect.grid_size
<benchmark.core.effects.Effect.grid_size>`, one linearised step)."""

from __future__ import annotations

import numpy as np

from benchmark.core.effects import EffectContext
from benchmark.problems.timedomain.diagnosis.fit import JointModel


def on_grid(model: JointModel, x0, mask, effects, ctx: EffectContext, values=None,
            cache: dict | None = None) -> np.ndarray:
    """``x0`` with the grid parameter of each of ``effects`` (indices into ``model.effects``)
    set to the grid value (``values[name]`` when given, else :meth:`Effect.start_grid`'s)
    that fits ``mask`` best, all values evaluated in one batch. Where the effect names a size
    (:attr:`Effect.grid_size`), each value is also judged with that size at its best
    (:func:`sized`): judged at the start's size alone, an instant is best where that size
    changes least (independent plant, a DC generator loaded from the start and read by the
    base as viscous friction: a step of the start's size at 0.949 s, inside the other fold's
    last block). ``x0`` as it was wins ties.

    ``cache``: a dict for one model and one ``mask``, in which each grid's best row is kept by
    the start's other parameters: starts that differ only in the grid parameter (a load step's
    starts at several instants; a round's screening and its fits from the same start) share
    one evaluation of the grid. The result is the same with or without it."""
    x = np.asarray(x0, float)
    for j in effects:
        eff = model.effects[j]
        col = grid_column(model, j, ctx)
        grid = np.atleast_1d(values[eff.name] if values else eff.start_grid(ctx)[1])
        size = None if eff.grid_size is None else model.slices[j].start + eff.grid_size
        here = _judged(model, np.clip(x, model.lower, model.upper)[None, :], mask, size)
        key = (col, np.delete(x, col).tobytes(), np.asarray(grid, float).tobytes())
        best = cache.get(key) if cache is not None else None
        if best is None:
            X = np.repeat(x[None, :], len(grid), axis=0)
            X[:, col] = grid
            best = _judged(model, np.clip(X, model.lower, model.upper), mask, size)
            if cache is not None:
                cache[key] = best
        # in the order of one batch [x, grid, x at its size, grid at its size]: the first lowest wins
        options = [here[0], best[0]] + ([here[1], best[1]] if size is not None else [])
        x = options[int(np.argmin([o[1] for o in options]))][0]
    return x


def _judged(model: JointModel, X: np.ndarray, mask, size: int | None) -> list[tuple[np.ndarray, float]]:
    """The row of ``X`` that fits ``mask`` best (the first where equal) with what the fits
    minimise there; where ``size`` is a column, also the best row with that size moved to its
    best (:func:`sized`)."""
    def first_lowest(rows, ssr):
        k = int(np.argmin(ssr))
        return rows[k], ssr[k]

    if size is None:
        return [first_lowest(X, batched_ssr(model, X, mask))]
    at_size, ssr = sized(model, X, mask, size)
    return [first_lowest(X, ssr), first_lowest(at_size, batched_ssr(model, at_size, mask))]


def batched_ssr(model: JointModel, X: np.ndarray, mask) -> np.ndarray:
    """What the fits minimise (:meth:`JointModel.ssr`) at every row of ``X``, simulated 64 rows
    at a time."""
    return np.concatenate([np.sum(model.objective(X[k:k + 64], mask) ** 2, axis=1) for k in range(0, len(X), 64)])


def sized(model: JointModel, X: np.ndarray, mask, col: int) -> tuple[np.ndarray, np.ndarray]:
    """Each row of ``X`` with its parameter ``col`` (a size) moved to its best by one
    linearised step of what the fits minimise (forward difference), within its bounds; and
    what the fits minimise at the rows of ``X`` (:func:`batched_ssr`), computed on the way."""
    lo, hi = model.lower[col], model.upper[col]
    h = 1e-3 * (hi - lo)
    X1 = X.copy()
    X1[:, col] = np.where(X[:, col] + h > hi, X[:, col] - h, X[:, col] + h)
    out = X.copy()
    ssr = np.empty(len(X))
    for k in range(0, len(X), 64):
        rows = slice(k, k + 64)
        a, b = model.objective(X[rows], mask), model.objective(X1[rows], mask)
        ssr[rows] = np.sum(a * a, axis=1)
        d = (b - a) / (X1[rows, col] - X[rows, col])[:, None]
        dd = np.sum(d * d, axis=1)
        step = np.where(dd > 0, -np.sum(a * d, axis=1) / np.where(dd > 0, dd, 1.0), 0.0)
        out[rows, col] = np.clip(X[rows, col] + step, lo, hi)
    return out, ssr


def grid_column(model: JointModel, j: int, ctx: EffectContext) -> int:
    """The column of ``model.effects[j]``'s grid parameter (:meth:`Effect.start_grid`)."""
    return model.slices[j].start + model.effects[j].start_grid(ctx)[0]
