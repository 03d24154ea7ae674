"""The scores of several blind evaluations pooled per source, by the same scoring as each alone.

Each folder is an ``out`` of ``python -m benchmark.blind`` (one ``SOURCE/blind.json`` per source
drawn); the sets of every folder are scored together by
:func:`~benchmark.analysis.blind_report.summarise`, and one row per source is printed: effect sets
named exactly, false alarms, both effects of a pair, the sets where the rule named an effect that
was not injected (its false-selection rate), ``channel_delay`` named where it was not injected,
each with its Wilson 95 % interval::

    python -m benchmark.analysis.blind_pool results/blind/heldout_fast results/blind/heldout_fast2
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from benchmark.analysis.blind_report import summarise


def pooled(folders: list[Path]) -> dict[str, dict]:
    """The pooled summary per source found in ``folders`` (sources in the order first found)."""
    rows: dict[str, list[dict]] = {}
    for folder in folders:
        found = sorted(Path(folder).glob("*/blind.json"))
        if not found:
            raise FileNotFoundError(f"{folder}: no SOURCE/blind.json (an `out` folder of python -m benchmark.blind)")
        for path in found:
            rows.setdefault(path.parent.name, []).extend(json.loads(path.read_text())["sets"])
    return {source: summarise(sets) for source, sets in rows.items()}


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


def main(argv: list[str]) -> None:
    if not argv:
        raise SystemExit("usage: python -m benchmark.analysis.blind_pool OUT_FOLDER [OUT_FOLDER ...]")
    try:
        print(table(pooled([Path(a) for a in argv])), end="")
    except FileNotFoundError as err:
        raise SystemExit(f"error: {err}") from None


if __name__ == "__main__":
    main(sys.argv[1:])
