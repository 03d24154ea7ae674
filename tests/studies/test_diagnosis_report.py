"""The perf study's diagnosis report (benchmark/studies/perf/diagnosis_report.py): the spread of
CPU ratios between two runs that computed the same thing, the floor below which a measured
difference is the machine's own (on a 2-core Xeon, 2026-12-07: seven of twelve records identical
to the last digit between two checkouts, CPU ratios 0.91-1.30)."""

from __future__ import annotations

from benchmark.studies.perf.diagnosis_report import identical, render, same_computation_spread


def _summary(cpu, verdict="load_torque", share=0.99):
    return {"wall_s": cpu / 1.7, "cpu_s": cpu, "load_before": 1.0, "status": "explained", "verdict": verdict,
            "effects": verdict.split("+"), "explained_share": share, "pruned": [], "weak_effects": [],
            "drop_one_shares": {e: share for e in verdict.split("+")}, "gap_before": 14.5, "gap_after": 1.0,
            "rounds": [], "inside_wall_s": cpu / 1.8, "inside_cpu_s": cpu * 0.95}


def test_the_spread_counts_only_runs_that_computed_the_same_summary():
    runs = {"plant_1kw_sixstep_probe_coupling": {"reference": _summary(63.8), "new": _summary(56.7)},
            "plant_7k5_pwm_none": {"reference": _summary(10.6, "none", 0.0), "new": _summary(9.6, "none", 0.0)},
            # a last digit apart: not the same computation, whatever its ratio
            "plant_3k7_sixstep_load": {"reference": _summary(56.1), "new": _summary(113.0, share=0.99 + 1e-12)},
            "own_1kw_dol_load_nostop": {"reference": _summary(9.6, "none", 0.0), "new": _summary(10.6, "none", 0.0)}}
    assert identical(runs["plant_7k5_pwm_none"]["new"], runs["plant_7k5_pwm_none"]["reference"])
    assert not identical(runs["plant_3k7_sixstep_load"]["new"], runs["plant_3k7_sixstep_load"]["reference"])
    count, low, high = same_computation_spread(runs)
    assert count == 3
    assert low == 9.6 / 10.6 and high == 63.8 / 56.7
    assert "on the 3 records whose two runs computed the same summary to the last digit, CPU ratios 0.91-1.13" \
        in render(runs)


def test_no_spread_without_two_identical_runs():
    runs = {"plant_7k5_pwm_none": {"reference": _summary(10.6, "none", 0.0), "new": _summary(9.6, "none", 0.0)},
            "plant_3k7_sixstep_load": {"reference": _summary(56.1), "new": _summary(113.0, "load_torque+double_cage")}}
    assert same_computation_spread(runs) is None
    assert same_computation_spread({k: {"new": v["new"]} for k, v in runs.items()}) is None
    assert "own spread" not in render(runs)
