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
from collections.abc import Sequence

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


def run_hydra_main(main, config_name: str, title: str, usage: Sequence[str], footer: Sequence[str] = (),
                   sections: Sequence[str] = ("problem", "optimizer")) -> None:
    """Call a ``@hydra.main`` function whose primary configuration is ``conf/<config_name>.yaml``.

    ``--help`` prints the entry point's own help (:func:`benchmark.core.config_help.config_help`:
    ``title``, ``usage`` lines, its keys, those of the groups in ``sections``, the groups,
    ``footer``). Before Hydra composes, the overrides are checked
    (:func:`benchmark.core.config_files.compose_config`): a misspelt key or option, with or
    without ``+``, is one line naming it and the nearest known one, exit status 2; so are
    Hydra's own configuration errors. With ``IMBENCH_DEBUG=1`` Hydra shows its full stack
    traces too (``HYDRA_FULL_ERROR=1``)."""
    if debug():
        os.environ.setdefault("HYDRA_FULL_ERROR", "1")
    from hydra._internal.utils import get_args_parser

    args, _ = get_args_parser().parse_known_args(sys.argv[1:])
    name = args.config_name or config_name
    try:
        if args.help:
            from benchmark.core.config_help import config_help

            print(config_help(name, title, usage, args.overrides, footer, sections), end="")
            sys.exit(0)
        if not (args.hydra_help or args.info or args.shell_completion or args.config_dir or args.config_path):
            from benchmark.core.config_files import compose_config

            compose_config(name, args.overrides)
    except UserError as exc:
        if debug():
            raise
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
    try:
        main()
    except SystemExit as exc:
        if exc.code == 1:
            sys.exit(2)
        raise
    except UserError:  # IMBENCH_DEBUG=1: Hydra let it through with its traceback
        traceback.print_exc()
        sys.exit(2)
