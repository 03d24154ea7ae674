"""Wall-time limit of one optimiser run (``time_limit_s``): SIGALRM, a clock check in each
evaluation, and a last-resort kill for a plugin stuck in native code."""

from __future__ import annotations

import contextlib
import faulthandler
import signal
import sys
import threading
import time
from typing import TYPE_CHECKING

from benchmark.core.problem import TimeLimitExceeded

if TYPE_CHECKING:
    from benchmark.core.budget import BudgetedProblem

# -- wall-time limit ---------------------------------------------------------------------------
#: After the limit, a plugin stuck in native code (which neither SIGALRM nor the check in
#: ``evaluate`` can interrupt) gets this much more time before the process is ended by
#: ``faulthandler`` (tracebacks on stderr, exit status 1, no result.json): max(this, limit/2) s.
HARD_KILL_GRACE_S = 30.0


@contextlib.contextmanager
def time_limit(seconds: float | None, budgeted: BudgetedProblem | None = None):
    """Raise :class:`TimeLimitExceeded` in the block once ``seconds`` of wall time have passed.

    Three layers, because no single one covers every way a plugin can hang:

    1. ``signal.setitimer(ITIMER_REAL)``: the SIGALRM handler raises in the main thread at
       the next Python bytecode, which stops a pure-Python loop that never evaluates, a
       ``time.sleep``, or a wait on a lock. Only in the main thread of a POSIX process (not
       on Windows, nor when a launcher runs jobs in threads); it replaces any SIGALRM handler
       for the duration of the block and restores it afterwards.
    2. ``budgeted.deadline``: every evaluation checks the clock, so a plugin that keeps
       evaluating stops even where signals are unavailable.
    3. ``faulthandler.dump_traceback_later``: native code that never returns to Python
       (a C extension or a compiled loop spinning forever, holding the GIL) cannot be
       interrupted at all from inside the process; after a grace period
       (:data:`HARD_KILL_GRACE_S`) the process dumps its tracebacks and exits with status 1.
       That run then has no ``result.json`` (its checkpoint journal survives) and a sweep in the
       same process stops: run such plugins under an external ``timeout`` if that matters.

    A signal arriving inside a plugin's ``finally``/``except BaseException`` block may be
    swallowed by it; layer 2 then catches the plugin at its next evaluation.
    """
    if seconds is None:
        yield
        return
    seconds = float(seconds)
    start = time.monotonic()
    if budgeted is not None:
        budgeted.deadline = start + seconds
        budgeted.time_limit_s = seconds
    if budgeted is not None:
        message = budgeted._time_message
    else:
        def message():
            return f"time limit of {seconds:g} s exceeded"

    use_signal = (hasattr(signal, "setitimer") and threading.current_thread() is threading.main_thread())
    previous = None
    armed = [True]

    def on_alarm(signum, frame):
        if not armed[0]:
            return
        armed[0] = False
        if budgeted is not None and budgeted._critical:
            budgeted._timeout_pending = True  # raised once the batch in flight is counted
            return
        raise TimeLimitExceeded(message())

    if use_signal:
        previous = signal.signal(signal.SIGALRM, on_alarm)
        signal.setitimer(signal.ITIMER_REAL, max(seconds, 1e-3))
    hard = max(HARD_KILL_GRACE_S, 0.5 * seconds) + seconds
    with contextlib.suppress(Exception):
        faulthandler.dump_traceback_later(hard, exit=True, file=sys.stderr)
    try:
        yield
    finally:
        armed[0] = False
        if budgeted is not None:
            budgeted._timeout_pending = False
        if use_signal:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, previous if previous is not None else signal.SIG_DFL)
        with contextlib.suppress(Exception):
            faulthandler.cancel_dump_traceback_later()
        if budgeted is not None:
            budgeted.deadline = None

