"""The scores of a blind evaluation and their report: exact sets, false alarms, pairs, with
Wilson intervals (see :mod:`benchmark.analysis.blind` for what is drawn and how it is scored).
"""

from __future__ import annotations

import math

import numpy as np

from benchmark.core.uncertainty import wilson

__all__ = ["summarise", "wilson"]


def summarise(rows: list[dict]) -> dict:
    """Scores of one source (see the module docstring). A set whose diagnosis raised is a miss of
    every score it enters; one the source could not make is left out (``failed_sets`` lists both)."""
    failed = [r for r in rows if r["status"] == "error"]
    rows_made = [r for r in rows if r.get("error_stage") != "make"]
    scored = [r for r in rows_made if not r["invisible"]]
    left_out = [r for r in rows_made if r["invisible"]]
    eff_rows = [r for r in scored if r["truth"] != "none"]
    free = [r for r in rows_made if r["truth"] == "none"]
    two = [r for r in scored if len(r["truth_effects"]) == 2]
    correct = [r for r in scored if r["truth"] == r["predicted"]]
    eff_correct = [r for r in eff_rows if r["truth"] == r["predicted"]]
    alarms = [r for r in free if r["status"] != "no_gap" or r["predicted"] != "none"]
    both = [r for r in two if set(r["truth_effects"]) <= set(r["effects"])]
    shares = [r["explained_share"] for r in eff_correct]
    # names the rule gave but a noise estimate within its band would not (Rule.firm), right or not
    named = [(e, e in r["truth_effects"]) for r in scored for e in _rule_names(r)]
    not_firm = [(e, e in r["truth_effects"]) for r in scored for e in r.get("not_firm", [])]
    # false selections: scored sets where the rule named an effect that was not injected
    falsely = [r for r in scored if any(e not in r["truth_effects"] for e in _rule_names(r))]
    # the catch-all: channel_delay named on sets where it was not injected (every set made: the
    # diagnosis may name it on a set left out of the other scores too)
    no_delay = [r for r in rows_made if "channel_delay" not in r.get("injected", r["truth"]).split("+")]
    delay_named = [r for r in no_delay if "channel_delay" in r["effects"]]
    labels = sorted({r["truth"] for r in rows} | {r["predicted"] for r in rows},
                    key=lambda s: (s in ("none", "unexplained"), s.count("+"), s))
    idx = {k: i for i, k in enumerate(labels)}
    cm = np.zeros((len(labels), len(labels)), dtype=int)
    for r in scored:
        cm[idx[r["truth"]], idx[r["predicted"]]] += 1
    statuses = {}
    for r in rows:
        statuses[r["status"]] = statuses.get(r["status"], 0) + 1
    return {
        "n": len(rows), "scored": len(scored),
        "failed_sets": [{"index": r["index"], "truth": r["truth"], "stage": r["error_stage"], "message": r["verdict"]}
                        for r in failed],
        "left_out_invisible": [{"index": r["index"], "truth": r["truth"], "gap_before": r["gap_before"]}
                               for r in left_out],
        "left_out_of_pairs": [{"index": r["index"], "injected": r["injected"], "effect": e,
                               "gap_alone": r.get("alone_gaps", {}).get(e, math.nan)}
                              for r in rows for e in r.get("left_out_effects", [])],
        "exact": len(correct), "exact_rate": len(correct) / len(scored) if scored else math.nan,
        "exact_ci95": wilson(len(correct), len(scored)),
        "effect_sets": len(eff_rows), "effect_sets_exact": len(eff_correct),
        "effect_sets_exact_rate": len(eff_correct) / len(eff_rows) if eff_rows else math.nan,
        "effect_sets_exact_ci95": wilson(len(eff_correct), len(eff_rows)),
        "effect_free_sets": len(free), "false_alarms": len(alarms),
        "false_alarm_rate": len(alarms) / len(free) if free else math.nan,
        "false_alarm_ci95": wilson(len(alarms), len(free)),
        "two_effect_sets": len(two), "both_named": len(both),
        "both_named_rate": len(both) / len(two) if two else math.nan,
        "both_named_ci95": wilson(len(both), len(two)),
        "median_explained_share_correct": float(np.median(shares)) if shares else math.nan,
        "statuses": statuses, "labels": labels, "confusion": cm.tolist(),
        "names_right": sum(ok for _, ok in named), "names_wrong": sum(not ok for _, ok in named),
        "not_firm_right": sum(ok for _, ok in not_firm), "not_firm_wrong": sum(not ok for _, ok in not_firm),
        "false_selection_sets": len(falsely), "false_selection_ci95": wilson(len(falsely), len(scored)),
        "channel_delay_not_injected": len(no_delay), "channel_delay_named": len(delay_named),
        "channel_delay_ci95": wilson(len(delay_named), len(no_delay)),
        "warned_sets": [r["index"] for r in scored if r.get("warnings")],  # a Check: line in diagnosis.md
    }


def _rule_names(row: dict) -> list[str]:
    """The effects of a verdict that the selection rule named (not those the conditioning on
    load removed, nor those the base model holds)."""
    return [e for e in row["effects"] if e not in row.get("conditioned", []) and e not in row.get("held_by_base", [])]


def _pct(x):
    return "n/a" if x != x else f"{100 * x:.0f} %"


def _ci(c):
    return "" if c[0] != c[0] else f" (95 % CI {100 * c[0]:.0f}-{100 * c[1]:.0f} %)"


def render(summary: dict, rows: list[dict], cmd: str, title: str, tuned: str) -> str:
    s = summary
    lines = [title, "", f"Command: `{cmd}`", "", f"Thresholds: {tuned}", "",
             f"- {s['n']} data sets, {s['scored']} scored; exact effect set named: **{s['exact']} of {s['scored']} "
             f"({_pct(s['exact_rate'])}){_ci(s['exact_ci95'])}**",
             f"- sets with effects: {s['effect_sets_exact']} of {s['effect_sets']} exact "
             f"({_pct(s['effect_sets_exact_rate'])}){_ci(s['effect_sets_exact_ci95'])}",
             f"- false alarms on effect-free sets: {s['false_alarms']} of {s['effect_free_sets']} "
             f"({_pct(s['false_alarm_rate'])}){_ci(s['false_alarm_ci95'])}",
             f"- two-effect sets with both named: {s['both_named']} of {s['two_effect_sets']} "
             f"({_pct(s['both_named_rate'])}){_ci(s['both_named_ci95'])}",
             f"- median explained share of the excess held-out misfit, correct verdicts with effects: "
             f"{_pct(s['median_explained_share_correct'])}",
             "- statuses: " + ", ".join(f"{k} {v}" for k, v in sorted(s["statuses"].items())),
             f"- names the rule gave that are not firm (a noise estimate within its band would not give them): "
             f"{s['not_firm_right']} of {s['names_right']} right names, {s['not_firm_wrong']} of "
             f"{s['names_wrong']} wrong ones"]
    for r in s.get("failed_sets", []):
        lines.append(f"- set {r['index']} ({r['truth']}): {r['message']}"
                     + (" (left out of the score)" if r["stage"] == "make" else " (a miss)"))
    if s["left_out_invisible"]:
        lines.append("- left out of the score (injected, but the base model's held-out gap is within the noise "
                     "band): " + ", ".join(f"set {r['index']} ({r['truth']}, {r['gap_before']:.2f})"
                                          for r in s["left_out_invisible"]))
    if s.get("warned_sets"):
        lines.append("- sets whose diagnosis.md opens with a **Check:** line (a speed filter nobody stated): "
                     + ", ".join(map(str, s["warned_sets"])))
    if s.get("left_out_of_pairs"):
        lines.append("- effects of two-effect sets left out (their own base-model gap, the set made with that effect "
                     "alone, within the noise band; not named; the set scored on the other): "
                     + ", ".join(f"set {r['index']} {r['effect']} of {r['injected']} ({r['gap_alone']:.2f})"
                                 for r in s["left_out_of_pairs"]))
    labels, cm = s["labels"], np.array(s["confusion"])
    lines += ["", "Rows: the injected set (less a left-out effect); columns: the verdict (scored sets).", "",
              "| truth \\ verdict | " + " | ".join(labels) + " |", "|---|" + "---|" * len(labels)]
    for i, lab in enumerate(labels):
        if cm[i].sum():
            lines.append(f"| {lab} | " + " | ".join(str(v) if v else "." for v in cm[i]) + " |")
    lines += ["", "| set | truth | status | verdict | held-out gap before | after | explained share | s |",
              "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        truth = r["truth"] if r.get("injected", r["truth"]) == r["truth"] else f"{r['truth']} (of {r['injected']})"
        lines.append(f"| {r['index']} | {truth} | {r['status']} | {r['verdict']} | {r['gap_before']:.2f} "
                     f"| {r['gap_after']:.2f} | {_pct(r['explained_share'])} | {r['wall_time_s']:.0f} |")
    return "\n".join(lines) + "\n"
