"""Every effect declares the unit of each of its augmentation's extra parameters (issue 37: units
in every parameter table), and the reports show them."""

from __future__ import annotations

import pytest

from benchmark.core.effects import Effect, load_effects, unit_suffix
from benchmark.problems.timedomain.diagnosis.run import fitted_parameter


def _all_subclasses(cls):
    for sub in cls.__subclasses__():
        yield sub
        yield from _all_subclasses(sub)


@pytest.mark.parametrize("problem", ["timedomain", "admittance"])
def test_every_registered_effect_has_one_unit_per_extra_parameter(problem):
    effects = load_effects(problem)
    assert len(effects) >= 6  # the conf/effect/*.yaml catalogue of the problem, not an empty list
    for name, eff in effects.items():
        assert eff.extra_names, name
        assert len(eff.extra_units) == len(eff.extra_names), (name, eff.extra_names, eff.extra_units)
        for p, unit in zip(eff.extra_names, eff.extra_units, strict=True):
            assert isinstance(unit, str) and unit.strip(), (name, p)
            assert eff.extra_unit(p) == unit
        assert eff.describe()["extra_units"] == list(eff.extra_units)


def test_every_effect_class_with_extra_parameters_declares_their_units():
    """Also the classes no YAML names (yet): a unit cannot be forgotten by leaving out the YAML."""
    classes = [c for c in _all_subclasses(Effect) if c.__module__.startswith("benchmark.") and c.extra_names]
    assert len(classes) >= 19
    missing = [c.__qualname__ for c in classes if len(c.extra_units) != len(c.extra_names)]
    assert not missing


def test_a_fitted_parameter_reads_with_its_unit():
    assert fitted_parameter("load_step", {"value": 0.2687, "standard_error": 0.0031,
                                          "unit": "p.u. of torque scale"}) == \
        "load_step = 0.2687 p.u. of torque scale +- 0.0031 p.u. of torque scale"
    # dimensionless (-) and documents written before units: bare numbers
    assert fitted_parameter("ms_exp", {"value": 6.0, "standard_error": 0.5, "unit": "-"}) == "ms_exp = 6 +- 0.5"
    assert fitted_parameter("ms_exp", {"value": 6.0, "standard_error": 0.5}) == "ms_exp = 6 +- 0.5"
    assert unit_suffix("K") == " K" and unit_suffix(None) == ""
