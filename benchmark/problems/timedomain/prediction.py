"""The time-domain model's response to a data set's inputs for a given parameter set (the
problem's ``predict`` hook, behind :func:`benchmark.api.simulate`)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from benchmark.core.errors import ConfigError
from benchmark.problems.timedomain.motor import PARAMETER_NAMES, coefficients
from benchmark.problems.timedomain.simulation import hold_is_linear, startup_outputs_batch

CHANNELS = ("i_alpha", "i_beta", "speed")


def predict(problem, params: dict) -> pd.DataFrame:
    """Each start-up record of ``problem.dataset`` (conditioned) simulated from rest with
    ``params`` (``Rs, Ls, Le, Rr`` in ohm and H, ``J`` kg m^2, ``fv`` N m s/rad, ``fc`` N m):
    columns ``record``, ``t`` (s), the simulated ``i_alpha``, ``i_beta`` (A), ``speed``
    (mechanical rad/s), and the measured channels with the suffix ``_measured``."""
    missing = [n for n in PARAMETER_NAMES if n not in params]
    if missing:
        raise ConfigError(f"params: missing {missing}; the time-domain model needs {list(PARAMETER_NAMES)}")
    ds = problem.dataset
    theta = np.array([[float(params[n]) for n in PARAMETER_NAMES]])
    coef = coefficients(theta, ds.pole_pairs)
    frames = []
    for j, rec in enumerate(ds.startups):
        sim = startup_outputs_batch(coef, np.ascontiguousarray(rec.v_alpha), np.ascontiguousarray(rec.v_beta),
                                    hold_is_linear(ds.input_hold), ds.sample_time, float(ds.pole_pairs))[0]
        table = {"record": np.full(len(rec.t), j), "t": rec.t}
        table.update({c: sim[k] for k, c in enumerate(CHANNELS)})
        table.update({f"{c}_measured": getattr(rec, c) for c in CHANNELS})
        frames.append(pd.DataFrame(table))
    return pd.concat(frames, ignore_index=True)
