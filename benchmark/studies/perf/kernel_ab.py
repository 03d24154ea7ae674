"""The extended model's kernel and the eddy-current brake's coast of one checkout against another's,
on the rows a real diagnosis gives them, in one process (so the ratio compares like with like on
a shared machine).

``capture`` diagnoses a record (``python -m benchmark.diagnose data.path=DIR``, figures off) and
keeps every row the kernel is given (:func:`~benchmark.problems.timedomain.extended.simulate_extended_batch`
through the diagnosis's row cache), the record's input, and the first calls of the brake's
coast (:func:`~benchmark.problems.timedomain.diagnosis.free_coast._brake_coast`). ``compare``
loads the reference checkout's ``extended.py`` and ``free_coast.py`` as modules of their own
(their imports resolve to this checkout: a change in another compiled file is not compared),
draws ``rows`` of the captured rows, and times both kernels alternately on one thread, best of
``rounds``, then both coasts on every captured call; it prints the ratios new / reference and
whether the outputs are the same bit for bit::

    python -m benchmark.studies.perf.kernel_ab capture /work/perf/recs/plant_6pole_dol_leakage rows.pkl
    python -m benchmark.studies.perf.kernel_ab compare rows.pkl REFERENCE_CHECKOUT [rows=600] [rounds=4] [seed=0]
"""

from __future__ import annotations

import importlib.util
import pickle
import sys
import tempfile
import time
from pathlib import Path

import numba
import numpy as np

#: Brake-coast calls kept by ``capture`` (each a few rows over the stop).
COAST_CALLS = 400


def capture(record: Path, out: Path) -> None:
    """Diagnose ``record`` and pickle the kernel's rows, the input and the coast calls to ``out``."""
    import benchmark.problems.timedomain.diagnosis.free_coast as free_coast
    import benchmark.problems.timedomain.diagnosis.kernel_cache as kernel_cache
    from benchmark import api

    kept: dict = {"rows": [], "input": None, "coasts": []}
    kernel, coast = kernel_cache.simulate_extended_batch, free_coast._brake_coast

    def kernel_kept(rows, v_a, v_b, linear, h, substeps):
        kept["rows"].append(np.array(rows))
        if kept["input"] is None:
            kept["input"] = (np.array(v_a), np.array(v_b), bool(linear), float(h), int(substeps))
        return kernel(rows, v_a, v_b, linear, h, substeps)

    def coast_kept(*args):
        if len(kept["coasts"]) < COAST_CALLS:
            kept["coasts"].append(tuple(np.array(a) for a in args))
        return coast(*args)

    kernel_cache.simulate_extended_batch, free_coast._brake_coast = kernel_kept, coast_kept
    try:
        with tempfile.TemporaryDirectory() as tmp:
            d = api.diagnose(str(record), outdir=tmp, figures=False)
    finally:
        kernel_cache.simulate_extended_batch, free_coast._brake_coast = kernel, coast
    rows = np.concatenate(kept["rows"])
    with open(out, "wb") as f:
        pickle.dump({"record": str(record), "verdict": d.verdict, "rows": rows, "input": kept["input"],
                     "coasts": kept["coasts"]}, f)
    print(f"{record}: {d.verdict}; {len(rows)} kernel rows in {len(kept['rows'])} calls, "
          f"{len(kept['coasts'])} brake-coast calls kept -> {out}")


def _module(path: Path, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _alternate(fa, fb, rounds: int) -> tuple[float, float, object, object]:
    """Best times of ``fa()`` and ``fb()`` called alternately, and their last outputs."""
    ta, tb = [], []
    for _ in range(rounds):
        t = time.perf_counter()
        oa = fa()
        ta.append(time.perf_counter() - t)
        t = time.perf_counter()
        ob = fb()
        tb.append(time.perf_counter() - t)
    return min(ta), min(tb), oa, ob


def compare(captured: Path, reference: Path, rows: int = 600, rounds: int = 4, seed: int = 0) -> dict:
    """Time this checkout's kernel and coast against ``reference``'s on ``captured``; prints and
    returns the figures."""
    from benchmark.problems.timedomain import extended
    from benchmark.problems.timedomain.diagnosis import free_coast

    with open(captured, "rb") as f:
        cap = pickle.load(f)
    ref_root = Path(reference) / "benchmark" / "problems" / "timedomain"
    ref_kernel = _module(ref_root / "extended.py", "_reference_extended")
    ref_coast = _module(ref_root / "diagnosis" / "free_coast.py", "_reference_free_coast")
    all_rows = cap["rows"]
    rng = np.random.default_rng(seed)
    pick = all_rows[np.sort(rng.choice(len(all_rows), size=min(rows, len(all_rows)), replace=False))]
    v_a, v_b, linear, h, substeps = cap["input"]
    numba.set_num_threads(1)
    for fn in (ref_kernel.simulate_extended_batch, extended.simulate_extended_batch):
        fn(pick[:2], v_a, v_b, linear, h, substeps)  # compiled (or loaded from the cache) before timing
    t_ref, t_new, o_ref, o_new = _alternate(
        lambda: ref_kernel.simulate_extended_batch(pick, v_a, v_b, linear, h, substeps),
        lambda: extended.simulate_extended_batch(pick, v_a, v_b, linear, h, substeps), rounds)
    out = {"record": cap["record"], "rows": len(pick), "samples": len(v_a),
           "kernel_reference_s": t_ref, "kernel_new_s": t_new, "kernel_ratio": t_new / t_ref,
           "kernel_same": bool(np.array_equal(o_ref, o_new, equal_nan=True))}
    print(f"{cap['record']}: kernel, {len(pick)} rows of {len(v_a)} samples on one thread: reference {t_ref:.3f} s, "
          f"new {t_new:.3f} s, new/reference {t_new / t_ref:.3f}; the same bit for bit: {out['kernel_same']}")
    calls = cap["coasts"]
    if calls:
        for fn in (ref_coast._brake_coast, free_coast._brake_coast):
            fn(*calls[0])
        t_ref, t_new, _, _ = _alternate(lambda: [ref_coast._brake_coast(*a) for a in calls],
                                        lambda: [free_coast._brake_coast(*a) for a in calls], rounds)
        same = all(np.array_equal(ref_coast._brake_coast(*a), free_coast._brake_coast(*a)) for a in calls)
        n_rows = sum(len(a[1]) for a in calls)
        out.update(coast_calls=len(calls), coast_rows=n_rows, coast_reference_s=t_ref, coast_new_s=t_new,
                   coast_ratio=t_new / t_ref, coast_same=same)
        print(f"{cap['record']}: brake coast, {len(calls)} calls ({n_rows} rows): reference {t_ref:.3f} s, "
              f"new {t_new:.3f} s, new/reference {t_new / t_ref:.3f}; the same bit for bit: {same}")
    return out


def main(argv: list[str]) -> None:
    if len(argv) >= 3 and argv[0] == "capture":
        capture(Path(argv[1]), Path(argv[2]))
    elif len(argv) >= 3 and argv[0] == "compare":
        keys = dict(a.split("=", 1) for a in argv[3:])
        compare(Path(argv[1]), Path(argv[2]), **{k: int(v) for k, v in keys.items()})
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    np.seterr(all="ignore")
    main(sys.argv[1:])
