"""The docstring examples of every semkit module run and hold."""
import doctest
import importlib
import pkgutil

import pytest

import semkit

MODULES = sorted(m.name for m in pkgutil.walk_packages(semkit.__path__, "semkit.")
                 if not m.name.endswith("__main__"))


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    mod = importlib.import_module(name)
    res = doctest.testmod(mod, optionflags=doctest.ELLIPSIS)
    assert res.failed == 0


def test_the_examples_are_found():
    assert len(MODULES) > 30
    n = sum(doctest.testmod(importlib.import_module(m), optionflags=doctest.ELLIPSIS,
                            report=False).attempted for m in ("semkit.skeleton",
                                                              "semkit.evaluate"))
    assert n >= 8
