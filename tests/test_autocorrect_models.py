"""``map2map autocorrect --model none|thesis|PATH`` (issue #32): the registry of
correctors in the jobs layer, the classical cleaning without a network (``none``) and
the thesis's Model_BA, from the command line on a small generated map."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

pytest.importorskip("torch")

from map2map.cli.main import main  # noqa: E402
from map2map.core.grid import OCCUPIED, OccupancyMap  # noqa: E402
from map2map.jobs.autocorrect import (  # noqa: E402
    DEFAULT_MODEL,
    MODELS,
    Corrector,
    corrector,
)
from map2map.learn.training.synthetic import make_pairs  # noqa: E402
from map2map.maps.formats import load_map, save_map  # noqa: E402


@pytest.fixture(scope="module")
def slam_map() -> OccupancyMap:
    """A small generated SLAM map (the parametric model's), not at the grid origin."""
    return OccupancyMap(make_pairs(1, 128, seed=3).b[0], 0.05, (1.0, -2.0, 0.0))


@pytest.mark.parametrize("model", ["none", "thesis", "PATH"])
def test_every_model_runs_from_the_command_line(tmp_path, capsys, slam_map, model):
    from map2map.learn.ba.model import pretrained_path

    save_map(slam_map, tmp_path / "in.yaml")
    if model == "PATH":  # a weights file given by its path
        model = str(shutil.copy(pretrained_path(), tmp_path / "w.safetensors"))
    rc = main(["autocorrect", str(tmp_path / "in.yaml"), "--out", str(tmp_path / "o.yaml"),
               "--model", model, "--dxf", str(tmp_path / "o.dxf"),
               "--figure", str(tmp_path / "o.png")])
    err = capsys.readouterr().err
    assert rc == 0, err
    out = load_map(tmp_path / "o.yaml")
    assert out.shape == slam_map.shape and out.origin == slam_map.origin
    assert (out.data == OCCUPIED).any()
    assert (tmp_path / "o.dxf").is_file() and (tmp_path / "o.png").is_file()
    assert "auto-corrected 1 map(s) with " in err


def test_none_reads_no_weights(tmp_path, capsys, monkeypatch, slam_map):
    """``--model none`` works where the weights are unreadable; ``thesis`` then fails
    with one line and exit 2."""
    import map2map.learn.ba.model as model_mod

    bad = tmp_path / "unreadable.safetensors"
    bad.write_bytes(b"not weights")
    bad.chmod(0)
    monkeypatch.setattr(model_mod, "pretrained_path", lambda: bad)

    def refuse(*a, **k):
        raise AssertionError("load_model called")

    monkeypatch.setattr(model_mod, "load_model", refuse)
    save_map(slam_map, tmp_path / "in.yaml")
    rc = main(["autocorrect", str(tmp_path / "in.yaml"), "--out", str(tmp_path / "o.yaml"),
               "--model", "none"])
    assert rc == 0 and load_map(tmp_path / "o.yaml").shape == slam_map.shape
    assert "with none" in capsys.readouterr().err
    monkeypatch.undo()
    monkeypatch.setattr(model_mod, "pretrained_path", lambda: bad)
    rc = main(["autocorrect", str(tmp_path / "in.yaml"), "--out", str(tmp_path / "t.yaml"),
               "--model", "thesis"])
    err = capsys.readouterr().err
    assert rc == 2 and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_none_is_the_anchored_cleaning_alone(slam_map):
    """``none`` straightens the input's own walls (fewer jagged wall pixels, the walls
    where they were), warns of no model, and refuses the options that need a network."""
    from map2map.core.errors import InputError

    none = corrector("none")
    assert isinstance(none, Corrector) and none.name == "none"
    (out,) = none.correct_many([slam_map])
    ac = out.meta["autocorrect"]
    assert ac["model"] == "none" and ac["warnings"] == [] and ac["segments_px"]
    occ_in, occ_out = slam_map.data == OCCUPIED, out.data == OCCUPIED
    assert (occ_in & occ_out).sum() > 0.5 * occ_in.sum()          # the input's own walls
    for bad in ({"anchor": False}, {"straighten": False}):
        with pytest.raises(InputError, match="need a network"):
            none.correct_many([slam_map], **bad)


def test_a_batch_is_drawn_alike_in_worker_processes_and_in_this_one():
    """From 16 maps on, ``none`` cleans and draws in worker processes (``workers``): same
    maps, same segments and record, in order."""
    maps = [OccupancyMap(b, 0.05) for b in make_pairs(16, 96, seed=5).b]
    none = corrector("none")
    one = none.correct_many(maps, workers=1)
    two = none.correct_many(maps, workers=2)
    for a, b in zip(one, two, strict=True):
        assert np.array_equal(a.data, b.data)
        assert a.meta["autocorrect"]["segments_px"] == b.meta["autocorrect"]["segments_px"]
        assert repr(a.meta) == repr(b.meta) and a.resolution == b.resolution
    assert len({a.data.tobytes() for a in one}) > 8               # the maps differ


def test_the_default_is_none_drawn_and_pretrained_the_thesis():
    from map2map.learn.ba.correctors import DrawnCorrector, NullCorrector, ThesisCorrector

    assert DEFAULT_MODEL == "none" and set(MODELS) >= {"none", "thesis"}
    default = corrector(None)
    assert default.name == "none" and isinstance(default, DrawnCorrector)
    assert isinstance(default.base, NullCorrector)
    assert isinstance(corrector("none", draw=False), NullCorrector)
    assert isinstance(corrector("thesis"), ThesisCorrector)           # as it is
    assert isinstance(corrector("thesis", draw=True), DrawnCorrector)
    assert corrector("pretrained").name == "thesis"
    assert corrector("thesis").source == corrector("pretrained").source


def test_the_default_output_is_the_shipped_models(slam_map):
    """The ``thesis`` corrector is :func:`autocorrect_many` with the shipped weights,
    pixel for pixel (the job's output before the registry)."""
    from map2map.learn.ba.autocorrect import autocorrect_many

    (ref,) = autocorrect_many([slam_map], "pretrained")
    (got,) = corrector("thesis").correct_many([slam_map])
    assert np.array_equal(ref.map.data, got.data)
    assert ref.map.meta["autocorrect"]["segments_px"] == got.meta["autocorrect"]["segments_px"]


def test_none_draws_one_sided_walls_as_thick_as_the_shipped_model():
    from map2map.learn.ba.model import load_model
    from map2map.learn.ba.null import PLAN_WALL_PX, NullNetwork

    net = load_model("pretrained")
    assert PLAN_WALL_PX == net.target_wall_px
    assert (NullNetwork().size, NullNetwork().data_size) == (net.size, net.data_size)


def test_the_library_takes_the_same_names(slam_map):
    """``map2map.autocorrect(m, "none" | "thesis")`` as the command line's ``--model``."""
    import warnings

    from map2map.core.errors import InputError
    from map2map.learn.ba.autocorrect import autocorrect

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        thesis = autocorrect(slam_map, "thesis")
        assert np.array_equal(thesis.data, autocorrect(slam_map).data)
    none = autocorrect(slam_map, "none")
    undrawn = corrector("none", draw=False).correct_many([slam_map])[0]
    assert np.array_equal(none.data, undrawn.data)     # the command line's draws it too
    with pytest.raises(InputError, match="need a network"):
        autocorrect(slam_map, "none", anchor=False)


def test_the_default_output_is_drawn_like_a_plan_and_its_dxf_agrees(tmp_path, capsys,
                                                                    slam_map):
    """With no ``--model`` the output goes through the plan drawer: one thickness, and the
    DXF holds the map's own segments; ``--no-draw`` is the classical cleaning as before;
    ``--draw-thickness`` sets the walls' metres; a thickness <= 0 is one line, exit 2."""
    import ezdxf

    from map2map.evaluate.drawing import median_wall_thickness
    from map2map.learn.ba.autocorrect import Correction

    save_map(slam_map, tmp_path / "in.yaml")
    args = ["autocorrect", str(tmp_path / "in.yaml")]
    assert main([*args, "--out", str(tmp_path / "d.yaml"), "--dxf", str(tmp_path / "d.dxf")]) == 0
    drawn = load_map(tmp_path / "d.yaml")
    (ref,) = corrector(None).correct_many([slam_map])
    assert np.array_equal(drawn.data, ref.data)
    lines = [(e.dxf.start, e.dxf.end) for e in
             ezdxf.readfile(tmp_path / "d.dxf").modelspace().query("LINE")]
    world = Correction.of(ref).segments
    assert len(lines) == len(world) > 0
    got = np.array(sorted((s.x, s.y, e.x, e.y) for s, e in lines))
    assert np.allclose(got, np.array(sorted(map(tuple, world))), atol=1e-6)
    # the plans' 0.30 m, less for a wall the input saw from both sides (drawn between
    # the faces it saw, grown by a pixel)
    tk = np.array(ref.meta["autocorrect"]["drawn"]["thicknesses_px"])
    assert tk.max() == pytest.approx(0.30 / 0.05) and (tk >= 2).all()
    assert 2.0 <= median_wall_thickness(drawn.data) <= 0.30 / 0.05 + 1.0
    assert main([*args, "--out", str(tmp_path / "n.yaml"), "--no-draw"]) == 0
    (undrawn,) = corrector("none", draw=False).correct_many([slam_map])
    assert np.array_equal(load_map(tmp_path / "n.yaml").data, undrawn.data)
    assert not np.array_equal(undrawn.data, drawn.data)
    assert main([*args, "--out", str(tmp_path / "t.yaml"), "--draw-thickness", "0.1"]) == 0
    assert median_wall_thickness(load_map(tmp_path / "t.yaml").data) <= 3.0
    capsys.readouterr()
    assert main([*args, "--out", str(tmp_path / "x.yaml"), "--draw-thickness", "0"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "draw-thickness" in err[0] and not (tmp_path / "x.yaml").exists()
