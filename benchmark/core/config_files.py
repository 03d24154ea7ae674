"""Where the Hydra configuration lives, and composing it outside a command line.

The repository keeps the configuration in the top-level ``conf/`` folder; a built wheel (or
``pip install .``) ships the same files as package data inside ``benchmark/conf/``
(``pyproject.toml`` maps one onto the other). :data:`CONFIG_DIR` is whichever of the two this
installation has: the packaged copy first, else the repository's folder (a source checkout or
an editable install). Every entry point, the API and the effect catalogue read it from here.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from benchmark.core.errors import ConfigError
from benchmark.core.spelling import did_you_mean

_PACKAGE = Path(__file__).resolve().parents[1]


def _find_config_dir() -> Path:
    for folder in (_PACKAGE / "conf", _PACKAGE.parent / "conf"):
        if (folder / "config.yaml").is_file() and (folder / "optimizer").is_dir():
            return folder
    raise ConfigError(f"the configuration folder is missing: neither {_PACKAGE / 'conf'} (an installed "
                      f"package) nor {_PACKAGE.parent / 'conf'} (a source checkout) holds config.yaml; "
                      "reinstall imbench")


#: The folder holding ``config.yaml``, ``diagnose.yaml`` and the config groups.
CONFIG_DIR: Path = _find_config_dir()


def config_groups() -> dict[str, list[str]]:
    """The config groups a user selects (``group=option``) and their options, from the folders of
    :data:`CONFIG_DIR`. ``effect`` is no group: its files are the diagnosis's catalogue
    (:func:`benchmark.core.effects.load_effects`), chosen with ``effects=[...]``."""
    return {d.name: sorted(f.stem for f in d.glob("*.yaml")) for d in sorted(CONFIG_DIR.iterdir())
            if d.is_dir() and d.name not in NOT_GROUPS}


#: Folders of the configuration that are not user-selectable groups.
NOT_GROUPS = ("effect", "hydra", "__pycache__")
#: What to say when one of them is given as a group.
NOT_GROUP_HINTS = {"effect": " (conf/effect/ is the diagnosis's catalogue, no group: inject effects with "
                             "effects=[double_cage] in python -m synthetic or benchmark.diagnose, and choose the "
                             "diagnosis's candidates with candidates=[...])"}


def compose_config(name: str = "config", overrides: Sequence[str] = ()):
    """The configuration ``conf/<name>.yaml`` composed with Hydra ``overrides`` (strings as typed
    on a command line, e.g. ``"optimizer=scipy_de"``; a sweep's ``a,b`` takes its first value),
    outside any command line. A misspelt key or option, with or without ``+``, raises a
    :class:`benchmark.core.errors.ConfigError` in one line naming it and the nearest known one."""
    from hydra import compose, initialize_config_dir
    from hydra.core.global_hydra import GlobalHydra
    from hydra.errors import HydraException

    single = [_first_value(o) for o in _parse(overrides)]
    hydra_instance = GlobalHydra.instance()
    saved = hydra_instance.hydra
    hydra_instance.clear()  # inside a caller's Hydra context: compose in our own, then restore it
    try:
        with initialize_config_dir(config_dir=str(CONFIG_DIR), version_base="1.3"):
            try:
                cfg = compose(name, overrides=single)
            except HydraException as exc:
                raise ConfigError(_explain(name, single, exc)) from None
            _check_added_keys(name, single, compose)
    finally:
        hydra_instance.clear()
        if saved is not None:
            hydra_instance.initialize(saved)
    return cfg


def _parse(overrides: Sequence[str]):
    from hydra.core.override_parser.overrides_parser import OverridesParser
    from hydra.errors import HydraException

    parser = OverridesParser.create()
    try:
        return parser.parse_overrides(list(overrides))
    except HydraException as exc:
        for one in overrides:  # name the override that does not parse
            try:
                parser.parse_overrides([one])
            except HydraException:
                raise ConfigError(f"{one}: {' '.join(str(exc).split())}") from None
        raise ConfigError(" ".join(str(exc).split())) from None


def _first_value(o) -> str:
    """The override as a single-run override string (a sweep takes its first value)."""
    if not o.is_sweep_override():
        return o.input_line
    first = next(iter(o.sweep_string_iterator()))
    return f"{o.get_key_element()}={first}"


def _user_keys(overrides: Sequence[str]):
    """(override, key) of every override that sets a key (no group choice, no hydra.*, no delete)."""
    groups = config_groups()
    for o in _parse(overrides):
        key = o.key_or_group
        if o.is_delete() or key.split(".")[0].split("/")[0] == "hydra" or (key in groups and o.package is None):
            continue
        yield o, key


def _explain(name: str, overrides: list[str], exc: Exception) -> str:
    """One line saying which override Hydra could not apply, with the nearest valid key or option."""
    from hydra import compose

    groups = config_groups()
    for o in _parse(overrides):
        key = o.key_or_group
        if key in groups and not o.is_delete():
            value = str(o.value())
            if value not in groups[key]:
                return f"{key}={value}: no such option{did_you_mean(value, groups[key])}; options: {groups[key]}"
    choices = [o.input_line for o in _parse(overrides) if o.key_or_group in groups or "/" in o.key_or_group]
    try:
        base = compose(name, overrides=choices)
    except Exception:
        return " ".join(str(exc).split())
    for _, key in _user_keys(overrides):
        message = unknown_key_message(base, key)
        if message:
            return message
    return " ".join(str(exc).split())


def _check_added_keys(name: str, overrides: list[str], compose) -> None:
    """``+key=value`` adds a key Hydra does not know: refused when it is a near miss of a known one."""
    added = [(o, key) for o, key in _user_keys(overrides) if o.is_add() or o.is_force_add()]
    if not added:
        return
    groups = config_groups()
    base = compose(name, overrides=[o.input_line for o in _parse(overrides) if o.key_or_group in groups])
    for _, key in added:
        message = unknown_key_message(base, key, only_near_misses=True)
        if message:
            raise ConfigError(message)


def unknown_key_message(cfg, key: str, only_near_misses: bool = False) -> str | None:
    """``KEY: unknown key (did you mean NEAREST?)`` when the dotted ``key`` is not in ``cfg``; None
    when it is (or, with ``only_near_misses``, when no known key is close to it)."""
    from omegaconf import OmegaConf

    parts = key.split(".")
    node = cfg
    for depth, part in enumerate(parts):
        if not OmegaConf.is_dict(node):
            return None
        if part in node:
            node = node[part]
            continue
        known = [str(k) for k in node.keys()]
        prefix = ".".join(parts[:depth])
        hint = did_you_mean(part, known, prefix) or (NOT_GROUP_HINTS.get(part, "") if depth == 0 else "")
        if only_near_misses and not hint:
            return None
        where = f"the keys under {prefix}" if prefix else f"the keys of {'this command'}"
        return f"{key}: unknown key{hint}; {where} are {sorted(known)}"
    return None
