"""What every effect of the catalogue shares: the build it edits and the form draw.

An effect has ``draw(rng, motor, form, forms, scenario) -> spec`` (a dict ``{name, form, size,
unit, ...}`` with everything needed to rebuild it) and ``apply(build, spec) -> dict`` (changes
the plant or sensor settings being assembled; returns what was actually realised, for
``truth.yaml``). Its forms come from :mod:`~synthetic.independent.forms`: a draw picks one of
the form set it is told (``development`` by default, draw for draw the plant's behaviour before
the held-out forms existed), limited to the forms that occur in the scenario when it is given.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from synthetic.independent.forms import SCENARIOS, all_forms, forms_of
from synthetic.independent.motors import Motor


@dataclass
class Build:
    """What the effects edit: the plant's parts, the sensor settings, the channel timing
    (``skew``: ``current``/``voltage`` lags in samples; held out, ``filter`` a Bessel filter's
    group delay in samples and ``mux`` a multiplexed card's ``slot`` (samples between two
    channels) and channel ``order``)
    and requests for the data-set maker (sizing that needs a simulation); ``scenario`` and
    ``duration`` (s) are read-only context."""

    motor: Motor
    scenario: object
    duration: float
    plant: dict = field(default_factory=dict)
    sensors: dict = field(default_factory=dict)
    skew: dict = field(default_factory=lambda: {"current": 0.0, "voltage": 0.0})
    requests: dict = field(default_factory=dict)

    @property
    def machine(self):
        return self.plant["machine"]


def signed(rng, lo, hi):
    """A magnitude uniform in ``[lo, hi]`` with a random sign."""
    return float(rng.choice([-1.0, 1.0]) * rng.uniform(lo, hi))


def log_uniform(rng, lo, hi):
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))


class Effect:
    name = ""
    unit = ""
    inverter_only = False

    @property
    def forms(self) -> tuple[str, ...]:
        """All forms, development first (:mod:`~synthetic.independent.forms`)."""
        return all_forms(self.name)

    def random_form(self, rng: np.random.Generator, forms: str = "development", scenario: str | None = None) -> str:
        """A form drawn uniformly from form set ``forms`` (``development``, ``heldout``,
        ``all``), among those that occur in a ``scenario`` kind (None: any)."""
        pool = forms_of(self.name, forms, scenario)
        if not pool:
            raise ValueError(f"{self.name}: no {forms} form occurs in a {scenario} start")
        return str(rng.choice(pool))

    def draw(self, rng: np.random.Generator, motor: Motor, form: str | None = None, forms: str = "development",
             scenario: str | None = None) -> dict:
        form = form if form is not None else self.random_form(rng, forms, scenario)
        if form not in self.forms:
            raise ValueError(f"{self.name}: form must be one of {self.forms}, got {form!r}")
        self.check_scenario(form, scenario)
        spec = {"name": self.name, "form": form, "unit": self.unit}
        spec.update(self._draw(rng, motor, form))
        return spec

    def check_scenario(self, form: str, scenario: str | None) -> None:
        if scenario is not None and scenario not in SCENARIOS.get(form, (scenario,)):
            raise ValueError(f"{self.name}: form {form!r} occurs only in {SCENARIOS[form]} starts, not {scenario}")

    def _draw(self, rng, motor, form) -> dict:
        raise NotImplementedError

    def apply(self, build: Build, spec: dict) -> dict:
        if self.inverter_only and build.scenario.kind == "dol":
            raise ValueError(f"{self.name} needs an inverter-fed scenario (six_step or pwm)")
        self.check_scenario(spec["form"], build.scenario.kind)
        return self._apply(build, spec) or {}

    def _apply(self, build, spec):
        raise NotImplementedError
