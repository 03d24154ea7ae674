"""``python -m plugins.genesis DIR``: the clone as a stand-in for the original program."""

from __future__ import annotations

import importlib
import os
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np

from benchmark.core.errors import UserError
from plugins.genesis.engine import Genesis, RunResult, sum_of_squares
from plugins.genesis.files import read_settings, read_template, write_min, write_out
from plugins.genesis.settings import GenesisInputError


def _load_objective(spec: str) -> Callable[[np.ndarray], np.ndarray]:
    mod_name, colon, func_name = spec.partition(":")
    if not colon or not mod_name or not func_name:
        raise GenesisInputError(f"objective {spec!r}: expected module:function")
    if "" not in sys.path and os.getcwd() not in sys.path:
        sys.path.insert(0, os.getcwd())
    try:
        func = getattr(importlib.import_module(mod_name), func_name)
    except Exception as exc:  # noqa: BLE001 - any import failure is bad input
        raise GenesisInputError(f"objective {spec!r}: cannot load: {type(exc).__name__}: {exc}") from None
    if not callable(func):
        raise GenesisInputError(f"objective {spec!r}: not callable")

    def batch(X: np.ndarray) -> np.ndarray:
        return np.array([float(func(np.array(x))) for x in X], dtype=float)

    return batch


def run_dir(
    directory,
    objective: Callable[[np.ndarray], np.ndarray] | None = None,
    out_dir=None,
) -> RunResult:
    """Read ``directory/in`` and ``directory/template``, run, write ``out`` and ``min``.

    ``objective`` maps decoded rows ``(n, n_genes)`` to costs; default :func:`sum_of_squares`.
    The files go into ``out_dir`` (created if missing) when given, else into ``directory`` as the
    original does; ``out`` only with option ``c`` or ``C``. Their paths are in ``result.files``."""
    d = Path(directory)
    settings, where = read_settings(d / "in")
    template = read_template(d / "template") if settings.flag("f") else None
    if template is not None and template.length != settings.structure_length:
        raise GenesisInputError(
            f"{d / 'in'}: line {where['structure_length']}: Structure Length: "
            f"{settings.structure_length}, but the genes of {d / 'template'} take {template.length} bits"
        )
    dest = d if out_dir is None else Path(out_dir)
    try:
        dest.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise GenesisInputError(f"{dest}: cannot create the output folder: {exc.strerror or exc}") from None
    engine = Genesis(settings, template, objective or sum_of_squares)
    result = engine.run()
    files = []
    try:
        if settings.flag("c") or settings.flag("C"):
            files.append(dest / "out")
            write_out(files[-1], result.out_lines)
        files.append(dest / "min")
        write_min(files[-1], result.saved, template, engine.gray)
    except OSError as exc:
        raise GenesisInputError(f"{files[-1]}: cannot write: {exc.strerror or exc}") from None
    result.files = files
    return result


_USAGE = "usage: python -m plugins.genesis DIR [module:function] [--out-dir OUTDIR]"
_HELP = f"""{_USAGE}

Run the GENESIS 5.0 clone on DIR/in (settings) and DIR/template (genes, with option f), in the
original program's file formats, and write the original's out (option c or C) and min files into
DIR, or into OUTDIR with --out-dir (-o). The objective is the sum of squares of the genes unless
module:function is given (imported from the current directory or PYTHONPATH; it receives the
genes as a 1-D numpy array and returns a float). Example: python -m plugins.genesis plugins/genesis_example
"""


def _parse_args(argv: list[str]) -> tuple[list[str], str | None] | None:
    """``(positionals, out_dir)``, or None when the arguments do not fit the usage."""
    pos: list[str] = []
    out_dir = None
    k = 0
    while k < len(argv):
        a = argv[k]
        if a in ("-o", "--out-dir"):
            if k + 1 >= len(argv) or out_dir is not None:
                return None
            out_dir = argv[k + 1]
            k += 2
            continue
        if a.startswith("--out-dir="):
            if out_dir is not None:
                return None
            out_dir = a.partition("=")[2]
        elif a.startswith("-") and a != "-":
            return None
        else:
            pos.append(a)
        k += 1
    if len(pos) not in (1, 2) or out_dir == "":
        return None
    return pos, out_dir


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if any(a in ("-h", "--help") for a in argv):
        print(_HELP, end="")
        return 0
    parsed = _parse_args(argv)
    if parsed is None:
        print(_USAGE, file=sys.stderr)
        return 2
    (directory, *rest), out_dir = parsed
    try:
        objective = _load_objective(rest[0]) if rest else None
        if not Path(directory).is_dir():
            raise GenesisInputError(f"{directory}: not a directory")
        res = run_dir(directory, objective, out_dir)
    except UserError as exc:
        print(f"genesis: {exc}", file=sys.stderr)
        return 2
    print(
        f"genesis: {res.generations} generations, {res.trials} trials, best {res.best_cost:.6e} "
        f"(stopped: {res.stop_reason}); wrote {', '.join(str(f) for f in res.files)}"
    )
    return 0
