"""MkDocs hook: the docstrings' Sphinx cross-reference roles as code in the rendered pages.

The API reference renders the docstrings as Markdown, where ``:func:`benchmark.api.identify``` comes
out as the role's name before a code span. This hook drops the role and shortens the target as
Sphinx shows it: ``~a.b.c`` as ``c``, a leading dot (a name relative to the module) without it.
"""

from __future__ import annotations

import re

ROLE = re.compile(r":(?:py:)?(?:func|class|meth|mod|data|attr|obj|const|exc):<code>([^<]*)</code>")


def shown(target: str) -> str:
    """How Sphinx shows a role's target."""
    target = target.strip()
    if target.startswith("~"):
        return target[1:].rsplit(".", 1)[-1]
    return target.lstrip(".")


def on_page_content(html: str, **kwargs) -> str:
    return ROLE.sub(lambda m: f"<code>{shown(m.group(1))}</code>", html)
