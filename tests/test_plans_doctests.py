"""The examples in the floor-plan and preprocessing docstrings run and hold."""

import doctest
import importlib

import pytest

MODULES = ["map2map.maps.floorplan", "map2map.maps.preprocess"]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0
    assert result.failed == 0
