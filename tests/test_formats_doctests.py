"""The examples in the format modules' docstrings run and hold."""

import doctest
import importlib

import pytest

MODULES = [
    "map2map.maps.raster",
    "map2map.maps.ros",
    "map2map.maps.image",
    "map2map.maps.houseexpo",
    "map2map.maps.rasterize",
    "map2map.maps.dxf",
    "map2map.maps.formats",
    "map2map.maps.render",
]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0
    assert result.failed == 0
