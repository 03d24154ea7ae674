"""The API's docstring examples run as written (a cold reviewer copied the DataSet example and got a
NameError: it used the class without importing it)."""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

import benchmark._api

MODULES = ["benchmark.api"] + [f"benchmark._api.{m.name}" for m in pkgutil.iter_modules(benchmark._api.__path__)]


@pytest.mark.parametrize("name", MODULES)
def test_the_docstring_examples_run(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0, f"{name}: {result.failed} of {result.attempted} examples failed"


def test_the_examples_are_there():
    attempted = sum(doctest.testmod(importlib.import_module(n), optionflags=doctest.ELLIPSIS).attempted
                    for n in ("benchmark.api", "benchmark._api.dataset"))
    assert attempted >= 5
