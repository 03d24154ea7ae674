"""What a suite is: its instances, optimisers, seeds and budget, read from ``conf/suite_<name>.yaml``.

A suite file lists **blocks**; each block is a cartesian product of its list-valued keys
(a scalar is a list of one), so a few lines describe many instances::

    timedomain:
      - {motors: [alonge_1kw, krause_500hp], source: independent, experiment: [dol, six_step],
         stop: false, noise: white, effect: none}
    admittance:
      - {motors: [lindsay_barton_7p5hp], sweep: [full, motoring], model: [6, 8], noise: 0.003}
    explicit:
      - {name: ..., problem: timedomain, motor: ..., ...}   # one instance, every field given

Time-domain fields: ``source`` (``independent``: the plant of ``synthetic/independent``;
``motulator``), ``experiment`` (``dol``, ``six_step``, ``pwm``), ``stop`` (a free-stop record
too), ``noise`` (``none``, ``white``, ``coloured``: see :mod:`benchmark.studies.suite.instances`),
``effect`` (``none`` or one unmodelled effect of the independent plant). Admittance fields:
``sweep`` (``full``: braking through generating, slip 2 to -1/3; ``motoring``: slip 1 to 0),
``model`` (6 or 8 parameters fitted), ``data_model`` (the circuit that made the data; default
``model``: a 6-parameter fit to an 8-parameter machine is a model-error instance), ``noise``
(the admittance noise as a fraction of full scale). Every instance gets a data seed from its
name (CRC-32), so an instance is the same in every suite that holds it.
"""

from __future__ import annotations

import itertools
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from benchmark.core.config_files import CONFIG_DIR
from benchmark.core.errors import ConfigError

CONF = CONFIG_DIR
TIMEDOMAIN_KEYS = ("motors", "source", "experiment", "stop", "noise", "effect")
ADMITTANCE_KEYS = ("motors", "sweep", "model", "data_model", "noise")


@dataclass(frozen=True)
class InstanceSpec:
    """One instance: a data set (made once) and how it is identified.

    ``noise`` is ``none``/``white``/``coloured`` (time domain) or the admittance noise fraction
    of full scale (admittance); ``effect`` the unmodelled effect (``none`` without model error);
    ``settings`` explicit generator settings (``friction``, ``noise``, ``duration`` s,
    ``sample_rate`` Hz, ``seed``) that replace the zoo's rules."""

    name: str
    problem: str
    motor: str
    source: str
    experiment: str
    stop: bool = False
    noise: str | float = "white"
    effect: str = "none"
    model: int | None = None
    data_model: int | None = None
    settings: dict = field(default_factory=dict, hash=False, compare=False)

    @property
    def seed(self) -> int:
        """The data seed (noise, effect draw, supply imperfections): ``settings.seed`` if given,
        else CRC-32 of the name."""
        if "seed" in self.settings:
            return int(self.settings["seed"])
        return zlib.crc32(self.name.encode()) % (2**31)

    @property
    def held_stop(self) -> bool:
        """An inverter start's stop record: the inverter holds its zero vector and the trapped
        flux brakes the rotor, which the free-stop pre-identification reads as friction."""
        return self.problem == "timedomain" and self.stop and self.experiment != "dol"

    @property
    def model_error(self) -> bool:
        return (self.effect != "none" or self.held_stop
                or (self.model is not None and self.data_model not in (None, self.model)))


@dataclass(frozen=True)
class SuiteSpec:
    """A suite: instances, the optimisers run on each (``optimizers`` on every problem, plus
    ``problem_optimizers[problem]``), each with polish off and on, ``variants`` (labelled
    optimiser settings, polish off), ``seeds`` optimiser seeds, ``budget`` evaluations per run
    and ``polish_budget``; ``records``: ``max_samples`` and ``min_sample_rate`` (Hz) cap the
    time-domain records' length (null: the zoo's recommended settings)."""

    name: str
    seeds: int
    budget: int
    polish_budget: int
    optimizers: tuple[str, ...]
    problem_optimizers: dict
    variants: dict
    records: dict
    instances: tuple[InstanceSpec, ...]

    def optimizers_for(self, problem: str) -> list[str]:
        return list(self.optimizers) + list(self.problem_optimizers.get(problem, []))


def _as_list(v) -> list:
    return list(v) if isinstance(v, (list, tuple)) else [v]


def _fmt_noise(v) -> str:
    """A noise level as a name part without dots (Hydra option names): 0.003 -> 0p3pct."""
    return f"{100 * float(v):g}".replace(".", "p") + "pct" if isinstance(v, (int, float)) else str(v)


def _timedomain(block: dict, where: str) -> list[InstanceSpec]:
    unknown = set(block) - set(TIMEDOMAIN_KEYS)
    if unknown:
        raise ConfigError(f"{where}: unknown key(s) {sorted(unknown)}; valid: {list(TIMEDOMAIN_KEYS)}")
    out = []
    for motor, source, exp, stop, noise, effect in itertools.product(
            *(_as_list(block.get(k, d)) for k, d in zip(TIMEDOMAIN_KEYS, ([], "independent", "dol", False,
                                                                          "white", "none"), strict=True))):
        name = f"td-{source[:3]}-{motor}-{exp}{'-stop' if stop else ''}-{noise}-{effect}"
        out.append(InstanceSpec(name=name, problem="timedomain", motor=motor, source=source, experiment=exp,
                                stop=bool(stop), noise=noise, effect=effect))
    return out


def _admittance(block: dict, where: str) -> list[InstanceSpec]:
    unknown = set(block) - set(ADMITTANCE_KEYS)
    if unknown:
        raise ConfigError(f"{where}: unknown key(s) {sorted(unknown)}; valid: {list(ADMITTANCE_KEYS)}")
    out = []
    for motor, sweep, model, data_model, noise in itertools.product(
            *(_as_list(block.get(k, d)) for k, d in zip(ADMITTANCE_KEYS, ([], "full", 8, None, 0.003), strict=True))):
        data_model = int(data_model or model)
        tag = f"m{model}" + (f"-data{data_model}" if data_model != model else "")
        name = f"adm-{motor}-{sweep}-{tag}-{_fmt_noise(noise)}"
        out.append(InstanceSpec(name=name, problem="admittance", motor=motor, source="synthetic", experiment=sweep,
                                noise=float(noise), effect="none", model=int(model), data_model=data_model))
    return out


def _explicit(e: dict, where: str) -> InstanceSpec:
    need = ("name", "problem", "motor", "source", "experiment")
    missing = [k for k in need if k not in e]
    if missing:
        raise ConfigError(f"{where}: missing {missing}")
    known = set(need) | {"stop", "noise", "effect", "model", "data_model", "settings"}
    unknown = set(e) - known
    if unknown:
        raise ConfigError(f"{where}: unknown key(s) {sorted(unknown)}; valid: {sorted(known)}")
    return InstanceSpec(**{k: e[k] for k in e if k != "settings"}, settings=dict(e.get("settings") or {}))


def suite_file(name_or_path: str) -> Path:
    """``small``/``full`` -> ``conf/suite_<name>.yaml``; anything else is a path."""
    p = Path(name_or_path)
    return p if p.suffix in (".yaml", ".yml") else CONF / f"suite_{name_or_path}.yaml"


def load_suite(name_or_path: str) -> SuiteSpec:
    path = suite_file(name_or_path)
    if not path.is_file():
        raise ConfigError(f"suite: {path} not found (known: small, full, or a YAML path)")
    doc = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
    instances: list[InstanceSpec] = []
    for k, b in enumerate(doc.get("timedomain") or []):
        instances += _timedomain(b, f"{path.name}: timedomain[{k}]")
    for k, b in enumerate(doc.get("admittance") or []):
        instances += _admittance(b, f"{path.name}: admittance[{k}]")
    for k, e in enumerate(doc.get("explicit") or []):
        instances.append(_explicit(e, f"{path.name}: explicit[{k}]"))
    names = [i.name for i in instances]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ConfigError(f"{path.name}: instances listed twice: {dup[:5]}")
    try:
        return SuiteSpec(name=str(doc.get("name", path.stem)), seeds=int(doc["seeds"]), budget=int(doc["budget"]),
                         polish_budget=int(doc.get("polish_budget", 2000)),
                         optimizers=tuple(doc["optimizers"]),
                         problem_optimizers=dict(doc.get("problem_optimizers") or {}),
                         variants=dict(doc.get("variants") or {}), records=dict(doc.get("records") or {}),
                         instances=tuple(instances))
    except KeyError as exc:
        raise ConfigError(f"{path.name}: missing key {exc.args[0]}") from None
