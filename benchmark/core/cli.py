"""Command-line plumbing shared by the entry points: user errors become one clear line on
stderr and exit status 2, with no traceback unless ``IMBENCH_DEBUG=1``; imbench's warnings
(:class:`benchmark.core.errors.ImbenchWarning`, e.g. a speed column that looks like rpm) become one
``warning: ...`` line each."""

from __future__ import annotations

import contextlib
import functools
import os
import sys
import traceback
import warnings

from benchmark.core.errors import ImbenchWarning, UserError


def debug() -> bool:
    return os.environ.get("IMBENCH_DEBUG", "") not in ("", "0")


@contextlib.contextmanager
def one_line_warnings():
    """Within the block, an ImbenchWarning prints as ``warning: <message>`` on stderr (no
    source line); other warnings print as usual."""
    previous = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        if isinstance(category, type) and issubclass(category, ImbenchWarning):
            print(f"warning: {message}", file=file or sys.stderr)
        else:
            previous(message, category, filename, lineno, file, line)

    warnings.showwarning = show
    try:
        yield
    finally:
        warnings.showwarning = previous


def user_errors(fn):
    """Decorator for a Hydra task function: UserError -> 'error: ...' and exit status 2."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            with one_line_warnings():
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
    status 2 like every other user error. With ``IMBENCH_DEBUG=1`` Hydra shows its full
    stack traces too (``HYDRA_FULL_ERROR=1``)."""
    if debug():
        os.environ.setdefault("HYDRA_FULL_ERROR", "1")
    try:
        main()
    except SystemExit as exc:
        if exc.code == 1:
            sys.exit(2)
        raise
    except UserError:  # IMBENCH_DEBUG=1: Hydra let it through with its traceback
        traceback.print_exc()
        sys.exit(2)
