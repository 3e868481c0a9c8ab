"""The examples in the SLAM modules' docstrings run and hold."""

import doctest
import importlib

import pytest

MODULES = [
    f"map2map.slam.{m}" for m in ("base", "gridmap", "rbpf", "graph", "logs", "offline", "quality")
]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0
    assert result.failed == 0
