"""A bench record, from files to a model, through the Python API (``benchmark.api``).

    python examples/bench_record.py [DATA_FOLDER] [OUT_FOLDER]

Loads a measured-format data folder (``examples/data/bench_1kw``: phase voltages and currents,
a speed column, a free stop, the stator's DC resistance and the nameplate in ``meta.yaml``),
identifies the motor with the default pipeline, prints the estimate with its standard errors,
diagnoses what the model misses (here only the double cage is a candidate, to keep it short),
and exports the model to MATLAB and to motulator. ``python -m benchmark data.path=FOLDER`` and
``python -m benchmark.diagnose data.path=FOLDER 'candidates=[double_cage]' budget=2000
polish_budget=400`` print the same numbers (tests/cli/test_example.py checks it).
"""

import sys
from pathlib import Path

from benchmark import api

HERE = Path(__file__).resolve().parent
folder = Path(sys.argv[1]) if len(sys.argv) > 1 else HERE / "data" / "bench_1kw"
out = Path(sys.argv[2]) if len(sys.argv) > 2 else Path("example_output")

# 1. The data set: meta.yaml as a dict, each table as a pandas DataFrame.
data = api.load(folder)
print(data)

# 2. Identify (the default pipeline: differential evolution, then least squares from several starts).
result = api.identify(data)
print(result)  # the command line's table: estimate, unit, standard error, fit quality, warnings
for name, value in result.estimate.items():
    se = result.standard_error.get(name)
    print(f"{name} = {value:.5g} {result.units[name]}" + (f" +- {se:.2g}" if se is not None else " (not searched)"))
result.to_json(out / "identification.json")

# 3. Diagnose: which unmodelled effect explains the misfit the warnings report.
diagnosis = api.diagnose(data, candidates=["double_cage"], budget=2000, polish_budget=400)
print(f"diagnosis: {diagnosis.status}, effects {diagnosis.effects}, held-out gap {diagnosis.gap_before:.3g} -> "
      f"{diagnosis.gap_after:.3g} times the noise ({100 * diagnosis.explained_share:.0f} % of the excess explained)")
diagnosis.to_json(out / "diagnosis.json")

# 4. Export the identified model.
print("MATLAB:", result.to_mat(out / "model.mat"))
try:
    print("motulator:", result.to_motulator().machine_pars)
except ImportError as exc:  # motulator is the optional extra imbench[validation]
    print(exc)
