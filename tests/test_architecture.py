"""The package reads as the data flow: no import runs back up, no cycle between packages.

Every module of ``src/map2map`` is parsed with :mod:`ast` (imports at the top, inside
functions and under ``TYPE_CHECKING`` alike, relative and absolute) and every import of
another map2map package is checked against :data:`LAYERS`, bottom to top::

    core < maps < trajectory < robotlog < parametric | sim | slam < evaluate
         < jobs < datasets < learn < reports < demo < cli

A package may import its own modules and any package of a lower layer; packages of
one layer (``parametric``, ``sim``, ``slam``) do not import each other. ``datasets``
sits above ``jobs`` so that it may use them (today the pair builder calls the domain
functions directly, for the reasons in ``datasets.pair``); ``learn`` trains on the
datasets; ``reports`` reads every layer below. Heavy optional dependencies stay where
they are needed: ``torch`` only in ``map2map.learn``, ``dask`` only in ``map2map.learn``
and ``map2map.datasets`` (the scale-out), and ``import map2map`` loads neither them nor
matplotlib nor numba.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
PKG = SRC / "map2map"

#: Layer of every package (and top-level module) of map2map; lower imports higher never.
LAYERS: dict[str, float] = {
    "core": 0,
    "_version": 0,
    "errors": 0.5,  # shims of map2map.core kept for old import paths
    "_io": 0.5,
    "viz": 0.5,
    "maps": 1,
    "trajectory": 2,
    "robotlog": 3,
    "parametric": 4,
    "sim": 4,
    "slam": 4,
    "evaluate": 5,
    "jobs": 6,
    "datasets": 7,
    "learn": 8,
    "reports": 8.5,
    "demo": 9,
    "experiments": 9.5,  # the accuracy experiments read every layer below; nothing imports them
    "cli": 10,
    "__main__": 11,
    "__init__": 10,  # the package root re-exports the public API (lazily)
}

#: Old module paths that only re-export a moved module; map2map itself never uses them.
SHIMS = {
    "map2map.errors",
    "map2map._io",
    "map2map.viz",
    "map2map.maps.grid",
    "map2map.evaluate.halmstad",
    "map2map.evaluate.synthetic",
}

#: Heavy dependency -> packages allowed to import it.
HEAVY = {"torch": {"learn"}, "dask": {"learn", "datasets"}}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _imports(path: Path) -> list[tuple[str, int]]:
    """(absolute module name, line) of every import in a module, functions included."""
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out += [(a.name, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            if node.module:
                out.append((mod, node.lineno))
            else:  # from . import x: x may be a module
                out += [(f"{mod}.{a.name}", node.lineno) for a in node.names]
    return out


def _package(module: str) -> str | None:
    """The map2map package (layer key) of a module name, None outside map2map."""
    parts = module.split(".")
    if parts[0] != "map2map":
        return None
    return parts[1] if len(parts) > 1 else "__init__"


MODULES = sorted(PKG.rglob("*.py"))


def _graph() -> dict[str, set[tuple[str, str, int]]]:
    """package -> {(imported package, importing module, line)}."""
    graph: dict[str, set[tuple[str, str, int]]] = {}
    for path in MODULES:
        src = _package(_module_name(path))
        for mod, line in _imports(path):
            dst = _package(mod)
            if dst is not None and dst != src:
                graph.setdefault(src, set()).add((dst, _module_name(path), line))
    return graph


def test_every_package_has_a_layer():
    found = {_package(_module_name(p)) for p in MODULES}
    assert not found - set(LAYERS), f"give these packages a layer: {sorted(found - set(LAYERS))}"


def test_no_import_runs_up_or_across_a_layer():
    bad = []
    for src, edges in _graph().items():
        for dst, module, line in sorted(edges):
            if dst not in LAYERS or src not in LAYERS:
                continue
            if LAYERS[dst] > LAYERS[src] or (LAYERS[dst] == LAYERS[src] and src != "__init__"):
                bad.append(f"{module}:{line} imports map2map.{dst} ({src} is below or beside it)")
    assert not bad, "\n".join(bad)


def test_no_cycle_between_packages():
    graph = {k: {d for d, _, _ in v} for k, v in _graph().items()}
    graph.pop("__init__", None)  # the root only re-exports; its lazy imports are strings
    for g in graph.values():
        g.discard("__init__")  # `from .. import __version__` reads the root's version only
    state: dict[str, int] = {}

    def visit(n: str, path: list[str]) -> None:
        state[n] = 1
        for m in sorted(graph.get(n, ())):
            if state.get(m) == 1:
                pytest.fail("import cycle: " + " -> ".join([*path, n, m]))
            if m not in state:
                visit(m, [*path, n])
        state[n] = 2

    for n in sorted(graph):
        if n not in state:
            visit(n, [])


def test_no_module_uses_the_old_paths():
    bad = [
        f"{_module_name(p)}:{line} imports {mod}"
        for p in MODULES
        if _module_name(p) not in SHIMS
        for mod, line in _imports(p)
        if mod in SHIMS
    ]
    assert not bad, "\n".join(bad)


def test_heavy_dependencies_stay_in_their_packages():
    bad = []
    for p in MODULES:
        pkg = _package(_module_name(p))
        for mod, line in _imports(p):
            top = mod.split(".")[0]
            if top in HEAVY and pkg not in HEAVY[top]:
                bad.append(f"{_module_name(p)}:{line} imports {mod}")
    assert not bad, "\n".join(bad)


def test_import_map2map_stays_light():
    code = (
        "import sys, map2map\n"
        "heavy = [m for m in ('matplotlib', 'numba', 'torch', 'dask') if m in sys.modules]\n"
        "print(','.join(heavy))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True,
        env={"PYTHONPATH": str(SRC), "PATH": ""},
    )  # fmt: skip
    assert out.stdout.strip() == "", f"import map2map loads {out.stdout.strip()}"


def test_the_checker_sees_relative_and_nested_imports(tmp_path):
    """The parser resolves ``from ..x import y`` in a package module and imports in functions."""
    mod = PKG / "sim" / "runner.py"
    found = {m for m, _ in _imports(mod)}
    assert "map2map.core.grid" in found  # top-level relative import
    assert "scipy" in found  # an import inside a function
