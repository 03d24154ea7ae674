"""The equivalent circuit's admittance at a sweep's readings for a given parameter set (the
problem's ``predict`` hook, behind :func:`benchmark.api.simulate`)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from benchmark.core.errors import ConfigError


def predict(problem, params: dict) -> pd.DataFrame:
    """The model admittance ``G + jB`` (S per phase, temperature-compensated as in the fit) at
    every reading for the circuit ``params`` (ohm, the names of ``problem.parameter_names``):
    columns ``slip``, ``G``, ``B``, ``G_measured``, ``B_measured``."""
    missing = [n for n in problem.parameter_names if n not in params]
    if missing:
        raise ConfigError(f"params: missing {missing}; this circuit needs {list(problem.parameter_names)}")
    x = np.array([[float(params[n]) for n in problem.parameter_names]])
    y = problem.admittance(x)[0]
    d = problem.data
    return pd.DataFrame({"slip": np.asarray(d.slip, float), "G": y.real, "B": y.imag,
                         "G_measured": np.asarray(d.G, float), "B_measured": np.asarray(d.B, float)})
