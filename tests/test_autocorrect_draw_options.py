"""``map2map autocorrect --draw-option KEY=VALUE``: the plan drawer's tolerances
(:class:`map2map.maps.vectorize.DrawOptions`) from the command line, with ``--model
none`` (no torch needed)."""

from __future__ import annotations

import numpy as np
import pytest

from map2map.cli.main import main
from map2map.core.errors import InputError
from map2map.core.grid import OccupancyMap
from map2map.jobs.autocorrect import corrector, parse_draw_options
from map2map.maps.formats import load_map, save_map
from map2map.maps.vectorize import DrawOptions

FREE, UNK, OCC = 255, 127, 0


def _z_wall() -> np.ndarray:
    """A walled room cut by an interior wall with a 0.7 m jog (at 0.05 m/px), which the
    drawer drops unless bridges reach runs that short (``bridge_run`` 0.5)."""
    m = np.full((100, 120), UNK, np.uint8)
    m[5:96, 5:115] = FREE
    m[5, 5:115] = m[95, 5:115] = OCC
    m[5:96, 5] = m[5:96, 114] = OCC
    m[10:51, 54] = OCC
    m[50, 40:55] = OCC
    m[50:91, 40] = OCC
    return m


def test_a_draw_option_reaches_the_drawer(tmp_path):
    m = OccupancyMap(_z_wall(), 0.05)
    save_map(m, tmp_path / "in.yaml")
    args = ["autocorrect", str(tmp_path / "in.yaml")]
    assert main([*args, "--out", str(tmp_path / "d.yaml")]) == 0
    assert main([*args, "--out", str(tmp_path / "b.yaml"), "--draw-option",
                 "bridge_run=0.5", "--draw-option", "bridge_share=0.5"]) == 0
    default, bridged = load_map(tmp_path / "d.yaml"), load_map(tmp_path / "b.yaml")
    (ref,) = corrector("none", draw_options=DrawOptions(bridge_run=0.5)).correct_many([m])
    assert np.array_equal(bridged.data, ref.data)
    # the jog: open by default (the two rooms open into each other), closed with it
    assert (default.data[50, 42:52] == FREE).all() and (bridged.data[50, 42:52] == OCC).all()


@pytest.mark.parametrize("item, says", [
    ("no_such=1", "not an option of the drawer"),
    ("bridge_run", "not an option of the drawer"),
    ("bridge_run=far", "bridge_run is a number"),
    ("bridge_run=-1", "must be 0 or more"),
    ("two_sided=1", "true or false"),
    ("families=2.5", "an integer"),
    ("tol=none", "tol is a number, not"),
])
def test_a_bad_draw_option_is_one_line_exit_2_nothing_written(tmp_path, capsys, item, says):
    save_map(OccupancyMap(_z_wall(), 0.05), tmp_path / "in.yaml")
    capsys.readouterr()
    rc = main(["autocorrect", str(tmp_path / "in.yaml"), "--out", str(tmp_path / "o.yaml"),
               "--draw-option", item])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "--draw-option" in err[0] and says in err[0]
    assert not (tmp_path / "o.yaml").exists()


def test_draw_options_on_an_undrawn_output_are_refused(tmp_path, capsys):
    save_map(OccupancyMap(_z_wall(), 0.05), tmp_path / "in.yaml")
    rc = main(["autocorrect", str(tmp_path / "in.yaml"), "--out", str(tmp_path / "o.yaml"),
               "--no-draw", "--draw-option", "bridge_run=0"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "add --draw" in err[0]
    assert not (tmp_path / "o.yaml").exists()


def test_parse_draw_options_types():
    assert parse_draw_options([]) is None
    o = parse_draw_options(["lean_px=none", "families=2", "cut_free=false", "tol=0.1"])
    assert o == DrawOptions(lean_px=None, families=2, cut_free=False, tol=0.1)
    with pytest.raises(InputError, match="lean_px is a number or none"):
        parse_draw_options(["lean_px=x"])
