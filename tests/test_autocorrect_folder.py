"""``map2map autocorrect FOLDER``: which files are maps, and no two outputs on one file
(issue #32, item 5). Only the planning of the paths is exercised (no model is run)."""

from __future__ import annotations

import numpy as np
import pytest

from map2map.core.errors import InputError
from map2map.core.grid import OccupancyMap
from map2map.jobs.autocorrect import AutocorrectSpec, _plan_paths
from map2map.maps.formats import save_map


def _map(path):
    m = OccupancyMap(np.full((20, 30), 255, np.uint8), resolution=0.05)
    save_map(m, path)


def test_a_ros_map_in_a_folder_is_one_map(tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    _map(src / "map.yaml")                             # writes map.yaml + map.pgm
    assert sorted(p.name for p in src.iterdir()) == ["map.pgm", "map.yaml"]
    files, outs = _plan_paths(AutocorrectSpec(src, tmp_path / "out", dxf=tmp_path / "dxf"))
    assert [f.name for f in files] == ["map.yaml"]
    assert outs[0]["map"] == tmp_path / "out" / "map.yaml"
    assert outs[0]["dxf"] == tmp_path / "dxf" / "map.dxf"


def test_a_lone_image_beside_a_ros_map_is_still_a_map(tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    _map(src / "map.yaml")
    _map(src / "other.png")
    files, _ = _plan_paths(AutocorrectSpec(src, tmp_path / "out"))
    assert [f.name for f in files] == ["map.yaml", "other.png"]


def test_two_inputs_writing_one_file_are_refused_before_writing(tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    _map(src / "a.yaml")
    (src / "a.pgm").rename(src / "img.pgm")             # a.yaml now names img.pgm
    (src / "a.yaml").write_text((src / "a.yaml").read_text().replace("a.pgm", "img.pgm"))
    _map(src / "a.png")                                  # and a.png: both write dxf/a.dxf
    spec = AutocorrectSpec(src, tmp_path / "out", dxf=tmp_path / "dxf")
    with pytest.raises(InputError, match="would write .*a.dxf"):
        _plan_paths(spec)
    assert not (tmp_path / "out").exists() and not (tmp_path / "dxf").exists()


def test_a_yaml_output_and_a_pgm_input_of_the_same_name_collide(tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    _map(src / "b.yaml")
    (src / "b.pgm").rename(src / "c.pgm")
    (src / "b.yaml").write_text((src / "b.yaml").read_text().replace("b.pgm", "c.pgm"))
    _map(src / "b.png")
    _map(src / "b.pgm")                                  # out/b.yaml also writes out/b.pgm
    with pytest.raises(InputError, match="would write"):
        _plan_paths(AutocorrectSpec(src, tmp_path / "out"))


def test_the_command_refuses_in_one_line(tmp_path, capsys):
    pytest.importorskip("torch")
    from map2map.cli.main import main

    src = tmp_path / "in"
    src.mkdir()
    _map(src / "a.png")
    _map(src / "a.pgm")                                  # both write dxf/a.dxf
    rc = main(["autocorrect", str(src), "--out", str(tmp_path / "out"),
               "--dxf", str(tmp_path / "dxf")])
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert rc == 2 and len(lines) == 1, err
    assert "would write" in lines[0] and "Traceback" not in err
    assert not (tmp_path / "out").exists()


def test_the_default_model_needs_no_pytorch(tmp_path):
    """``autocorrect`` with the default ``none`` runs where torch cannot be imported (the
    base install); ``--model thesis`` then fails with one line naming the extra, exit 2."""
    import subprocess
    import sys

    d = np.full((90, 140), 127, np.uint8)
    d[10:80, 10:130] = 255
    d[10, 10:130] = d[79, 10:130] = 0
    d[10:80, 10] = d[10:80, 129] = 0
    save_map(OccupancyMap(d, 0.05), tmp_path / "in.yaml")
    run = ("import sys, importlib.abc\n"        # torch cannot be found, as on the base install
           "class NoTorch(importlib.abc.MetaPathFinder):\n"
           "    def find_spec(self, name, path=None, target=None):\n"
           "        if name.split('.')[0] == 'torch':\n"
           "            raise ModuleNotFoundError(\"No module named 'torch'\", name=name)\n"
           "sys.meta_path.insert(0, NoTorch())\n"
           "from map2map.cli.main import main\n"
           "sys.exit(main(sys.argv[1:]))")

    def cli(*args):
        return subprocess.run([sys.executable, "-c", run, "autocorrect",
                               str(tmp_path / "in.yaml"), *args],
                              capture_output=True, text=True, timeout=300)

    ok = cli("--out", str(tmp_path / "o.yaml"), "--dxf", str(tmp_path / "o.dxf"))
    assert ok.returncode == 0, ok.stderr
    assert (tmp_path / "o.yaml").exists() and (tmp_path / "o.dxf").exists()
    bad = cli("--out", str(tmp_path / "t.yaml"), "--model", "thesis")
    assert bad.returncode == 2 and "Traceback" not in bad.stderr
    assert "map2map[learn]" in bad.stderr and len(bad.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "t.yaml").exists()


def test_workers_change_nothing_but_the_speed(tmp_path, capsys):
    """A folder of 16 maps (the drawer then runs in worker processes): the same files
    with ``--workers 1`` and ``--workers 2``; ``--workers 0`` is refused in one line."""
    from map2map.cli.main import main

    src = tmp_path / "in"
    src.mkdir()
    rng = np.random.default_rng(0)
    for i in range(16):
        d = np.full((90, 140), 127, np.uint8)
        r0, c0 = rng.integers(5, 15, 2)
        d[r0:80, c0:130] = 255
        d[r0, c0:130] = d[79, c0:130] = 0
        d[r0:80, c0] = d[r0:80, 129] = 0
        d[r0:80, 60 + i] = 0                                  # an interior wall
        d[40:44, 60 + i] = 255                                # with a door
        save_map(OccupancyMap(d, 0.05), src / f"m{i:02d}.yaml")
    got = {}
    for w in (1, 2):
        assert main(["autocorrect", str(src), "--out", str(tmp_path / f"o{w}"),
                     "--workers", str(w)]) == 0
        got[w] = {p.name: p.read_bytes() for p in sorted((tmp_path / f"o{w}").iterdir())}
    assert len(got[1]) == 32 and got[1] == got[2]
    capsys.readouterr()
    assert main(["autocorrect", str(src), "--out", str(tmp_path / "o0"), "--workers",
                 "0"]) == 2
    err = capsys.readouterr().err
    assert "workers" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o0").exists()


def test_only_a_missing_extra_reads_as_needs_pytorch(monkeypatch):
    """A model whose import fails on torch is refused in one line naming the extra; one
    that fails on anything else is a fault and keeps its own error (not 'needs PyTorch')."""
    import map2map.jobs.autocorrect as J

    def failing(name):
        def make(device):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return make

    monkeypatch.setitem(J.MODELS, "thesis", J.ModelEntry(failing("torch.nn"), "x"))
    with pytest.raises(InputError, match=r"needs PyTorch: pip install 'map2map\[learn\]'"):
        J.corrector("thesis")
    monkeypatch.setitem(J.MODELS, "thesis", J.ModelEntry(failing("map2map.gone"), "x"))
    with pytest.raises(ModuleNotFoundError, match="map2map.gone"):
        J.corrector("thesis")


def test_a_folder_leaves_the_cleaning_to_the_workers(tmp_path):
    """With ``none`` on a folder of 16 maps the workers clean and draw; the calling
    process only reads, wraps and writes, and imports neither numba nor scipy.ndimage
    (0.3-0.5 s before the pool could start, 2026-11-29)."""
    import subprocess
    import sys

    src = tmp_path / "in"
    src.mkdir()
    for i in range(16):
        d = np.full((60, 80), 127, np.uint8)
        d[5:55, 5:75] = 255
        d[5, 5:75] = d[54, 5:75] = 0
        d[5:55, 5] = d[5:55, 74] = 0
        d[5:55, 20 + i] = 0
        save_map(OccupancyMap(d, 0.05), src / f"m{i:02d}.yaml")
    run = ("import sys\n"
           "from map2map.cli.main import main\n"
           "rc = main(sys.argv[1:])\n"
           "heavy = sorted({m.split('.')[0] + ('.ndimage' if m.startswith('scipy.ndimage') "
           "else '') for m in sys.modules if m.startswith(('numba', 'scipy.ndimage'))})\n"
           "print('HEAVY', heavy)\n"
           "sys.exit(rc)")
    r = subprocess.run([sys.executable, "-c", run, "autocorrect", str(src), "--out",
                        str(tmp_path / "out"), "--workers", "2"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert "HEAVY []" in r.stdout
    assert len(list((tmp_path / "out").glob("*.yaml"))) == 16
