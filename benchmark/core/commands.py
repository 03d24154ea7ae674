"""Commands a result suggests, complete and runnable: the same run with a change
(:func:`rerun_command`), or the diagnosis of the same data (:func:`diagnose_command`).

A run's overrides are the ones given on its command line (Hydra's task overrides); a run
started without Hydra's command line (the Python API, a test) gets the overrides that remake
its data and model from its configuration (:func:`overrides_from_config`). Every override is
quoted for a POSIX shell.
"""

from __future__ import annotations

import shlex
from pathlib import Path

import yaml
from omegaconf import DictConfig, OmegaConf

from benchmark.core.config_files import CONFIG_DIR

#: The diagnosis's configuration: its top-level keys and groups are what its command accepts.
DIAGNOSE_CONFIG = CONFIG_DIR / "diagnose.yaml"
#: Keys of a run that the diagnosis does not take over: its base identification uses its own
#: optimiser and budgets (the default pipeline, which the diagnosis's thresholds were set with).
NOT_FOR_DIAGNOSIS = ("optimizer", "budget", "polish_budget")


def run_overrides(cfg: DictConfig | None = None) -> list[str]:
    """The overrides of the current run: Hydra's task overrides when it runs from the command
    line, else :func:`overrides_from_config` of ``cfg`` (an empty list without either)."""
    try:
        from hydra.core.hydra_config import HydraConfig

        return [str(o) for o in HydraConfig.get().overrides.task]
    except ValueError:  # no Hydra command line
        return overrides_from_config(cfg) if cfg is not None else []


def overrides_from_config(cfg: DictConfig) -> list[str]:
    """Overrides that remake a run's data and model from its configuration: the problem, the
    optimiser, the data folder or the synthetic noise, the seed, the budget and the bounds."""
    out = [f"problem={cfg.problem.name}", f"optimizer={cfg.optimizer.name}"]
    path = (cfg.get("data") or {}).get("path")
    if path is not None:
        out.append(f"data.path={path}")
    else:
        out += [f"noise.{k}={v}" for k, v in (cfg.get("noise") or {}).items() if v]
    for key in ("seed", "budget"):
        if cfg.get(key) is not None:
            out.append(f"{key}={cfg.get(key)}")
    if cfg.get("bounds") is not None:
        pairs = ",".join(f"{k}:[{lo},{hi}]" for k, (lo, hi) in OmegaConf.to_container(cfg.bounds).items())
        out.append(f"bounds={{{pairs}}}")
    return out


def _key(override: str) -> str:
    """The dotted key of an override (``+a.b=1`` -> ``a.b``)."""
    return override.split("=", 1)[0].lstrip("+~")


#: Keys that change only what a run writes or shows, not its numbers: a suggested command leaves
#: them out (so the command line and the Python API suggest the same command).
PRESENTATION_KEYS = ("figures", "checkpoint", "progress", "resume", "hydra")


def command(module: str, overrides) -> str:
    """``python -m module`` with the overrides, each quoted for the shell (without the
    :data:`PRESENTATION_KEYS`)."""
    kept = [o for o in overrides if _key(o).split(".")[0] not in PRESENTATION_KEYS]
    return " ".join(["python", "-m", module, *(shlex.quote(o) for o in kept)])


def typed_command(argv) -> str:
    """The command a run was started with, as a user types it: ``.../benchmark/__main__.py ARGS`` (``sys.argv``
    under ``python -m``) -> ``python -m benchmark ARGS``, each argument quoted for the shell; a string already
    so written is returned as it is."""
    if isinstance(argv, str):
        if argv.startswith("python"):
            return argv
        argv = shlex.split(argv)
    argv = [str(a) for a in argv]
    if not argv:
        return ""
    head = Path(argv[0])
    prog = [] if head.name != "__main__.py" or not head.parent.name else ["python", "-m", head.parent.name]
    return " ".join([*prog, *(shlex.quote(a) for a in argv[1:])] if prog else [shlex.quote(a) for a in argv])


def rerun_command(overrides, **changes) -> str:
    """``python -m benchmark`` with the run's overrides and ``changes`` (key -> value) in place
    of any the run gave for those keys and their sub-keys (a value None drops the key: its default is
    used; ``optimizer`` also drops ``optimizer.plugin.xatol=...``, a setting of the optimiser replaced)."""
    kept = [o for o in overrides if not any(_key(o) == k or _key(o).startswith(k + ".") for k in changes)]
    return command("benchmark", kept + [f"{k}={_value(v)}" for k, v in changes.items() if v is not None])


def _value(v) -> str:
    return str(v).lower() if isinstance(v, bool) else str(v)


def diagnostic_keys() -> set[str]:
    """Top-level keys and config groups the diagnosis's command accepts."""
    doc = yaml.safe_load(DIAGNOSE_CONFIG.read_text(encoding="utf-8")) or {}
    groups = {str(k).split(" ")[-1].split("@")[0] for entry in doc.get("defaults", []) if isinstance(entry, dict)
              for k in entry}
    return ({*doc, *groups} - {"defaults", "hydra", "_self_"}) - set(NOT_FOR_DIAGNOSIS)


def diagnose_command(overrides) -> str:
    """``python -m benchmark.diagnose`` of the same data and model: the run's overrides whose
    keys the diagnosis accepts (the data folder, or the synthetic plant's motor and noise; the
    problem's settings and bounds), without its optimiser and budgets."""
    keys = diagnostic_keys()
    return command("benchmark.diagnose", [o for o in overrides if _key(o).split(".")[0] in keys])
