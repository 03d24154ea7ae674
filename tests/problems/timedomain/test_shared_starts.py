"""The batch simulation's shared starts (:mod:`benchmark.problems.timedomain.extended_prefix`): rows
that differ only in a switched load run from the state of the one that switches last, and give
the outputs of a simulation from rest bit for bit, whatever else the rows hold."""

import numpy as np
import pytest

from benchmark.problems.timedomain.extended import IDX, base_rows, simulate_extended_batch
from benchmark.problems.timedomain.extended_prefix import MIN_SHARED_SAMPLES, branch_samples, shared_starts

H = 1e-4
N = 3000
_rng = np.random.default_rng(7)
_t = np.arange(N) * H
V_A = 300.0 * np.cos(377.0 * _t) + _rng.normal(0.0, 0.3, N)
V_B = 300.0 * np.sin(377.0 * _t) + _rng.normal(0.0, 0.3, N)
BASE = base_rows(np.array([[0.3, 0.06, 0.003, 0.2, 0.02, 0.001, 0.1]]), 2)[0]
BASE[IDX["w_ref"]] = 188.0

#: One row of each kind of physics the kernel steps differently.
KINDS = {
    "base": {},
    "leakage_saturation": {"ls_k": 0.3, "ls_psi": 0.05, "ls_exp": 1.7},
    "t_node_saturation": {"t_split": 1.0, "ms_k": 0.2, "ms_psi": 0.8},
    "two_mass": {"J_l": 0.01, "k_sh": 300.0, "c_sh": 0.1},
    "stator_iron_loss": {"g_fe_s": 0.001},
    "heating": {"h_th": 0.01, "alpha_th": 0.0039},
    "coulomb": {"fc": 0.3},
}


def _switched(row, j, rng):
    """Row ``row`` with the ``j``-th switched load of a family: smooth and hard steps, first-order
    rises, armature lags of two time constants, switch-offs, brake laws."""
    q = row.copy()
    q[IDX["T_s"]] = rng.uniform(0.5, 5.0)
    q[IDX["t_step"]] = rng.uniform(0.02, 0.28)
    q[IDX["t_rise"]] = H if j % 3 else 0.0
    if j % 4 == 0:
        q[IDX["tau_s"]] = 0.02 if j % 8 else 0.03
        q[IDX["T_s_speed"]] = 0.5
    if j % 5 == 0:
        q[IDX["t_step_off"]] = q[IDX["t_step"]] + 0.03
    if j % 6 == 0:
        q[IDX["r_crit"]], q[IDX["T_s_speed"]] = 1.5, 1.0
    return q


def _rows():
    rng = np.random.default_rng(3)
    rows = []
    for fields in KINDS.values():
        row = BASE.copy()
        for name, value in fields.items():
            row[IDX[name]] = value
        rows += [row] + [_switched(row, j, rng) for j in range(1, 10)]
    diverging = BASE.copy()
    diverging[IDX["Rs"]] = -5.0  # grows without bound within the record
    rows += [diverging] + [_switched(diverging, j, rng) for j in (1, 2, 3)]
    return np.array(rows)


@pytest.mark.parametrize("linear", [True, False])
@pytest.mark.parametrize("substeps", [1, 2])
def test_rows_that_share_a_start_give_the_outputs_of_a_simulation_from_rest(linear, substeps):
    rows = _rows()
    plan = shared_starts(rows, H, N)
    assert len(plan.members) >= 40  # most switched rows run from a representative's state
    assert np.all(plan.branch >= MIN_SHARED_SAMPLES)
    batch = simulate_extended_batch(rows, V_A, V_B, linear, H, substeps)
    for r, row in enumerate(rows):
        alone = simulate_extended_batch(row[None], V_A, V_B, linear, H, substeps)[0]
        assert np.array_equal(batch[r], alone, equal_nan=True), r
    assert np.isnan(batch[-4:, :, -1]).all()  # the diverging rows, members included


def test_a_share_is_taken_only_where_nothing_but_the_switched_load_differs():
    rows = _rows()
    plan = shared_starts(rows, H, N)
    branch = branch_samples(rows, H, N)
    for m, src, at in zip(plan.members, plan.source, plan.branch, strict=True):
        a, b = rows[m].copy(), rows[src].copy()
        arm = [r[IDX["T_s"]] != 0 and r[IDX["T_s_speed"]] != 0 and r[IDX["tau_s"]] > 0 for r in (a, b)]
        assert arm[0] == arm[1]
        if arm[0]:  # an armature lag's state follows the speed through tau_s from the start
            assert a[IDX["tau_s"]] == b[IDX["tau_s"]]
        for name in ("T_s", "t_step", "t_rise", "T_s_speed", "t_step_off", "r_crit", "tau_s"):
            a[IDX[name]] = b[IDX[name]] = 0.0
        assert np.array_equal(a, b)
        # the representative switches last: its state at the member's branch is the member's
        assert at == branch[m] <= branch[src]
