"""The docstring examples of semkit's modules run and hold."""
import doctest
import importlib

import pytest

MODULES = ["io", "illumination", "scanlines", "threshold", "ridge", "link", "cleanup", "skeleton",
           "measure", "analysis", "synth", "_kernels", "robust"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    mod = importlib.import_module(f"semkit.{name}")
    res = doctest.testmod(mod, optionflags=doctest.ELLIPSIS)
    assert res.failed == 0 and res.attempted > 0
