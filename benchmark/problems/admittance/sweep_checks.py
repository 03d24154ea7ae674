"""Checks on load of a slip sweep's table for mistakes that still produce a result: a slip in
per cent, admittances in mS, a susceptance of the wrong sign. Each is a
:class:`~benchmark.core.errors.DataError` naming the file and column (and row) with the fix. A
cold user's sweep of a textbook circuit gave, with the slip in per cent, "converged" with R2
100 times too large and no warning; in mS, a circuit 1000 times too small; with B positive, a
bounds error about readings near synchronous speed.
"""

from __future__ import annotations

import numpy as np

from benchmark.core.errors import DataError

#: A slip above this is a rotor turning backwards at twice the field's speed, beyond any sweep
#: (Lindsay and Barton's braking reaches 2, the rotor at minus synchronous speed): a column in per cent.
MAX_SLIP = 3.0
#: A sweep whose largest ``Re(1/(G + jB))`` is below this share of the stator's DC resistance
#: cannot be a motor's (every reading's resistance holds the stator's, R1 plus the rotor's or
#: the core's part; the share allows a winding measured hot and a DC value given line to line).
DC_RESISTANCE_SHARE = 0.5


def check_sweep_table(path, slip: np.ndarray | None, G: np.ndarray, B: np.ndarray,
                      stator_dc_resistance: tuple[float, float] | None) -> None:
    """The table ``path``'s slip (per unit, None when given as ``speed_rpm``), ``G`` and ``B``
    (S per phase) against what a motor's sweep can hold."""
    if slip is not None and np.any(np.abs(slip) > MAX_SLIP):
        k = int(np.argmax(np.abs(slip)))
        raise DataError(path, f"slip {slip[k]:.4g}: slip is per unit, (n_s - n) / n_s (0.03 for 3 %), and above "
                              f"{MAX_SLIP:g} the rotor would turn backwards at twice the field's speed: is the "
                              "column in per cent? Divide it by 100", column="slip", row=k + 1)
    positive = int(np.sum(B > 0))
    if positive > len(B) / 2:
        raise DataError(path, f"B is positive on {positive} of {len(B)} readings: a motor's admittance lags its "
                              "voltage, B < 0 per phase (G + jB with the current's phase): negate the column B",
                        column="B")
    if stator_dc_resistance is not None:
        with np.errstate(divide="ignore", invalid="ignore"):
            resistance = np.real(1.0 / (G + 1j * B))
        largest = float(np.nanmax(resistance)) if np.any(np.isfinite(resistance)) else np.nan
        r_dc = min(stator_dc_resistance)
        if largest < DC_RESISTANCE_SHARE * r_dc:
            raise DataError(path, f"every reading's resistance Re(1/(G + jB)) is at most {largest:.4g} ohm, below the "
                                  f"stator's DC resistance {r_dc:.4g} ohm (meta.yaml stator_dc_resistance), which a "
                                  "motor's impedance holds: are G and B in S per phase (not mS), and the DC "
                                  "resistance per phase?", column="G, B")
