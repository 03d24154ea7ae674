"""The nearest known name to a misspelt one, for error messages: one matching rule, two phrasings.

:func:`did_you_mean` follows what a user typed (a command-line argument, a config key or option):
``" (did you mean seed?)"``. :func:`found_instead` follows a name a file should hold (a column, a
``meta.yaml`` key): ``" (found 'Speed': names are case-sensitive)"`` or ``" (found 'sampel_time':
misspelt?)"``. Both take the nearest name by :func:`nearest`."""

from __future__ import annotations

import difflib
from collections.abc import Iterable

#: Similarity (difflib's ratio, 0-1) a known name needs to be offered: 0.6 is difflib's default,
#: which offers ``seed`` for ``seeed`` and ``budget`` for ``bugdet`` but nothing for unrelated words.
CUTOFF = 0.6


def nearest(word: str, known: Iterable[str]) -> str | None:
    """The known name closest to ``word`` (at least :data:`CUTOFF` alike), or None."""
    close = difflib.get_close_matches(word, list(known), n=1, cutoff=CUTOFF)
    return close[0] if close else None


def did_you_mean(word: str, known: Iterable[str], prefix: str = "") -> str:
    """`` (did you mean X?)`` for the nearest of ``known`` (``prefix.X`` with a prefix), or ''."""
    close = nearest(word, known)
    return f" (did you mean {prefix + '.' if prefix else ''}{close}?)" if close else ""


def found_instead(name: str, candidates: Iterable[str]) -> str:
    """`` (found 'X': ...)`` for a name a file holds in place of ``name``: the same name in another
    case first (names are case-sensitive), else the nearest; '' when none is near."""
    candidates = list(candidates)
    lower = {c.lower(): c for c in candidates}
    if name.lower() in lower:
        return f" (found '{lower[name.lower()]}': names are case-sensitive)"
    close = nearest(name, candidates)
    return f" (found '{close}': misspelt?)" if close else ""
