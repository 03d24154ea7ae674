"""The identified model out of imbench: motulator's model objects and a MATLAB ``.mat`` file."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from benchmark.core.errors import ConfigError

#: What :meth:`benchmark.api.Identification.to_motulator` needs (the optional extra ``validation``).
MOTULATOR_HINT = "motulator is not installed: pip install 'imbench[validation]' (or pip install motulator==0.5.*)"


@dataclass
class MotulatorModel:
    """The identified motor as motulator 0.5 objects.

    Attributes
    ----------
    machine_pars
        ``motulator.drive.utils.InductionMachinePars``, the Gamma model (``R_s``,
        ``R_r`` in ohm, ``L_ell``, ``L_s`` in H, ``n_p`` pole pairs) equivalent to the identified
        ``Rs, Ls, Le, Rr`` (whose rotor is referred so that ``Lr = Ls``).
    machine
        ``motulator.drive.model.InductionMachine(machine_pars)``.
    mechanics
        ``motulator.drive.model.StiffMechanicalSystem`` with the identified inertia
        ``J`` (kg m^2) and the friction torque ``fv w_M + fc sign(w_M)`` (N m) as its load
        coefficient ``B_L(|w_M|) = fv + fc / max(|w_M|, 1e-3 rad/s)``.
    """

    machine_pars: Any
    machine: Any
    mechanics: Any


def motulator_model(estimate: dict, pole_pairs: int | None, problem: str = "timedomain") -> MotulatorModel:
    """:class:`MotulatorModel` of a time-domain estimate (``Rs, Ls, Le, Rr`` in ohm and H, ``J`` in
    kg m^2, ``fv`` in N m s/rad, ``fc`` in N m) for a motor of ``pole_pairs``."""
    if problem != "timedomain":
        raise ConfigError(f"to_motulator: motulator simulates the time-domain model; a {problem} estimate "
                          "(a steady-state equivalent circuit) has no inertia or friction to export")
    if not pole_pairs:
        raise ConfigError("to_motulator: the pole pairs are unknown (identify a data set, whose meta.yaml gives them)")
    try:
        from motulator.drive import model
        from motulator.drive.utils import InductionMachinePars
    except ImportError as exc:
        raise ImportError(MOTULATOR_HINT) from exc
    from synthetic.motulator_source import COULOMB_SMOOTHING, gamma_from_project

    gamma = gamma_from_project(estimate)
    pars = InductionMachinePars(n_p=int(pole_pairs), **gamma)
    fv, fc = float(estimate["fv"]), float(estimate["fc"])

    def friction_coefficient(speed):
        return fv + fc / np.maximum(speed, COULOMB_SMOOTHING)

    mechanics = model.StiffMechanicalSystem(J=float(estimate["J"]), B_L=friction_coefficient)
    return MotulatorModel(machine_pars=pars, machine=model.InductionMachine(pars), mechanics=mechanics)


def write_mat(path, result) -> Path:
    """Write an identification to a MATLAB ``.mat`` file (version 5, ``load`` reads it): one
    scalar per parameter (``Rs``, ``Ls``, ... in SI units), the structs ``units``,
    ``standard_error`` (NaN where a parameter was not searched) and ``truth`` (synthetic data),
    ``parameter_names`` and ``correlation`` (searched parameters), ``pole_pairs`` (0 when
    unknown), ``cost``, ``seed``, and the strings ``problem``, ``optimizer``, ``status``."""
    import scipy.io

    path = Path(path)
    if path.suffix.lower() != ".mat":
        path = path.with_suffix(".mat")
    se = result.standard_error
    doc = {name: float(value) for name, value in result.estimate.items()}
    doc.update(
        units={k: result.units.get(k, "") for k in result.estimate},
        standard_error={k: float("nan") if se.get(k) is None else float(se[k]) for k in result.estimate},
        parameter_names=np.array(list(result.correlation.index) if result.correlation is not None else [],
                                 dtype=object),
        correlation=np.asarray(result.correlation.to_numpy() if result.correlation is not None else np.zeros((0, 0))),
        pole_pairs=int(result.pole_pairs or 0), cost=float("nan") if result.cost is None else float(result.cost),
        seed=int(result.seed), problem=result.problem, optimizer=result.optimizer, status=result.status,
    )
    if result.truth:
        doc["truth"] = {k: float(v) for k, v in result.truth.items() if isinstance(v, int | float)}
    path.parent.mkdir(parents=True, exist_ok=True)
    scipy.io.savemat(path, doc, oned_as="column")
    return path
