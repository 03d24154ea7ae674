"""A motor started in reverse: the records mirrored so that they turn forwards.

A start whose supply turns backwards (a negative phase sequence), with the currents and the rotor
turning with it (the load checks make sure they do), is the mirror image of a forward start: with
``beta -> -beta`` on the voltages and currents and the speeds negated, a symmetric machine's
equations are the same. The models, the bounds derived from the data and the free stop's friction
are written for a forward start, so the records are mirrored on reading, each on its own, and the
report says so; the identified parameters are those of the motor either way.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from benchmark.core.errors import DataError
from benchmark.problems.timedomain.load_checks import electrical_speed


def _mirrored(rec):
    return replace(rec, v_beta=-rec.v_beta, i_beta=-rec.i_beta, speed=-rec.speed,
                   torque=None if rec.torque is None else -rec.torque)


def turn_forwards(startups: list, stops: list, channel_skew, meta_path) -> tuple[list, list, str | None]:
    """The start-up records whose voltage turns backwards at their end, and the stop records whose speed
    is mostly negative, mirrored (``v_beta``, ``i_beta``, the speed and a measured torque negated); with a
    sentence for the report, or None when every record turns forwards. A multiplexed card's channel
    sequence (``channel_skew`` per phase) names phases the mirror relabels: a DataError asks for the
    relabelling in the file instead."""
    backwards = [k for k, rec in enumerate(startups) if electrical_speed(rec) < 0]
    stopped_backwards = [k for k, rec in enumerate(stops)
                         if np.count_nonzero(rec.speed < 0) > np.count_nonzero(rec.speed > 0)]
    if not backwards and not stopped_backwards:
        return startups, stops, None
    if backwards and isinstance(channel_skew, dict):
        raise DataError(meta_path, "the supply turns backwards in " + ", ".join(startups[k].source for k in backwards)
                        + " (a negative phase sequence) and 'channel_skew' names the card's phase channels: "
                        "relabel phases S and T in the files (v_s <-> v_t, i_s -> -(i_r + i_s)) and negate the "
                        "speed, so that the records turn forwards")
    startups = [_mirrored(r) if k in backwards else r for k, r in enumerate(startups)]
    stops = [replace(r, speed=-r.speed) if k in stopped_backwards else r for k, r in enumerate(stops)]
    names = [startups[k].source for k in backwards] + [stops[k].source for k in stopped_backwards]
    note = ("The motor turns backwards in " + ", ".join(str(n) for n in names) + " (a negative phase sequence, "
            "the speed negative): each is mirrored (v_beta, i_beta and the speed negated) so that it turns "
            "forwards; a symmetric machine's parameters are the same either way, and the records shown are the "
            "mirrored ones.")
    return startups, stops, note
