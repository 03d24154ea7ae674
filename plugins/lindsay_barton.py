"""``lindsay_barton``: the paper's optimisation -- an initial model, then conjugate-gradient searches.

Lindsay and Barton (1972) start from an initial model (A: a crude reading of the admittance at
synchronous speed and standstill; E: the regression ("quadratic curve fit") of the modified Morris
model mapped back to the circuit) and minimise the error function by conjugate gradients in
"searches". Here:

* **Start.** The plugin only knows the plugin interface. A problem that can compute the paper's
  initial models from its data offers the optional hook ``initial_guess(kind) -> vector | None`` on
  the :class:`benchmark.core.problem.Problem` (reached as ``problem.problem`` through the
  :class:`benchmark.core.problem.SearchProblem`); ``kind`` is ``initial_model`` ("A" or "E"). Without the
  hook, or when it returns None, the start is ``problem.crude_start()`` (so the plugin also runs on the
  time-domain problem). The hook works on the data alone and evaluates no cost, so it spends none of
  the budget: for the admittance problem's "E" this includes the regression's own outer search over
  two warp ratios (a data-reduction step, as in the paper). Comparisons with black-box plugins should
  say so; ``initial_model: crude`` skips the hook.
* **Searches.** One search is one run of ``scipy.optimize.minimize(method="CG")`` (Polak-Ribiere
  conjugate gradients with its own line search) limited to ``iterations_per_search`` iterations
  (default ``n_var``: one cycle of conjugate directions, after which conjugate-gradient methods
  restart); ``searches`` such runs are chained, each restarting from the best point so far. The paper
  does not define a search further; this is the project's reading. It stops early when a whole search
  improves the cost by less than ``rtol``.
* **Coordinates and gradients.** The search runs in coordinates normalised to the bounds,
  ``u = (x - lower)/(upper - lower)``; a point outside ``[0, 1]`` is evaluated at its projection onto
  the box plus a quadratic penalty ``bound_penalty*|u - clip(u)|^2`` (so every counted evaluation is
  inside the bounds). The objective is the cost divided by the cost at the start. Gradients are central
  finite differences with step ``fd_step`` in ``u``, their ``2*n_var`` points evaluated in one batch.
* **Budget.** Every point goes through ``problem.evaluate`` (the harness's counter). When the budget is
  spent, the batch that crossed it is trimmed by the counter and the plugin returns.
"""

from __future__ import annotations

import numpy as np
from scipy import optimize

from benchmark.core.problem import OptimizerOutput, SearchProblem

__all__ = ["minimize", "initial_point"]


class _BudgetSpent(Exception):
    pass


def initial_point(problem: SearchProblem, initial_model: str) -> tuple[np.ndarray, str]:
    """The start and a note saying where it came from (the hook, or the crude start)."""
    inner = getattr(problem, "problem", None)
    hook = getattr(inner, "initial_guess", None)
    if str(initial_model).lower() != "crude" and callable(hook):
        x0 = hook(initial_model)
        if x0 is not None:
            x0 = np.asarray(x0, float)
            if x0.shape == (problem.n_var,) and np.all(np.isfinite(x0)):
                return x0, f"initial model {initial_model} (problem's initial_guess hook)"
    return np.asarray(problem.crude_start(), float), "crude start (centre of the bounds)"


def minimize(
    problem: SearchProblem,
    seed: int = 0,
    *,
    initial_model: str = "E",
    searches: int = 5,
    iterations_per_search: int | None = None,
    fd_step: float = 1e-7,
    gtol: float = 1e-12,
    rtol: float = 1e-12,
    bound_penalty: float = 100.0,
) -> OptimizerOutput:
    """Initial model then ``searches`` conjugate-gradient searches (see the module docstring).

    ``seed`` is accepted for the interface; the method is deterministic."""
    del seed
    if int(searches) < 1:
        from benchmark.core.errors import ConfigError

        raise ConfigError(f"optimizer.plugin.searches: at least 1, got {searches}")
    lo, hi = problem.lower, problem.upper
    span = hi - lo
    n = problem.n_var
    iters = int(iterations_per_search) if iterations_per_search else n

    def to_x(U):
        return lo + np.clip(U, 0.0, 1.0) * span

    def penalty(U):
        return bound_penalty * np.sum((U - np.clip(U, 0.0, 1.0)) ** 2, axis=-1)

    def raw(U):
        """Counted costs of the rows of U (projected into the box)."""
        U = np.atleast_2d(U)
        c = problem.evaluate(to_x(U))
        if problem.exhausted:
            raise _BudgetSpent
        return c

    x0, note = initial_point(problem, initial_model)
    u0 = (x0 - lo) / span
    try:
        c0 = float(raw(u0)[0])
        if not np.isfinite(c0) and note.startswith("initial"):
            x0, note2 = np.asarray(problem.crude_start(), float), "crude start"
            note += f" had an infinite cost; {note2}"
            u0 = (x0 - lo) / span
            c0 = float(raw(u0)[0])
    except _BudgetSpent:
        return OptimizerOutput(x=x0, nit=0, message=f"{note}; budget spent at the start")
    if not np.isfinite(c0):
        return OptimizerOutput(x=x0, nit=0, message=f"{note}: infinite cost at the start, nothing to search")
    scale = c0 if c0 > 0 else 1.0
    cache: dict[bytes, float] = {u0.tobytes(): c0 / scale}
    best = {"u": u0.copy(), "f": c0 / scale}

    def fun(u):
        key = u.tobytes()
        if key not in cache:
            c = raw(u)[0]
            f = c / scale + penalty(u)
            cache[key] = float(f) if np.isfinite(f) else 1e300
        f = cache[key]
        if f < best["f"]:
            best["u"], best["f"] = u.copy(), f
        return f

    def jac(u):
        E = np.eye(n) * fd_step
        U = np.concatenate([u + E, u - E])
        c = raw(U)
        f = c / scale + penalty(U)
        f = np.where(np.isfinite(f), f, 1e300)
        return (f[:n] - f[n:]) / (2 * fd_step)

    nit = 0
    done = 0
    message = ""
    try:
        for _ in range(int(searches)):
            f_before = best["f"]
            res = optimize.minimize(
                fun, best["u"], jac=jac, method="CG", options={"maxiter": iters, "gtol": gtol, "norm": np.inf}
            )
            nit += int(res.nit)
            done += 1
            if f_before - best["f"] <= rtol * max(abs(f_before), 1e-300):
                message = f"search {done} improved by less than rtol"
                break
    except _BudgetSpent:
        message = f"budget spent during search {done + 1}"
    x_best = to_x(best["u"])
    msg = f"{note}; start cost {c0:.6g}; {done} search(es), {nit} CG iterations"
    return OptimizerOutput(x=x_best, nit=nit, message=f"{msg}; {message}" if message else msg)
