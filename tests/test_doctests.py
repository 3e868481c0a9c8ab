"""Every library module's docstring examples run and hold.

The modules are discovered, not listed, so a new module is covered the day it lands.
Command-line modules (``map2map.cli``) and ``__main__`` are thin wrappers without
examples and are left out.
"""

import doctest
import importlib
import pkgutil

import pytest

import map2map

MODULES = sorted(
    info.name
    for info in pkgutil.walk_packages(map2map.__path__, prefix="map2map.")
    if not info.name.startswith("map2map.cli") and not info.name.endswith("__main__")
)


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0


#: Glue that only writes files for a command or the demo (their tests run them end to end).
NO_EXAMPLE_NEEDED = {
    "map2map._version",
    "map2map.demo",
}


def test_library_modules_carry_examples():
    """Numpydoc with short examples: every non-package library module shows one."""
    missing = []
    for name in MODULES:
        if name in NO_EXAMPLE_NEEDED:
            continue
        module = importlib.import_module(name)
        if hasattr(module, "__path__"):  # packages: their __init__ only re-exports
            continue
        tests = doctest.DocTestFinder().find(module)
        if not any(t.examples for t in tests):
            missing.append(name)
    assert not missing, f"modules without a docstring example: {missing}"
