"""Layout of ``benchmarks/`` and ``map2map.experiments`` (issue #31).

Benchmarks run as modules from the repository root (``python3 -m benchmarks.bench_sim``)
and experiments as ``python3 -m map2map.experiments.<name>``: none of them edits
``sys.path`` to find the package. Every experiment is a folder holding its package
docstring (``__init__.py``), its script (``__main__.py``) and the write-up of its current
result (``README.md``).
"""

from __future__ import annotations

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
BENCHMARKS = REPO / "benchmarks"
EXPERIMENTS = REPO / "src" / "map2map" / "experiments"

#: ``sys.path.insert(...)``, ``.append``, ``.extend``, ``sys.path += ...``, ``sys.path = ...``
SYS_PATH_EDIT = re.compile(r"\bsys\.path\s*(\.\s*(insert|append|extend)\s*\(|\+=|=(?!=))")

def _scripts() -> list[Path]:
    files = sorted(BENCHMARKS.rglob("*.py")) + sorted(EXPERIMENTS.rglob("*.py"))
    return [p for p in files if "__pycache__" not in p.parts]


def _edits(paths: list[Path]) -> list[str]:
    out = []
    for p in paths:
        for i, line in enumerate(p.read_text().splitlines(), 1):
            if SYS_PATH_EDIT.search(line):
                out.append(f"{p.relative_to(REPO)}:{i}: {line.strip()}")
    return out


def test_no_script_edits_sys_path():
    bad = _edits(_scripts())
    assert not bad, "run as a module instead of editing sys.path:\n" + "\n".join(bad)


def test_the_pattern_sees_every_kind_of_edit():
    for line in ("sys.path.insert(0, str(ROOT / 'src'))", "sys.path.append(x)",
                 "sys.path += [x]", "sys.path = [x, *sys.path]", "sys.path.extend(y)"):  # fmt: skip
        assert SYS_PATH_EDIT.search(line), line
    for line in ("env['PYTHONPATH'] = str(src)", "if p in sys.path:", "sys.path == x"):
        assert not SYS_PATH_EDIT.search(line), line


def test_every_experiment_has_its_script_and_write_up():
    folders = sorted(
        p for p in EXPERIMENTS.iterdir() if p.is_dir() and not p.name.startswith(("_", "."))
    )
    assert folders, f"no experiment folders in {EXPERIMENTS}"
    missing = [
        f"{p.relative_to(REPO)}/{f}"
        for p in folders
        for f in ("__init__.py", "__main__.py", "README.md")
        if not (p / f).is_file()
    ]
    assert not missing, "every experiment needs these files:\n" + "\n".join(missing)


def test_benchmarks_is_a_package():
    assert (BENCHMARKS / "__init__.py").is_file()
