"""The start grid of a load step's instant (diagnosis/grid.py): starts that differ only in the
instant share one evaluation of the grid, and give what each gives alone, bit for bit."""

from __future__ import annotations

import numpy as np

from benchmark.core.effects import load_effects
from benchmark.problems.timedomain.data import StartupDataset, StartupRecord
from benchmark.problems.timedomain.diagnosis.fit import DiagnosisData, JointModel
from benchmark.problems.timedomain.diagnosis.folds import segment_folds
from benchmark.problems.timedomain.diagnosis.grid import on_grid
from benchmark.problems.timedomain.diagnosis.pipeline import base_context
from benchmark.problems.timedomain.protocol import StartupStopTest, run_startup_stop
from tests.conftest import PAPER_MOTOR

LOAD = load_effects("timedomain", ["load_torque"])["load_torque"]


def test_starts_that_differ_only_in_the_instant_share_one_grid_and_each_gives_what_it_gives_alone():
    s = run_startup_stop(PAPER_MOTOR, StartupStopTest(cycles=20))["startup"]
    rec = StartupRecord(t=s["t"], v_alpha=s["v_alpha"], v_beta=s["v_beta"], i_alpha=s["i_alpha"],
                        i_beta=s["i_beta"], speed=s["speed"])
    data = DiagnosisData.from_dataset(StartupDataset(pole_pairs=1, sample_time=1 / 12000, startups=[rec],
                                                     input_hold="zoh"))
    truth = {k: getattr(PAPER_MOTOR, k) for k in ("Rs", "Ls", "Le", "Rr", "J", "fv", "fc")}
    ctx = base_context(data, truth, 300.0)
    model = JointModel(data, 2, [LOAD], ctx, truth, 1.0)
    base = np.array([truth[k] for k in model.base_names])
    starts = [np.clip(np.concatenate([base, e]), model.lower, model.upper) for e in LOAD.extra_starts(ctx)]
    mask = segment_folds(data)[0]
    cache: dict = {}
    alone = [on_grid(model, x0, mask, [0], ctx) for x0 in starts]
    shared = [on_grid(model, x0, mask, [0], ctx, cache=cache) for x0 in starts]
    assert all(np.array_equal(a, b) for a, b in zip(alone, shared, strict=True))
    # the step starts at 0.35, 0.65 and 0.85 of the record differ only in the instant: one grid
    steps = [x for x in starts if x[len(base) + 2] > 0 and x[len(base) + 4] == 0]
    assert len(steps) >= 3 and len(cache) <= len(starts) - len(steps) + 1
    # each moved to the grid's instant (where the first fits best), the same for all step starts
    assert len({float(x[len(base) + 3]) for x in shared if x[len(base) + 2] > 0 and x[len(base) + 4] == 0}) == 1
