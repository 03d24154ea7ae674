"""The suite's measures on a user's own data folders (measured records included).

A YAML file lists the folders and, optionally, the suite settings::

    name: my_bench                 # optional
    instances:
      - path: bench/motor1         # a data folder (meta.yaml kind: startup or admittance)
        name: motor1               # optional (default: the folder's name)
        bounds: {Rs: [0.1, 5]}     # optional search bounds (default: the harness's, from the data)
        groups: {site: lab A}      # optional labels the measures are broken down by
    optimizers: [multistart, cmaes]   # optional (default: the small suite's)
    seeds: 3                       # optional (default: the small suite's)
    budget: 10000                  # optional

Every optimiser runs on every folder through the harness (as the suite's own instances); the
targets are relative to the best cost any run found (no truth is needed; a ``truth.yaml``, if
present, scores the parameters).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import yaml

from benchmark.core.errors import ConfigError
from benchmark.core.harness import DATA_KIND_PROBLEM
from benchmark.studies.suite.spec import SuiteSpec, load_suite


def _problem_of(folder: Path, where: str) -> str:
    meta = folder / "meta.yaml"
    if not meta.is_file():
        raise ConfigError(f"{where}: {folder} has no meta.yaml (not a data folder)")
    kind = (yaml.safe_load(meta.read_text(encoding="utf-8")) or {}).get("kind")
    if kind not in DATA_KIND_PROBLEM:
        raise ConfigError(f"{where}: {meta} kind {kind!r} is not one of {sorted(DATA_KIND_PROBLEM)}")
    return DATA_KIND_PROBLEM[kind]


def load_user(path: str | Path) -> tuple[SuiteSpec, list[tuple[dict, dict]]]:
    """The suite settings and, per folder, its instance document and harness configuration."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"user: {path} not found")
    doc = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
    entries = doc.get("instances")
    if not isinstance(entries, list) or not entries:
        raise ConfigError(f"{path}: instances: a list of {{path: DATA_FOLDER}} is needed")
    base = load_suite("small")
    suite = replace(base, name=str(doc.get("name", path.stem)), seeds=int(doc.get("seeds", base.seeds)),
                    budget=int(doc.get("budget", base.budget)),
                    optimizers=tuple(doc.get("optimizers", base.optimizers)), variants={}, instances=())
    out, names = [], set()
    for k, e in enumerate(entries):
        where = f"{path}: instances[{k}]"
        if not isinstance(e, dict) or "path" not in e:
            raise ConfigError(f"{where}: expected {{path: DATA_FOLDER}}, got {e!r}")
        folder = (path.parent / str(e["path"])).resolve() if not Path(str(e["path"])).is_absolute() \
            else Path(str(e["path"]))
        problem = _problem_of(folder, where)
        name = str(e.get("name", folder.name))
        if name in names:
            raise ConfigError(f"{where}: name {name!r} used twice (give name: ...)")
        names.add(name)
        cfg = {"problem": problem, "data": {"path": str(folder)}}
        if e.get("bounds"):
            cfg["bounds"] = dict(e["bounds"])
        groups = {"problem": problem, **{str(a): str(b) for a, b in (e.get("groups") or {}).items()}}
        out.append(({"name": name, "problem": problem, "model_error": False, "groups": groups}, cfg))
    return suite, out
