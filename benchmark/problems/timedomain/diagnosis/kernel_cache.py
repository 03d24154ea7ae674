"""The extended model's outputs for the rows simulated last, so that no row is simulated twice.

Many rows of a diagnosis repeat one another exactly: a forward-difference Jacobian perturbs a
sensor effect's parameters (a probe's level, a current offset, a tachometer's gain, a channel
skew), which act after the simulation (:meth:`Effect.measure`), so those rows are the
unperturbed row again; the point a fit ends at is evaluated again by the ``ssr`` that judges it,
by the set's fold scores and by the other fold's cross start. :class:`KernelCache` simulates
each distinct row of a batch once and keeps the outputs of the last :data:`CACHE_ROWS` distinct
rows (keyed by the row's bytes). The kernel's output for a row does not depend on anything but
that row and the record's input, so a cached output is the one a new simulation would give, bit
for bit.
"""

from __future__ import annotations

import threading
from collections import OrderedDict

import numpy as np

from benchmark.problems.timedomain.extended import simulate_extended_batch

#: Distinct rows whose outputs are kept (each 3 N float64: 0.23 MB for a 9600-sample record).
CACHE_ROWS = 48


class KernelCache:
    """:func:`~benchmark.problems.timedomain.extended.simulate_extended_batch` of one record's
    input (``v_a``, ``v_b`` V, ``linear`` hold, sample time ``h`` s, one step per sample),
    each distinct row simulated once; safe to use from several threads."""

    def __init__(self, v_a: np.ndarray, v_b: np.ndarray, linear: bool, h: float, size: int = CACHE_ROWS):
        self.v_a, self.v_b, self.linear, self.h, self.size = v_a, v_b, bool(linear), float(h), int(size)
        self._kept: OrderedDict[bytes, np.ndarray] = OrderedDict()
        self._lock = threading.Lock()
        self.simulated = 0  # rows given to the kernel
        self.requested = 0  # rows asked for

    def simulate(self, rows: np.ndarray) -> np.ndarray:
        """Outputs (n, 3, N) of the extended rows (n, N_EXT)."""
        rows = np.ascontiguousarray(rows, dtype=float)
        keys = [r.tobytes() for r in rows]
        out = np.empty((len(rows), 3, len(self.v_a)))
        todo: dict[bytes, list[int]] = {}
        with self._lock:
            for j, key in enumerate(keys):
                kept = self._kept.get(key)
                if kept is not None:
                    self._kept.move_to_end(key)
                    out[j] = kept
                else:
                    todo.setdefault(key, []).append(j)
            self.requested += len(rows)
            self.simulated += len(todo)
        if todo:
            first = [js[0] for js in todo.values()]
            sim = simulate_extended_batch(rows[first], self.v_a, self.v_b, self.linear, self.h, 1)
            if len(first) == len(rows):  # every row new and distinct: the batch is the output
                out = sim
            else:
                for m, js in enumerate(todo.values()):
                    out[js] = sim[m]
            with self._lock:
                # only the last ``size`` new rows can stay (the older would be dropped at once)
                for m, key in list(enumerate(todo))[-self.size:]:
                    self._kept[key] = sim[m].copy()
                    self._kept.move_to_end(key)
                while len(self._kept) > self.size:
                    self._kept.popitem(last=False)
        return out
