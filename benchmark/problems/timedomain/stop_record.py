"""Whether a stop record is a free coast of the machine the start-up shows: one check, used by the
identification (:meth:`benchmark.problems.timedomain.problem.TimeDomainProblem.second_look`) and
by the diagnosis's base identification (:mod:`benchmark.problems.timedomain.diagnosis.run`).

The free-stop pre-identification takes the stop record for a coast braked by friction alone
(``tau_m = J / fv`` and ``fc / J``). An inverter that holds its zero vector after the start
short-circuits the stator: the trapped flux brakes the rotor to rest within a few rotor time
constants, and the free-stop fit takes that for a mechanical time constant of 14 ms; a brake
or another load does the same. The start-up then has to be fitted with a friction tens of
times the motor's, and J ends far off (blind sets: a tenth to a twentieth of the truth). The
check fits the start-up alone (``fv`` and ``fc`` searched) and compares the two inertias
(:func:`stop_record_check`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

#: A stop record whose free-coast constants give a J more than this factor away from the
#: start-up's own J (fitted without the stop record) is set aside (:func:`stop_record_check`).
STOP_INERTIA_CONFLICT = 2.0


def startup_alone(settings, ds):
    """The problem of the start-up alone that :func:`stop_record_check` identifies (``fv`` and ``fc``
    searched), or None where there is no check (no stop record, or J not searched)."""
    from benchmark.problems.timedomain.problem import problem_from_dataset  # (problem.py imports this module)

    if ds is None or not ds.stops or ds.inertia is not None or settings.known_inertia is not None:
        return None
    return problem_from_dataset(settings, dataclasses.replace(ds, stops=[]), truth=None)


def stop_record_check(settings, ds, problem, ident, identify: Callable,
                      seed: int, alone_identified: tuple | None = None) -> tuple[dict, object, object] | None:
    """Whether the stop record is a free coast of the machine the start-up shows: the start-up
    fitted alone (``fv`` and ``fc`` searched, one seed) must find a J within a factor
    :data:`STOP_INERTIA_CONFLICT` of the J of the fit that takes ``tau_m`` and ``fc/J`` from the
    stop record; else, when the start-up alone is also fitted better by the start-up-alone
    parameters than by those found with the stop, the stop record is set aside (``used`` False,
    and the start-up-alone fit becomes the base). A start-up-alone search that stopped in a
    worse basin (blind plant seed 18, set 3: J 0.16 of the truth, the stop's J right) keeps the
    stop. ``settings`` are the problem's :class:`~benchmark.problems.timedomain.settings.
    TimeDomainSettings`, ``ds`` the data set it was made from, ``ident`` its identification
    (``.x``), ``identify(problem, seed=...)`` the identification to run on the start-up alone
    (``alone_identified``: the :func:`startup_alone` problem and its identification, already run).
    Returns the record of the check, the start-up-alone problem and its identification; None
    when there is no stop record or J is not searched.

    On 114 blind stop records (independent plant, own plant, motulator) the two J agreed within
    0.76-1.64 on every free coast, loaded or not (the start-up alone was the closer to the truth
    at both ends); on five independent-plant 7.5 kW six-step starts followed by a zero vector
    they differed 6-19 fold (J with the stop 0.05-0.16 of the truth, the start-up alone
    0.96-1.00), and three of those five had been diagnosed `unexplained` at 47-99 times the
    noise. A later draw flagged a sixth such start, with a fan load at 56 % of rated torque
    (ratio 0.34, J with the stop 0.33 of the truth)."""
    if alone_identified is not None:
        alone, ident_alone = alone_identified
    else:
        alone = startup_alone(settings, ds)
        if alone is None:
            return None
        ident_alone = identify(alone, seed=seed)
    if ident_alone.x is None:
        return None
    with_stop = problem.estimate(ident.x)
    j_stop, j_alone = float(with_stop["J"]), float(alone.estimate(ident_alone.x)["J"])
    ratio = j_stop / j_alone if j_alone > 0 else math.inf
    # the start-up's own cost at the parameters found with the stop: a start-up-alone search that
    # stopped in a worse basin than those parameters is no evidence against the stop record
    x_with_stop = np.array([[with_stop[n] for n in alone.parameter_names]])
    cost_with_stop = float(alone.evaluate(x_with_stop)[0])
    cost_alone = float(alone.evaluate(np.atleast_2d(ident_alone.x))[0])
    conflict = not 1.0 / STOP_INERTIA_CONFLICT <= ratio <= STOP_INERTIA_CONFLICT
    used = bool(not conflict or cost_with_stop <= cost_alone)
    return ({"used": used, "conflict": conflict, "J_with_stop": j_stop, "J_start_alone": j_alone, "ratio": ratio,
             "start_alone_cost": cost_alone, "start_cost_at_stop_fit": cost_with_stop}, alone, ident_alone)


def stop_record_lines(sr: dict | None, uses: str = "the diagnosis uses") -> list[str]:
    """What a report says about a :func:`stop_record_check` record: a stop record set aside (or
    kept although the start-up alone found another J); empty when the two agreed. ``uses``
    names who goes on with the start-up alone."""
    if sr and not sr["used"]:
        return [f"Stop record set aside: with it the fit finds J = {sr['J_with_stop']:.4g} kg m^2, from the "
                f"start-up alone J = {sr['J_start_alone']:.4g} kg m^2 ({sr['ratio']:.3g} times; more than "
                f"{STOP_INERTIA_CONFLICT:g} apart). The stop record is no free coast of this machine (an "
                f"inverter holding a zero vector brakes it, or a brake, or another load): {uses} "
                "the start-up alone, with fv and fc searched."]
    if sr and sr.get("conflict"):
        return [f"Stop record kept: the start-up alone found J = {sr['J_start_alone']:.4g} kg m^2 against "
                f"{sr['J_with_stop']:.4g} with the stop ({sr['ratio']:.3g} times), but it fits the start-up "
                f"worse than the parameters found with the stop do (cost {sr['start_alone_cost']:.6g} "
                f"against {sr['start_cost_at_stop_fit']:.6g}): that search stopped in another basin."]
    return []
