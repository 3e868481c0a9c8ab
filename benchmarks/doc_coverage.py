"""Numpydoc coverage of the public API: how many public callables document what they take.

Counts, per package, the public functions, methods and classes (names without a
leading underscore, defined in a public module, methods of public classes) and how
many docstrings carry a numpydoc ``Parameters`` section (among those that take
arguments), a ``Returns``/``Yields`` section (among functions that return something:
annotation other than ``None``), and an ``Examples`` section. Read with :mod:`ast`,
nothing is imported. Dataclasses and other classes are counted for ``Parameters``
only when their ``__init__`` takes arguments they do not document as ``Attributes``.

Usage::

    python3 -m benchmarks.doc_coverage                  # ./src
    python3 -m benchmarks.doc_coverage --src OLD/src    # another source tree
"""

from __future__ import annotations

import argparse
import ast
import re
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SECTION = re.compile(r"^\s*(Parameters|Returns|Yields|Examples|Attributes)\s*\n\s*-{3,}", re.M)
#: The packages issue 12 item 4 asks to document.
SCOPE = ("maps", "trajectory", "parametric", "sim", "slam", "robotlog", "core")


def _sections(doc: str | None) -> set[str]:
    return set(SECTION.findall(doc or ""))


def _takes_arguments(fn: ast.FunctionDef | ast.AsyncFunctionDef, method: bool) -> bool:
    a = fn.args
    names = [x.arg for x in a.posonlyargs + a.args + a.kwonlyargs]
    if method and names and names[0] in ("self", "cls"):
        names = names[1:]
    return bool(names or a.vararg or a.kwarg)


def _returns_value(fn: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    if fn.returns is not None:
        return not (isinstance(fn.returns, ast.Constant) and fn.returns.value is None)
    return any(isinstance(n, ast.Return) and n.value is not None for n in ast.walk(fn))


def _is_property(fn) -> bool:
    return any(
        (isinstance(d, ast.Name) and d.id in ("property", "cached_property"))
        or (isinstance(d, ast.Attribute) and d.attr == "setter")
        for d in fn.decorator_list
    )


def _count(c: Counter, fn, method: bool) -> None:
    if fn.name.startswith("_") or _is_property(fn):
        return
    s = _sections(ast.get_docstring(fn))
    c["functions"] += 1
    if _takes_arguments(fn, method):
        c["need_parameters"] += 1
        c["have_parameters"] += "Parameters" in s
    if _returns_value(fn):
        c["need_returns"] += 1
        c["have_returns"] += bool(s & {"Returns", "Yields"})
    c["have_examples"] += "Examples" in s


def audit(src: Path) -> dict[str, Counter]:
    """Per package: public callables and how many carry each section."""
    out: dict[str, Counter] = {}
    for path in sorted((src / "map2map").rglob("*.py")):
        rel = path.relative_to(src / "map2map").with_suffix("").parts
        if any(p.startswith("_") and p != "__init__" for p in rel):
            continue
        pkg = rel[0] if len(rel) > 1 else "(top)"
        c = out.setdefault(pkg, Counter())
        tree = ast.parse(path.read_text(), str(path))

        for node in tree.body:
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                _count(c, node, False)
            elif isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
                c["classes"] += 1
                s = _sections(ast.get_docstring(node))
                c["classes_documented"] += bool(s & {"Parameters", "Attributes"})
                for item in node.body:
                    if isinstance(item, ast.FunctionDef | ast.AsyncFunctionDef):
                        _count(c, item, True)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--src", type=Path, default=ROOT / "src", help="source tree to read")
    args = ap.parse_args()
    table = audit(args.src)
    cols = ("functions", "need_parameters", "have_parameters", "need_returns", "have_returns")
    cols += ("have_examples", "classes", "classes_documented")
    print(f"{'package':<12}" + "".join(f"{c:>19}" for c in cols))
    totals: dict[str, Counter] = {"scope": Counter(), "all": Counter()}
    for pkg, c in sorted(table.items()):
        print(f"{pkg:<12}" + "".join(f"{c[k]:>19}" for k in cols))
        totals["all"].update(c)
        if pkg in SCOPE:
            totals["scope"].update(c)
    for name, c in totals.items():
        print(f"{'= ' + name:<12}" + "".join(f"{c[k]:>19}" for k in cols))
    s = totals["scope"]
    print(
        f"in scope ({', '.join(SCOPE)}): Parameters {s['have_parameters']}/{s['need_parameters']}, "
        f"Returns {s['have_returns']}/{s['need_returns']}, examples "
        f"{s['have_examples']}/{s['functions']} public functions and methods"
    )


if __name__ == "__main__":
    main()
