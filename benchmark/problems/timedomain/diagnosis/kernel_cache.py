"""Model outputs for the rows computed last, so that no row is computed twice.

Many rows of a diagnosis repeat one another exactly: a forward-difference Jacobian perturbs a
sensor effect's parameters (a probe's level, a current offset, a tachometer's gain, a channel
skew), which act after the simulation (:meth:`Effect.measure`), so those rows are the
unperturbed row again; the point a fit ends at is evaluated again by the ``ssr`` that judges it,
by the set's fold scores and by the other fold's cross start. The free stop repeats more often
still: only the mechanical parameters, a load's and the speed sensor's move it, so every other
column of a Jacobian is the unperturbed coast again. :class:`RowCache` computes each distinct
key of a batch once and keeps the outputs of the last ``size`` distinct keys;
:class:`KernelCache` is it for the extended model's kernel (keyed by the row's bytes: the
kernel's output for a row does not depend on anything but that row and the record's input), and
:meth:`~benchmark.problems.timedomain.diagnosis.fit.JointModel.recorded_stop` keeps the coast in
one (``DiagnosisData.coasts``, keyed by what the coast of a row is computed from). A cached
output is the one a new computation would give, bit for bit, as long as the key holds all an
output depends on and each row's output does not depend on the other rows of its batch.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable

import numpy as np

from benchmark.problems.timedomain.extended import simulate_extended_batch

#: Distinct rows whose outputs are kept (each 3 N float64: 0.23 MB for a 9600-sample record).
CACHE_ROWS = 48


class RowCache:
    """Outputs of rows by key (any hashable: a row's bytes), each distinct key computed once; the
    last ``size`` distinct keys' outputs kept; safe to use from several threads."""

    def __init__(self, size: int = CACHE_ROWS):
        self.size = int(size)
        self._kept: OrderedDict[Hashable, np.ndarray] = OrderedDict()
        self._lock = threading.Lock()
        self.computed = 0  # rows given to ``compute``
        self.requested = 0  # rows asked for

    def get(self, keys: list[Hashable], compute: Callable[[list[int]], np.ndarray], shape: tuple) -> np.ndarray:
        """Outputs ``(len(keys), *shape)``: kept ones where a key was computed before, the rest
        from ``compute(indices)`` (the rows to compute, one per distinct new key, in order: an
        array ``(len(indices), *shape)``)."""
        out = np.empty((len(keys), *shape))
        todo: dict[Hashable, list[int]] = {}
        with self._lock:
            for j, key in enumerate(keys):
                kept = self._kept.get(key)
                if kept is not None:
                    self._kept.move_to_end(key)
                    out[j] = kept
                else:
                    todo.setdefault(key, []).append(j)
            self.requested += len(keys)
            self.computed += len(todo)
        if todo:
            first = [js[0] for js in todo.values()]
            new = compute(first)
            if len(first) == len(keys):  # every row new and distinct: the batch is the output
                out = new
            else:
                for m, js in enumerate(todo.values()):
                    out[js] = new[m]
            with self._lock:
                # only the last ``size`` new rows can stay (the older would be dropped at once)
                for m, key in list(enumerate(todo))[-self.size:]:
                    self._kept[key] = new[m].copy()
                    self._kept.move_to_end(key)
                while len(self._kept) > self.size:
                    self._kept.popitem(last=False)
        return out


class KernelCache(RowCache):
    """:func:`~benchmark.problems.timedomain.extended.simulate_extended_batch` of one record's
    input (``v_a``, ``v_b`` V, ``linear`` hold, sample time ``h`` s, one step per sample),
    each distinct row simulated once; safe to use from several threads."""

    def __init__(self, v_a: np.ndarray, v_b: np.ndarray, linear: bool, h: float, size: int = CACHE_ROWS):
        super().__init__(size)
        self.v_a, self.v_b, self.linear, self.h = v_a, v_b, bool(linear), float(h)

    @property
    def simulated(self) -> int:
        """Rows given to the kernel."""
        return self.computed

    def simulate(self, rows: np.ndarray) -> np.ndarray:
        """Outputs (n, 3, N) of the extended rows (n, N_EXT)."""
        rows = np.ascontiguousarray(rows, dtype=float)
        return self.get([r.tobytes() for r in rows],
                        lambda first: simulate_extended_batch(rows[first], self.v_a, self.v_b, self.linear, self.h, 1),
                        (3, len(self.v_a)))
