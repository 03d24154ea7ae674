"""The progress bar of a run (tqdm): evaluations against the budget, best cost, time left.
Shown on a terminal only: not in CI, not in sweeps, not with ``progress=false``."""

from __future__ import annotations

import contextlib
import math
import os
import sys
import time

from benchmark.core.budget import BudgetedProblem


def progress_wanted(setting, *, stream=None, environ=None, multirun: bool | None = None) -> bool:
    """Whether a run shows its progress bar: ``progress=true`` forces it and ``false`` turns it
    off; ``auto`` shows it only where someone watches: on a terminal (``stream``, default
    stderr, is a tty), outside CI (no ``CI`` environment variable) and outside a sweep (Hydra's
    multirun mode)."""
    if setting is True or setting is False:
        return setting
    environ = os.environ if environ is None else environ
    if environ.get("CI"):
        return False
    stream = sys.stderr if stream is None else stream
    try:
        if not stream.isatty():
            return False
    except (AttributeError, ValueError, OSError):
        return False
    return not (_in_multirun() if multirun is None else multirun)


def _in_multirun() -> bool:
    try:
        from hydra.core.hydra_config import HydraConfig
        from hydra.types import RunMode

        return HydraConfig.initialized() and HydraConfig.get().mode == RunMode.MULTIRUN
    except Exception:
        return False


class ProgressBar:
    """A tqdm bar of one run on stderr: evaluations against the budget, the best cost and the
    estimated time left. Set as :attr:`BudgetedProblem.on_evaluate`; it redraws at most every
    :attr:`interval` seconds, so the evaluation loop pays one clock read per batch. A bar that
    cannot be drawn (stderr closed) goes quiet instead of failing the run."""

    interval = 0.1

    def __init__(self, budget: int, desc: str, file=None):
        from tqdm import tqdm

        file = file if file is not None else sys.stderr
        try:
            columns = os.get_terminal_size(file.fileno()).columns
        except (AttributeError, ValueError, OSError):
            columns = 0
        # a terminal that reports no size (a bare pty) would hide the bar: give it one
        width = {"dynamic_ncols": True} if columns > 0 else {"ncols": 100, "nrows": 24}
        self._last = -math.inf
        try:
            self._bar = tqdm(total=int(budget), desc=desc, unit="eval", file=file, leave=False, mininterval=0.0,
                             miniters=1, smoothing=0.1, **width)
        except Exception:
            self._bar = None

    def __call__(self, budgeted: BudgetedProblem) -> None:
        now = time.monotonic()
        if now - self._last >= self.interval:
            self._last = now
            self._show(budgeted)

    def _show(self, budgeted: BudgetedProblem) -> None:
        if self._bar is None:
            return
        try:
            self._bar.set_postfix_str(f"best {budgeted.best_cost:.5g}", refresh=False)
            self._bar.update(min(budgeted.nfev, budgeted.budget) - self._bar.n)
        except Exception:
            self._bar = None

    def close(self, budgeted: BudgetedProblem) -> None:
        self._show(budgeted)
        if self._bar is not None:
            with contextlib.suppress(Exception):
                self._bar.close()
            self._bar = None
