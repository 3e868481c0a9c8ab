"""The examples in the simulator modules' docstrings run and hold."""

import doctest
import importlib

import pytest

MODULES = [
    f"map2map.sim.{m}"
    for m in (
        "raycast",
        "lidar",
        "robot",
        "odometry",
        "world",
        "mapping",
        "mappers",
        "carmen",
        "explore",
        "runner",
    )
]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0
    assert result.failed == 0
