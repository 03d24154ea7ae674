"""Command-line plumbing shared by the entry points: user errors become one clear line on
stderr and exit status 2, with no traceback unless ``IMBENCH_DEBUG=1``."""

from __future__ import annotations

import functools
import os
import sys

from benchmark.errors import UserError


def debug() -> bool:
    return os.environ.get("IMBENCH_DEBUG", "") not in ("", "0")


def user_errors(fn):
    """Decorator for a Hydra task function: UserError -> 'error: ...' and exit status 2."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except UserError as exc:
            if debug():
                raise
            print(f"error: {exc}", file=sys.stderr)
            sys.exit(2)

    return wrapper


def run_hydra_main(main) -> None:
    """Call a ``@hydra.main`` function; Hydra's own configuration errors (an unknown
    optimiser or problem name, a misspelt key; Hydra prints the valid choices) exit with
    status 2 like every other user error."""
    try:
        main()
    except SystemExit as exc:
        if exc.code == 1:
            sys.exit(2)
        raise
