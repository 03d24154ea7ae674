"""Configuration checks made before any work starts: the groups, the top-level keys (a misspelt
key gets the nearest known one), seed, budget, time limit, switches, the shape of ``bounds``, the
problem's own ``check_config`` and the optimiser plugin's options."""

from __future__ import annotations

import importlib
import inspect
import math

import yaml
from omegaconf import DictConfig, OmegaConf

from benchmark.core.config_files import CONFIG_DIR
from benchmark.core.errors import ConfigError
from benchmark.core.spelling import did_you_mean


def resolve_budget(cfg: DictConfig) -> int:
    budget = cfg.get("budget")
    if budget is None:
        budget = cfg.optimizer.get("default_budget")
        key = "optimizer.default_budget"
    else:
        key = "budget"
    if isinstance(budget, bool) or not isinstance(budget, int) or budget < 1:
        raise ConfigError(f"{key}: must be a positive whole number of evaluations, got {budget!r}")
    return budget


def validate_config(cfg: DictConfig) -> None:
    """Catch configuration mistakes before any work starts (no data read, nothing simulated):
    groups present, seed, budget, polish, time limit, checkpoint keys, the shape of
    ``bounds``, the problem's own checks (``check_config`` in the module of its set-up
    function) and the optimiser plugin (importable, options it accepts)."""
    for key in ("problem", "optimizer", "motor"):
        if key not in cfg or cfg[key] is None:
            raise ConfigError(f"{key}: missing config group")
    check_top_level_keys(cfg)
    if "plugin" not in cfg.optimizer or "_target_" not in cfg.optimizer.plugin:
        raise ConfigError("optimizer.plugin._target_: the optimiser config must name its plugin function")
    if "setup" not in cfg.problem or "_target_" not in cfg.problem.setup:
        raise ConfigError("problem.setup._target_: the problem config must name its set-up function")
    seed = cfg.get("seed")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ConfigError(f"seed: must be a non-negative integer, got {seed!r}")
    resolve_budget(cfg)
    if cfg.get("polish"):
        pb = cfg.get("polish_budget")
        if isinstance(pb, bool) or not isinstance(pb, int) or pb < 1:
            raise ConfigError(f"polish_budget: must be a positive whole number, got {pb!r}")
    limit = cfg.get("time_limit_s")
    if limit is not None and (isinstance(limit, bool) or not isinstance(limit, (int, float))
                              or not math.isfinite(limit) or limit <= 0):
        raise ConfigError(f"time_limit_s: must be a positive number of seconds or null, got {limit!r}")
    for key in ("resume", "checkpoint", "polish", "figures"):
        v = cfg.get(key)
        if v is not None and not isinstance(v, bool):
            raise ConfigError(f"{key}: must be true or false, got {v!r}")
    progress = cfg.get("progress", "auto")
    if not (isinstance(progress, bool) or progress == "auto"):
        raise ConfigError(f"progress: must be auto, true or false, got {progress!r}")
    if cfg.get("resume") and cfg.get("checkpoint") is False:
        raise ConfigError("resume: needs checkpoint=true (a run without checkpoints cannot be resumed)")
    data = cfg.get("data")
    mib = data.get("max_file_mib") if data is not None else None
    if mib is not None and (isinstance(mib, bool) or not isinstance(mib, (int, float)) or not mib > 0):
        raise ConfigError(f"data.max_file_mib: must be a positive number of MiB, got {mib!r}")
    bounds = cfg.get("bounds")
    if bounds is not None:
        if not OmegaConf.is_dict(bounds):
            raise ConfigError(f"bounds: expected a mapping {{name: [low, high]}}, e.g. bounds={{Rs:[1,10]}}, "
                              f"got {bounds!r}")
        for k, v in bounds.items():
            if not OmegaConf.is_list(v) or len(v) != 2:
                raise ConfigError(f"bounds.{k}: expected [low, high], got {v!r}")
    check = _problem_check(cfg)
    if check is not None:
        check(OmegaConf.to_container(cfg, resolve=True))
    check_plugin(cfg)


#: The primary configuration of ``python -m benchmark``: its top-level keys are the only ones a
#: run accepts (a misspelt ``+seeed=1`` would otherwise run silently with seed 0).
PRIMARY_CONFIG = CONFIG_DIR / "config.yaml"


def known_top_level_keys() -> list[str]:
    """Top-level keys of conf/config.yaml and its config groups."""
    doc = yaml.safe_load(PRIMARY_CONFIG.read_text(encoding="utf-8")) or {}
    groups = []
    for entry in doc.get("defaults", []):
        if isinstance(entry, dict):
            for k in entry:
                k = str(k).split(" ")[-1].split("@")[0]
                if not k.startswith("hydra") and k != "_self_":
                    groups.append(k)
    return sorted({*(k for k in doc if k not in ("defaults", "hydra")), *groups})


def check_top_level_keys(cfg: DictConfig) -> None:
    """A ConfigError naming a top-level key the project does not know, with the nearest one."""
    known = known_top_level_keys()
    for key in cfg:
        if key not in known and key != "hydra":
            raise ConfigError(f"{key}: unknown key{did_you_mean(str(key), known)}; the keys of a run are {known}")


def _problem_check(cfg):
    """The problem's ``check_config(run)``, if the module of its set-up function has one."""
    target = str(cfg.problem.setup._target_)
    module_name = target.rpartition(".")[0]
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise ConfigError(f"problem.setup._target_: cannot import {module_name!r}: {exc}") from None
    return getattr(module, "check_config", None)


def check_plugin(cfg: DictConfig):
    """Import the plugin function and check its options against its signature; returns it."""
    pcfg = cfg.optimizer.plugin
    target = str(pcfg._target_)
    module_name, _, attr = target.rpartition(".")
    try:
        fn = getattr(importlib.import_module(module_name), attr)
    except ImportError as exc:
        raise ConfigError(f"optimizer.plugin._target_: cannot import {module_name!r} for optimizer "
                          f"{cfg.optimizer.get('name')!r}: {exc}") from None
    except AttributeError:
        raise ConfigError(f"optimizer.plugin._target_: {module_name!r} has no function {attr!r}") from None
    try:
        sig = inspect.signature(fn)
    except (TypeError, ValueError):
        return fn
    params = sig.parameters
    if any(p.kind == inspect.Parameter.VAR_KEYWORD for p in params.values()):
        return fn
    valid = [n for n, p in params.items() if n not in ("problem", "seed")
             and p.kind in (inspect.Parameter.KEYWORD_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)]
    for key in pcfg:
        if str(key).startswith("_"):
            continue
        if key not in valid:
            raise ConfigError(f"optimizer.plugin.{key}: not an option of {target}; valid: {valid}")
    return fn
