"""imbench: identify the parameters of an induction-motor model from measured or synthetic data,
compare optimisers on it, and diagnose why an identified model still misses the data.

The Python API is :mod:`benchmark.api` (``from benchmark import api``; its functions are also
reachable here: ``benchmark.identify``, ``benchmark.diagnose``, ``benchmark.load``,
``benchmark.simulate``). The command line: ``python -m benchmark --help``.
"""

from __future__ import annotations

_API = ("DataSet", "Diagnosis", "Identification", "diagnose", "identify", "load", "simulate")


def __getattr__(name: str):
    # the API pulls in Hydra and pandas: imported on first use, not by every plugin's import
    if name == "api" or name in _API:
        import importlib

        api = importlib.import_module("benchmark.api")
        return api if name == "api" else getattr(api, name)
    raise AttributeError(f"module 'benchmark' has no attribute {name!r}")
