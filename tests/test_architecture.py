"""The package reads as the data flow: no import runs back up, no cycle between packages or files.

Every module of ``src/map2map`` is parsed with :mod:`ast` and every import of another
map2map module is checked against :data:`LAYERS`, bottom to top::

    core < maps < trajectory < robotlog < parametric | sim | slam < evaluate
         < datasets < learn < jobs < experiments < reports < demo < cli

An import is any of: ``import`` and ``from ... import`` statements (at the top, inside
functions and under ``TYPE_CHECKING`` alike, relative and absolute); an
``importlib.import_module`` or ``__import__`` call with a constant name; and a
``"map2map.x.y"`` or ``"map2map.x.y:attr"`` string in a module-level registry (a dict,
list, tuple or set literal assigned at the top of a module), which names a module to be
imported later. A dynamic import whose name is computed is allowed only in the modules of
:data:`DYNAMIC_IMPORTS`, each of which says where its names come from.

A package may import its own modules and any package of a lower layer; packages of
one layer (``parametric``, ``sim``, ``slam``) do not import each other. ``learn`` trains
on the ``datasets``; ``jobs`` (one function per command) sit above both so that the
learned-model commands can use them; ``reports`` reads every layer below. Every imported
map2map name must be a module that exists (or a name in one) in a package with a layer.
No two modules import each other, directly or around a loop, not even from inside a
function. Heavy optional dependencies stay where they are needed: ``torch`` only in
``map2map.learn``, ``dask`` (and its ``distributed`` scheduler) only in
``map2map.learn`` and ``map2map.datasets`` (the scale-out), the optional ``rosbags``
only in ``map2map.robotlog`` (ROS bags), and ``import map2map`` loads none of them
nor matplotlib nor numba.

One room per idea: the command line imports from ``learn`` only config modules (its
defaults), the work goes through a job; the pair folder's file names are spelled only in
``datasets.pairfolder`` and a DXF drawing is made only in ``maps.dxf``; no module of
``learn`` is over :data:`LEARN_MAX_LINES` lines.

The checks are functions of a source root, so that the tests at the end plant each kind
of violation in a small package under ``tmp_path`` and see the check refuse it.
"""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
PKG = SRC / "map2map"

#: Layer of every package (and top-level module) of map2map; lower imports higher never.
LAYERS: dict[str, float] = {
    "core": 0,
    "_version": 0,
    "maps": 1,
    "trajectory": 2,
    "robotlog": 3,
    "parametric": 4,
    "sim": 4,
    "slam": 4,
    "evaluate": 5,
    "datasets": 7,
    "learn": 8,
    "jobs": 8.2,
    "experiments": 8.4,  # the thesis's tables and figures; reports.reproduce runs them
    "reports": 8.5,
    "demo": 9,
    "cli": 10,
    "__main__": 11,
    "__init__": 10,  # the package root re-exports the public API (lazily)
}

#: Heavy dependency -> packages allowed to import it.
HEAVY = {
    "torch": {"learn"},
    "dask": {"learn", "datasets"},
    "distributed": {"learn", "datasets"},  # dask's scheduler
    "rosbags": {"robotlog"},  # the optional ROS bag reader and writer (robotlog.rosbag)
}

#: Modules that import by a computed name, and where those names come from.
DYNAMIC_IMPORTS = {
    "map2map": "the lazy public API: the module names of _LAZY (checked as a registry)",
    "map2map.cli.main": "its own subcommand modules, map2map.cli.<COMMANDS>",
    "map2map.reports.reproduce.runner": "its own sections, map2map.reports.reproduce.<SECTIONS>",
}

#: Known cycles between two modules, each to be removed; both directions are allowed.
ALLOWED_CYCLES: set[tuple[str, str]] = set()

#: Imports of a module that is gone, each to be fixed: (importing module, name imported).
ALLOWED_MISSING: set[tuple[str, str]] = set()

_NAME = re.compile(r"map2map(\.[A-Za-z_]\w*)+(:[A-Za-z_]\w*)?")


@dataclass(frozen=True)
class Import:
    """One import found in a module: the name as written (made absolute) and its line."""

    module: str  # importing module
    name: str  # absolute dotted name imported (for ``from a import b``: ``a.b``)
    line: int
    kind: str  # "import", "from", "call" (import_module / __import__), "registry", "dynamic"


def module_name(path: Path, src: Path) -> str:
    """Dotted module name of a file under the source root ``src``."""
    parts = list(path.relative_to(src).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def modules(src: Path, top: str = "map2map") -> dict[str, Path]:
    """Every module of the package ``top`` under ``src``: name -> file."""
    return {module_name(p, src): p for p in sorted((src / top).rglob("*.py"))}


def _call_name(func: ast.expr) -> str | None:
    if isinstance(func, ast.Attribute):
        return func.attr
    if isinstance(func, ast.Name):
        return func.id
    return None


def imports(path: Path, src: Path) -> list[Import]:
    """Every import in a module (see the module docstring for what counts as one)."""
    name = module_name(path, src)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]

    def relative(level: int, rest: str | None) -> str:
        base = package.split(".")
        base = base[: len(base) - (level - 1)]
        return ".".join(base + ([rest] if rest else []))

    tree = ast.parse(path.read_text(), str(path))
    out: list[Import] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [Import(name, a.name, node.lineno, "import") for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            mod = relative(node.level, node.module) if node.level else node.module or ""
            out += [Import(name, f"{mod}.{a.name}", node.lineno, "from") for a in node.names]
        elif isinstance(node, ast.Call) and _call_name(node.func) in {
            "import_module",
            "__import__",
        }:
            arg = node.args[0] if node.args else None
            if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
                target = arg.value
                if target.startswith("."):
                    level = len(target) - len(target.lstrip("."))
                    target = relative(level, target[level:] or None)
                out.append(Import(name, target, node.lineno, "call"))
            else:
                out.append(Import(name, "", node.lineno, "dynamic"))
    for stmt in tree.body:  # module-level registries
        value = stmt.value if isinstance(stmt, (ast.Assign, ast.AnnAssign)) else None
        if not isinstance(value, (ast.Dict, ast.List, ast.Tuple, ast.Set)):
            continue
        for node in ast.walk(value):
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                if _NAME.fullmatch(node.value):
                    target = node.value.partition(":")[0]
                    out.append(Import(name, target, node.lineno, "registry"))
    return out


def resolve(imp: Import, known: set[str], top: str = "map2map") -> str | None:
    """The module an import loads, None outside ``top``, "" for an unknown internal name.

    ``from a import b`` loads ``a.b`` when that is a module, else ``a``; a registry
    string ``a.b.c`` names the longest module prefix (the rest is an attribute).
    """
    parts = imp.name.split(".")
    if parts[0] != top:
        return None
    if imp.kind in {"import", "call"}:
        return imp.name if imp.name in known else ""
    for n in range(len(parts), 0, -1):
        cand = ".".join(parts[:n])
        if cand in known:
            if imp.kind == "from" and n < len(parts) - 1:
                return ""  # from a.b import c where a.b is no module
            if imp.kind == "registry" and cand == top:
                return ""  # a registry string naming no module below the root
            return cand
    return ""


def layer_key(module: str) -> str:
    """The :data:`LAYERS` key of a map2map module."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def module_graph(
    src: Path, top: str = "map2map", allowed_missing=ALLOWED_MISSING
) -> tuple[dict[str, set[str]], list[str]]:
    """(module -> {imported modules of ``top``}, problems: unknown names, unlisted dynamics).

    An unknown name in ``allowed_missing`` (pairs of importing module, name) is no problem.
    """
    mods = modules(src, top)
    known = set(mods)
    graph: dict[str, set[str]] = {m: set() for m in mods}
    bad = []
    for mod, path in mods.items():
        for imp in imports(path, src):
            if imp.kind == "dynamic":
                if mod not in DYNAMIC_IMPORTS:
                    bad.append(f"{mod}:{imp.line} imports a computed name")
                continue
            dst = resolve(imp, known, top)
            if dst == "" and (mod, imp.name) not in allowed_missing:
                bad.append(f"{mod}:{imp.line} imports {imp.name}, no module of {top}")
            elif dst and dst != mod:
                graph[mod].add(dst)
    return graph, bad


def check_names(src: Path, top: str = "map2map", allowed_missing=ALLOWED_MISSING) -> list[str]:
    """Unknown internal names, computed imports outside DYNAMIC_IMPORTS, unlayered packages."""
    graph, bad = module_graph(src, top, allowed_missing)
    for mod in graph:
        if layer_key(mod) not in LAYERS:
            bad.append(f"{mod}: give package {layer_key(mod)} a layer")
    return bad


def check_layers(src: Path, top: str = "map2map") -> list[str]:
    """Imports that run up a layer, or across to another package of the same layer."""
    graph, _ = module_graph(src, top)
    bad = []
    for mod, targets in sorted(graph.items()):
        a = layer_key(mod)
        for dst in sorted(targets):
            b = layer_key(dst)
            if a == b or a not in LAYERS or b not in LAYERS:
                continue
            if LAYERS[b] > LAYERS[a] or (LAYERS[b] == LAYERS[a] and a != "__init__"):
                bad.append(f"{mod} imports {dst} ({a} is below or beside {b})")
    return bad


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one node (Tarjan), sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(out)


def check_package_cycles(src: Path, top: str = "map2map") -> list[str]:
    """Cycles between packages (the root, which only re-exports, left out)."""
    graph, _ = module_graph(src, top)
    pkgs: dict[str, set[str]] = {}
    for mod, targets in graph.items():
        a = layer_key(mod)
        if a == "__init__":
            continue
        pkgs.setdefault(a, set()).update(layer_key(t) for t in targets)
    for a, targets in pkgs.items():
        targets.discard(a)
        targets.discard("__init__")
    return ["package cycle: " + " <-> ".join(c) for c in _cycles(pkgs)]


def check_file_cycles(src: Path, top: str = "map2map", allowed=ALLOWED_CYCLES) -> list[str]:
    """Cycles between modules, imports inside functions included; ``allowed`` pairs aside."""
    graph, _ = module_graph(src, top)
    for a, b in allowed:
        graph.get(a, set()).discard(b)
        graph.get(b, set()).discard(a)
    return ["file cycle: " + " <-> ".join(c) for c in _cycles(graph)]


def check_heavy(src: Path, top: str = "map2map") -> list[str]:
    """Imports of a :data:`HEAVY` dependency outside the packages allowed it."""
    bad = []
    for mod, path in modules(src, top).items():
        for imp in imports(path, src):
            dep = imp.name.split(".")[0]
            if dep in HEAVY and layer_key(mod) not in HEAVY[dep]:
                bad.append(f"{mod}:{imp.line} imports {imp.name}")
    return bad


#: Module -> the one place where a kind of file is written or laid out.
OWNERS = {
    "pair folder": ("map2map.datasets.pairfolder",
                    {"A.png", "B.png", "A.yaml", "B.yaml"}),
}
#: Calls only one module makes: (dotted call) -> owning module.
ONE_WRITER = {"ezdxf.new": "map2map.maps.dxf"}
#: Longest module of learn/ (lines).
LEARN_MAX_LINES = 600


def check_cli_parses_only(src: Path, top: str = "map2map") -> list[str]:
    """The command line reads only configuration from the learned models (their
    defaults); the work goes through :mod:`map2map.jobs`."""
    bad = []
    for mod, path in modules(src, top).items():
        if layer_key(mod) != "cli":
            continue
        for imp in imports(path, src):
            parts = imp.name.split(".")
            if parts[:2] == [top, "learn"] and "config" not in parts:
                bad.append(f"{mod}:{imp.line} imports {imp.name} (the CLI calls a job)")
    return bad


def _dotted(func: ast.expr) -> str | None:
    """``a.b.c`` of a call's function, None for anything but names and attributes."""
    parts = []
    while isinstance(func, ast.Attribute):
        parts.append(func.attr)
        func = func.value
    if not isinstance(func, ast.Name):
        return None
    return ".".join([func.id, *reversed(parts)])


def check_owners(src: Path, top: str = "map2map") -> list[str]:
    """File names of a layout (``"A.png"``) only in the module that owns it, and
    :data:`ONE_WRITER`'s calls only in theirs."""
    bad = []
    for mod, path in modules(src, top).items():
        tree = ast.parse(path.read_text(), str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                for what, (owner, names) in OWNERS.items():
                    if node.value in names and mod != owner:
                        bad.append(f"{mod}:{node.lineno} spells the {what} name "
                                   f"{node.value!r} (use {owner})")
            elif isinstance(node, ast.Call):
                name = _dotted(node.func)
                if name in ONE_WRITER and mod != ONE_WRITER[name]:
                    bad.append(f"{mod}:{node.lineno} calls {name} (only "
                               f"{ONE_WRITER[name]} does)")
    return bad


def check_learn_sizes(src: Path, top: str = "map2map", limit: int = LEARN_MAX_LINES
                      ) -> list[str]:
    """Modules of learn/ longer than ``limit`` lines."""
    return [f"{mod}: {n} lines" for mod, path in modules(src, top).items()
            if layer_key(mod) == "learn"
            and (n := len(path.read_text().splitlines())) > limit]


# ------------------------------------------------------------------------ the package


def test_every_import_names_a_known_module():
    bad = check_names(SRC)
    assert not bad, "\n".join(bad)


def test_no_import_runs_up_or_across_a_layer():
    bad = check_layers(SRC)
    assert not bad, "\n".join(bad)


def test_no_cycle_between_packages():
    bad = check_package_cycles(SRC)
    assert not bad, "\n".join(bad)


def test_no_cycle_between_files():
    bad = check_file_cycles(SRC)
    assert not bad, "\n".join(bad)


def test_the_allowed_cycles_still_exist():
    """An allowed cycle that is gone must leave :data:`ALLOWED_CYCLES` too."""
    cycles = _cycles(module_graph(SRC)[0])
    gone = [p for p in ALLOWED_CYCLES if not any(set(p) <= set(c) for c in cycles)]
    assert not gone, f"remove from ALLOWED_CYCLES: {gone}"


def test_the_allowed_missing_imports_still_exist():
    """A fixed import must leave :data:`ALLOWED_MISSING` too."""
    _, bad = module_graph(SRC, allowed_missing=set())
    gone = [
        (m, n)
        for m, n in ALLOWED_MISSING
        if not any(
            b.startswith(f"{m}:") and b.endswith(f"imports {n}, no module of map2map") for b in bad
        )
    ]
    assert not gone, f"remove from ALLOWED_MISSING: {gone}"


def test_heavy_dependencies_stay_in_their_packages():
    bad = check_heavy(SRC)
    assert not bad, "\n".join(bad)


def test_import_map2map_stays_light():
    code = (
        "import sys, map2map\n"
        "heavy = [m for m in ('matplotlib', 'numba', 'torch', 'dask', 'distributed',"
        " 'rosbags')"
        " if m in sys.modules]\n"
        "print(','.join(heavy))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True,
        env={"PYTHONPATH": str(SRC), "PATH": ""},
    )  # fmt: skip
    assert out.stdout.strip() == "", f"import map2map loads {out.stdout.strip()}"


def test_the_checker_sees_relative_and_nested_imports():
    """The parser resolves ``from ..x import y`` in a package module and imports in functions."""
    found = {i.name for i in imports(PKG / "sim" / "runner.py", SRC)}
    assert "map2map.core.grid.OccupancyMap" in found  # top-level relative import
    assert "scipy.ndimage" in found  # an import inside a function
    graph, _ = module_graph(SRC)
    assert "map2map.core.grid" in graph["map2map.sim.runner"]


def test_the_root_registry_is_read_at_the_top_layer():
    """The root's lazy ``_LAZY`` table counts as imports, and passes: the root is on top."""
    graph, _ = module_graph(SRC)
    assert "map2map.sim.runner" in graph["map2map"]


# ----------------------------------------------------- planted violations are refused


def _plant(tmp_path: Path, files: dict[str, str]) -> Path:
    """A fake ``map2map`` under ``tmp_path/src`` with a core and a sim, plus ``files``."""
    src = tmp_path / "src"
    base = {
        "map2map/__init__.py": "",
        "map2map/_version.py": "__version__ = '0'\n",
        "map2map/core/__init__.py": "",
        "map2map/core/grid.py": "X = 1\n",
        "map2map/sim/__init__.py": "",
        "map2map/sim/runner.py": "from ..core.grid import X\n",
    }
    for rel, text in {**base, **files}.items():
        p = src / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)
    return src


def test_a_clean_planted_package_passes(tmp_path):
    src = _plant(tmp_path, {})
    for check in (check_names, check_layers, check_package_cycles, check_file_cycles,
                  check_heavy):  # fmt: skip
        assert check(src) == [], check.__name__


def test_an_upward_import_is_refused(tmp_path):
    src = _plant(tmp_path, {"map2map/core/bad.py": "def f():\n    from ..sim import runner\n"})
    assert check_layers(src) == ["map2map.core.bad imports map2map.sim.runner "
                                 "(core is below or beside sim)"]  # fmt: skip


def test_an_unknown_internal_name_is_refused(tmp_path):
    src = _plant(tmp_path, {
        "map2map/core/a.py": "from .. import __version__\n",
        "map2map/core/b.py": "import map2map.core.nothere\n",
        "map2map/core/c.py": "from ..nothere.x import y\n",
        "map2map/nolayer/__init__.py": "",
    })  # fmt: skip
    bad = "\n".join(check_names(src))
    assert "map2map.core.a:1 imports map2map.__version__" not in bad  # the root: a layer issue
    assert "map2map.core.b:1 imports map2map.core.nothere" in bad
    assert "map2map.core.c:1 imports map2map.nothere.x.y" in bad
    assert "give package nolayer a layer" in bad
    # the root is a module, so `from .. import __version__` reads the top layer: refused
    assert any(b.startswith("map2map.core.a imports map2map ") for b in check_layers(src))


def test_imports_by_string_are_checked(tmp_path):
    src = _plant(tmp_path, {
        "map2map/core/reg.py": 'MAPPERS = {"oracle": "map2map.sim.runner:make"}\n',
        "map2map/core/call.py": (
            "import importlib\n"
            "def f():\n"
            "    return importlib.import_module('map2map.sim.runner')\n"
        ),
        "map2map/core/dunder.py": "m = __import__('map2map.sim')\n",
        "map2map/core/dyn.py": "import importlib\ndef f(n):\n    importlib.import_module(n)\n",
        "map2map/core/bad_string.py": 'NAMES = ("map2map.nothere:f",)\n',
        "map2map/__init__.py": '_LAZY = {"run": "map2map.sim.runner"}\n',
    })  # fmt: skip
    layers = "\n".join(check_layers(src))
    for mod in ("reg", "call", "dunder"):
        assert f"map2map.core.{mod} imports map2map.sim" in layers
    assert "map2map imports" not in layers  # the root's lazy table is at the top layer
    names = "\n".join(check_names(src))
    assert "map2map.core.dyn:3 imports a computed name" in names
    assert "map2map.core.bad_string:1 imports map2map.nothere" in names


def test_a_cycle_between_files_is_refused(tmp_path):
    src = _plant(tmp_path, {
        "map2map/core/a.py": "from .b import g\ndef f():\n    return g()\n",
        "map2map/core/b.py": "def g():\n    from .a import f\n    return f\n",
    })  # fmt: skip
    assert check_file_cycles(src) == ["file cycle: map2map.core.a <-> map2map.core.b"]
    allowed = {("map2map.core.a", "map2map.core.b")}
    assert check_file_cycles(src, allowed=allowed) == []
    assert check_package_cycles(src) == []  # one package: only the file check sees it


def test_a_cycle_between_packages_is_refused(tmp_path):
    src = _plant(tmp_path, {"map2map/core/a.py": "def f():\n    from ..sim import runner\n"})
    assert check_package_cycles(src) == ["package cycle: core <-> sim"]


def test_distributed_counts_as_dask(tmp_path):
    src = _plant(tmp_path, {
        "map2map/sim/farm.py": "def f():\n    from distributed import Client\n",
        "map2map/datasets/__init__.py": "import distributed\nimport dask.array\n",
        "map2map/core/t.py": "import torch\n",
    })  # fmt: skip
    assert check_heavy(src) == [
        "map2map.core.t:1 imports torch",
        "map2map.sim.farm:2 imports distributed.Client",
    ]


def test_the_cli_only_parses():
    assert not check_cli_parses_only(SRC), "\n".join(check_cli_parses_only(SRC))


def test_one_owner_per_file_layout_and_writer():
    assert not check_owners(SRC), "\n".join(check_owners(SRC))


def test_no_learn_module_is_over_600_lines():
    assert not check_learn_sizes(SRC), "\n".join(check_learn_sizes(SRC))


def test_a_cli_doing_a_models_work_is_refused(tmp_path):
    src = _plant(tmp_path, {
        "map2map/learn/__init__.py": "",
        "map2map/learn/ba/__init__.py": "",
        "map2map/learn/ba/config.py": "A = 1\n",
        "map2map/learn/ba/autocorrect.py": "B = 2\n",
        "map2map/cli/__init__.py": "",
        "map2map/cli/ok.py": "from ..learn.ba.config import A\n",
        "map2map/cli/bad.py": "def run():\n    from ..learn.ba.autocorrect import B\n",
    })  # fmt: skip
    assert check_cli_parses_only(src) == [
        "map2map.cli.bad:2 imports map2map.learn.ba.autocorrect.B (the CLI calls a job)"]


def test_a_second_pair_folder_reader_or_dxf_writer_is_refused(tmp_path):
    src = _plant(tmp_path, {
        "map2map/datasets/__init__.py": "",
        "map2map/datasets/pairfolder.py": "PLAN = 'A.png'\n",
        "map2map/sim/reader.py": "def f(d):\n    return d / 'B.png'\n",
        "map2map/maps/__init__.py": "",
        "map2map/maps/dxf.py": "import ezdxf\ndoc = ezdxf.new()\n",
        "map2map/sim/cad.py": "import ezdxf\ndoc = ezdxf.new(units=6)\n",
    })  # fmt: skip
    assert sorted(check_owners(src)) == [
        "map2map.sim.cad:2 calls ezdxf.new (only map2map.maps.dxf does)",
        "map2map.sim.reader:2 spells the pair folder name 'B.png' (use "
        "map2map.datasets.pairfolder)",
    ]


def test_a_long_learn_module_is_refused(tmp_path):
    src = _plant(tmp_path, {"map2map/learn/__init__.py": "",
                            "map2map/learn/big.py": "x = 1\n" * 7})
    assert check_learn_sizes(src, limit=6) == ["map2map.learn.big: 7 lines"]
