"""Rows of a batch that share the start of their trajectory: the plan by which the extended
model's batch simulation (:func:`~benchmark.problems.timedomain.extended.simulate_extended_batch`)
computes that start once.

Two rows that differ only in their switched load (its size ``T_s``, instant ``t_step``, rise
``t_rise`` and ``tau_s``, speed share, switch-off and brake law) follow the same trajectory, bit
for bit, until the earlier switch-on can first change a step: before it the envelope is exactly 0,
so the load adds exactly nothing (``_loads``), and nothing else of the kernel reads those fields. A
start grid of a load's instant (:func:`~benchmark.problems.timedomain.diagnosis.grid.on_grid`: a
hundred instants, each at two sizes) and the load's columns of a Jacobian are such rows. The
batch simulates one row of each such group in full (its *representative*, the one that switches
last) and keeps its state where each other row's switch-on may first act (its *branch sample*);
those rows then run from there. The rows' outputs are those of a simulation from rest, bit for
bit (tested), so a row's outputs still depend on nothing but that row and the record's input.

An armature lag's state (a DC machine's, ``_armature``: a speed share, ``tau_s`` > 0) follows the
speed from the start, through ``tau_s``: rows with one share a start only with rows of the same
``tau_s``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from benchmark.problems.timedomain.extended_rows import IDX

#: Fields of the switched load, which change nothing before its switch-on (with ``tau_s`` where no
#: armature lag is a state).
SWITCHED_FIELDS = ("T_s", "t_step", "t_rise", "T_s_speed", "t_step_off", "r_crit")
#: Rise times of a smooth (``tanh``) step before its instant at which its envelope is exactly 0:
#: ``tanh`` is -1 to the last bit below -19.1 (-22 in C libraries' own cut-off).
TANH_ZERO = 25.0
#: Fewest samples of shared start for which a row runs from its representative's state (below it
#: the row is simulated from rest, as are rows that share with no other).
MIN_SHARED_SAMPLES = 16


class SharedStarts(NamedTuple):
    """A batch's plan (indices into its rows). ``representatives``: rows simulated from rest;
    ``members`` (grouped by representative, each group by branch sample): rows that run from their
    representative's state at ``branch[k]`` (a sample index), ``source[k]`` that representative;
    ``first[j]:first[j + 1]`` the members of ``representatives[j]``."""

    representatives: np.ndarray
    first: np.ndarray
    members: np.ndarray
    source: np.ndarray
    branch: np.ndarray


def branch_samples(rows: np.ndarray, h: float, n: int) -> np.ndarray:
    """The last sample (index) of each row's trajectory that its switched load cannot have changed:
    every step before it ends earlier than the first instant at which the envelope may be non-zero
    (the switch-on; for a smooth step :data:`TANH_ZERO` rise times before it), less one sample for
    rounding; ``n`` (the record's length) where the row switches nothing or is not finite."""
    t_on, t_rise, tau = rows[:, IDX["t_step"]], rows[:, IDX["t_rise"]], rows[:, IDX["tau_s"]]
    t_first = np.where((tau <= 0.0) & (t_rise > 0.0), t_on - TANH_ZERO * t_rise, t_on)
    with np.errstate(invalid="ignore"):
        k = np.floor(t_first / h) - 1.0
        switches = (rows[:, IDX["T_s"]] != 0.0) & np.isfinite(k)
    return np.where(switches, np.clip(np.where(switches, k, 0.0), 0, n), n).astype(np.int64)


def shared_starts(rows: np.ndarray, h: float, n: int) -> SharedStarts:
    """The plan of a batch of extended ``rows`` (n_rows, N_EXT) over a record of ``n`` samples of
    ``h`` s (module docstring)."""
    key = np.array(rows, dtype=float)
    armature = (key[:, IDX["T_s"]] != 0.0) & (key[:, IDX["T_s_speed"]] != 0.0) & (key[:, IDX["tau_s"]] > 0.0)
    for name in SWITCHED_FIELDS:
        key[:, IDX[name]] = 0.0
    key[:, IDX["tau_s"]] = np.where(armature, key[:, IDX["tau_s"]], 0.0)
    key = np.ascontiguousarray(np.column_stack([key, armature.astype(float)]))
    finite = np.all(np.isfinite(rows), axis=1)
    branch = branch_samples(rows, h, n)
    groups: dict[bytes, list[int]] = {}
    alone: list[int] = []
    for r in range(len(rows)):
        (groups.setdefault(key[r].tobytes(), []) if finite[r] else alone).append(r)
    reps, first, members, source, at = [], [0], [], [], []
    for rs in groups.values():
        rep = max(rs, key=lambda r: (branch[r], -r))  # switches last (the first such)
        shared = sorted((r for r in rs if r != rep and branch[r] >= MIN_SHARED_SAMPLES), key=lambda r: (branch[r], r))
        alone += [r for r in rs if r != rep and branch[r] < MIN_SHARED_SAMPLES]
        reps.append(rep)
        members += shared
        source += [rep] * len(shared)
        at += [int(branch[r]) for r in shared]
        first.append(len(members))
    reps += alone
    first += [len(members)] * len(alone)
    as_int = [np.asarray(a, dtype=np.int64) for a in (reps, first, members, source, at)]
    return SharedStarts(*as_int)


def balanced(branch: np.ndarray, blocks: int) -> np.ndarray:
    """An order of rows that resume at ``branch`` in which ``blocks`` nearly equal consecutive
    parts take nearly equal work: the rows by branch sample, dealt to the parts in turn."""
    by_start = np.argsort(branch, kind="stable")
    return np.concatenate([by_start[b::blocks] for b in range(blocks)]) if len(by_start) else by_start
