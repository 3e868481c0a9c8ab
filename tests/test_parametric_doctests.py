"""The examples in the trajectory and parametric modules' docstrings run and hold."""

import doctest
import importlib

import pytest

MODULES = [
    "map2map.trajectory.prm",
    "map2map.trajectory.timing",
    "map2map.parametric.params",
    "map2map.parametric.visibility",
    "map2map.parametric.lidar",
    "map2map.parametric.odometry",
    "map2map.parametric.additive",
    "map2map.parametric.ekf",
    "map2map.parametric.field",
    "map2map.parametric.pipeline",
    "map2map.parametric.figures",
    "map2map.parametric.demo_stage",
]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0
    assert result.failed == 0
