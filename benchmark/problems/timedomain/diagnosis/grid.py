"""Start grids of the diagnosis's fits: an effect's parameter a local fit cannot be trusted to find
from afar (:meth:`Effect.start_grid <benchmark.core.effects.Effect.start_grid>`: an instant whose
one-sample edge gives a gradient only close to it) set to the grid value that fits best, all values
of a start evaluated in one batch, each also at its best size (:attr:`Effect.grid_size
<benchmark.core.effects.Effect.grid_size>`, one linearised step)."""

from __future__ import annotations

import numpy as np

from benchmark.core.effects import EffectContext
from benchmark.problems.timedomain.diagnosis.fit import JointModel


def on_grid(model: JointModel, x0, mask, effects, ctx: EffectContext, values=None) -> np.ndarray:
    """``x0`` with the grid parameter of each of ``effects`` (indices into ``model.effects``)
    set to the grid value (``values[name]`` when given, else :meth:`Effect.start_grid`'s)
    that fits ``mask`` best, all values evaluated in one batch. Where the effect names a size
    (:attr:`Effect.grid_size`), each value is also judged with that size at its best
    (:func:`sized`): judged at the start's size alone, an instant is best where that size
    changes least (independent plant, a DC generator loaded from the start and read by the
    base as viscous friction: a step of the start's size at 0.949 s, inside the other fold's
    last block). ``x0`` as it was wins ties."""
    x = np.asarray(x0, float)
    for j in effects:
        eff = model.effects[j]
        col = grid_column(model, j, ctx)
        grid = np.atleast_1d(values[eff.name] if values else eff.start_grid(ctx)[1])
        X = np.repeat(x[None, :], len(grid) + 1, axis=0)
        X[1:, col] = grid
        X = np.clip(X, model.lower, model.upper)
        if eff.grid_size is not None:
            at_size, ssr = sized(model, X, mask, model.slices[j].start + eff.grid_size)
            X, ssr = np.vstack([X, at_size]), np.concatenate([ssr, batched_ssr(model, at_size, mask)])
        else:
            ssr = batched_ssr(model, X, mask)
        x = X[int(np.argmin(ssr))]
    return x


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
