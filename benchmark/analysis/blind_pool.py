"""The scores of several blind evaluations pooled per source, by the same scoring as each alone.

Each folder is an ``out`` of ``python -m benchmark.blind`` (one ``SOURCE/blind.json`` per source
drawn); the sets of every folder are scored together by
:func:`~benchmark.analysis.blind_report.summarise`, and one row per source is printed: effect sets
named exactly, false alarms, both effects of a pair, the sets where the rule named an effect that
was not injected (its false-selection rate), ``channel_delay`` named where it was not injected,
each with its Wilson 95 % interval; then the diagnoses' wall times per source (median, 90th
percentile, maximum, the sets over a minute, the slowest set's injected effects), as the draws
recorded them: a draw's machine and what else ran on it (two sources diagnosed side by side share
its cores) are the draw's, not this table's::

    python -m benchmark.analysis.blind_pool results/blind/heldout_fast results/blind/heldout_fast2
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from benchmark.analysis.blind_report import summarise
from benchmark.studies.perf.diagnosis_report import TARGET_S


def scored_sets(folders: list[Path]) -> dict[str, list[dict]]:
    """The sets' rows of every ``SOURCE/blind.json`` in ``folders``, by source (in the order first found)."""
    rows: dict[str, list[dict]] = {}
    for folder in folders:
        found = sorted(Path(folder).glob("*/blind.json"))
        if not found:
            raise FileNotFoundError(f"{folder}: no SOURCE/blind.json (an `out` folder of python -m benchmark.blind)")
        for path in found:
            rows.setdefault(path.parent.name, []).extend(json.loads(path.read_text())["sets"])
    return rows


def pooled(folders: list[Path]) -> dict[str, dict]:
    """The pooled summary per source found in ``folders`` (sources in the order first found)."""
    return {source: summarise(sets) for source, sets in scored_sets(folders).items()}


def wall_times(rows: dict[str, list[dict]]) -> dict[str, dict]:
    """The wall times (s) of the diagnoses the draws recorded (``rows``: :func:`scored_sets`), per source and kind
    of set (keys ``"SOURCE, effect sets"`` and ``"SOURCE, effect-free sets"``; an effect-free set
    whose gap is at the noise level ends after its base identification): ``sets`` timed,
    ``median``, ``p90`` (90th percentile), ``max``, ``over_target`` (sets above :data:`TARGET_S`)
    and ``slowest`` (the injected effects of the slowest set, ``none`` if none)."""
    out = {}
    for source, sets in rows.items():
        for kind, chosen in (("effect sets", [s for s in sets if s.get("truth_effects")]),
                             ("effect-free sets", [s for s in sets if not s.get("truth_effects")])):
            timed = [s for s in chosen if s.get("wall_time_s") is not None]
            if not timed:
                continue
            t = np.array([float(s["wall_time_s"]) for s in timed])
            slowest = timed[int(np.argmax(t))]
            out[f"{source}, {kind}"] = {"sets": len(t), "median": float(np.median(t)),
                                        "p90": float(np.percentile(t, 90)), "max": float(t.max()),
                                        "over_target": int(np.sum(t > TARGET_S)),
                                        "slowest": slowest.get("truth") or "none"}
    return out


def _share(k: int, n: int, ci: list[float]) -> str:
    if not n:
        return "-"
    return f"{k}/{n}, {100 * k / n:.0f} % ({100 * ci[0]:.0f}-{100 * ci[1]:.0f} %)"


def table(summaries: dict[str, dict]) -> str:
    """A markdown table of :func:`pooled`'s summaries."""
    lines = ["| source | effect sets named exactly | false alarms | both of a pair | sets with a false selection "
             "| `channel_delay` where not injected |", "|---|---|---|---|---|---|"]
    for source, s in summaries.items():
        lines.append(f"| {source} | {_share(s['effect_sets_exact'], s['effect_sets'], s['effect_sets_exact_ci95'])} "
                     f"| {_share(s['false_alarms'], s['effect_free_sets'], s['false_alarm_ci95'])} "
                     f"| {_share(s['both_named'], s['two_effect_sets'], s['both_named_ci95'])} "
                     f"| {_share(s['false_selection_sets'], s['scored'], s['false_selection_ci95'])} "
                     f"| {_share(s['channel_delay_named'], s['channel_delay_not_injected'], s['channel_delay_ci95'])} "
                     "|")
    return "\n".join(lines) + "\n"


def time_table(times: dict[str, dict]) -> str:
    """A markdown table of :func:`wall_times`."""
    lines = [f"| source | sets timed | median s | 90th percentile s | maximum s | over {TARGET_S:.0f} s "
             "| slowest set |", "|---|---|---|---|---|---|---|"]
    for source, t in times.items():
        lines.append(f"| {source} | {t['sets']} | {t['median']:.0f} | {t['p90']:.0f} | {t['max']:.0f} "
                     f"| {t['over_target']} ({100 * t['over_target'] / t['sets']:.0f} %) | {t['slowest']} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str]) -> None:
    if not argv:
        raise SystemExit("usage: python -m benchmark.analysis.blind_pool OUT_FOLDER [OUT_FOLDER ...]")
    try:
        rows = scored_sets([Path(a) for a in argv])
        print(table({source: summarise(sets) for source, sets in rows.items()}))
        print("Wall time of each diagnosis, as the draws recorded it:\n")
        print(time_table(wall_times(rows)), end="")
    except FileNotFoundError as err:
        raise SystemExit(f"error: {err}") from None


if __name__ == "__main__":
    main(sys.argv[1:])
