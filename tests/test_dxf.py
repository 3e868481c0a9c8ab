"""DXF floor plans built with ezdxf: entities, layers, blocks, units, inside/outside."""

import math

import ezdxf
import numpy as np
import pytest
from scipy import ndimage as ndi

from map2map.errors import InputError
from map2map.maps.dxf import load_dxf
from map2map.maps.rasterize import segment_pixels, trace

RES = 0.05


def save(doc, tmp_path, name="plan.dxf"):
    path = tmp_path / name
    doc.saveas(path)
    return path


def at(m, x, y):
    r, c = m.world_to_pixel(x, y)
    return int(m.data[int(r), int(c)])


def components(mask):
    return ndi.label(mask, np.ones((3, 3), bool))[1]


def room(msp, x0, y0, x1, y1, **attribs):
    return msp.add_lwpolyline(
        [(x0, y0), (x1, y0), (x1, y1), (x0, y1)], close=True, dxfattribs=attribs
    )


def test_closed_room_is_free_inside_unknown_outside(tmp_path):
    doc = ezdxf.new(units=6)
    room(doc.modelspace(), 0, 0, 4, 3)
    m = load_dxf(save(doc, tmp_path), resolution=RES, wall_thickness=0.1)
    assert at(m, 2, 1.5) == 255 and at(m, -0.3, 1.5) == 127 and at(m, 0, 1.5) == 0
    # walls are exactly 0.1 m = 2 px thick: free is (4 - 0.1) x (3 - 0.1) m
    assert int(m.free.sum()) == round(3.9 * 2.9 / RES**2)
    row = m.data[m.world_to_pixel(2, 1.5)[0]]
    assert (row == 0).sum() == 4
    assert m.meta["entities"] == {"LWPOLYLINE": 1} and m.meta["units"] in ("m", "Meters")


def test_units_from_header_and_option(tmp_path):
    mm = ezdxf.new(units=4)  # millimetres
    room(mm.modelspace(), 0, 0, 4000, 3000)
    a = load_dxf(save(mm, tmp_path, "mm.dxf"), resolution=RES)
    metres = ezdxf.new(units=6)
    room(metres.modelspace(), 0, 0, 4, 3)
    b = load_dxf(save(metres, tmp_path, "m.dxf"), resolution=RES)
    assert a == b
    plain = ezdxf.new()
    plain.header["$INSUNITS"] = 0
    room(plain.modelspace(), 0, 0, 400, 300)
    c = load_dxf(save(plain, tmp_path, "cm.dxf"), resolution=RES, units="cm")
    assert c == b
    assert load_dxf(tmp_path / "cm.dxf", resolution=1.0).meta["units_assumed"] is True


def test_lines_with_a_door_gap_and_the_outside_stays_out(tmp_path):
    doc = ezdxf.new(units=6)
    msp = doc.modelspace()
    # a 5 x 4 m flat made of LINEs; the entrance in the bottom wall is a 0.9 m opening
    for a, b in [((0, 0), (2, 0)), ((2.9, 0), (5, 0)), ((5, 0), (5, 4)), ((5, 4), (0, 4))]:
        msp.add_line(a, b)
    msp.add_line((0, 4), (0, 0))
    m = load_dxf(save(doc, tmp_path), resolution=RES, wall_thickness=0.1)
    assert at(m, 2.5, 2) == 255  # inside is free although the door is open
    assert at(m, 2.45, 0.0) == 255  # the opening itself is free, not wall
    assert at(m, 2.5, -0.4) == 127
    # without gap closing the outside floods in through the door
    m0 = load_dxf(tmp_path / "plan.dxf", resolution=RES, close_gaps=0)
    assert at(m0, 2.5, 2) == 127


def test_arcs_circles_and_bulged_polylines(tmp_path):
    doc = ezdxf.new(units=6)
    msp = doc.modelspace()
    msp.add_circle((0, 0), 2.0)
    # a semicircular room: an ARC closed by a LINE, 10 m away
    msp.add_arc((10, 0), 2.0, 0, 180)
    msp.add_line((8, 0), (12, 0))
    # an old-style POLYLINE whose bulge makes a half circle (radius 1) on top of a square
    msp.add_polyline2d(
        [(20, 0, 0, 0, 0), (22, 0, 0, 0, 1.0), (22, 2, 0, 0, 0), (20, 2, 0, 0, 0)],
        format="xyseb",
        close=True,
    )
    m = load_dxf(save(doc, tmp_path), resolution=RES, wall_thickness=0.1)
    area = m.free.sum() * RES**2
    expect = math.pi * 1.95**2 + 0.5 * math.pi * 1.95**2 - 2 * 1.95 * 0.05
    expect += 1.9 * 1.9 + 0.5 * math.pi * 0.95**2 + 0.05 * 1.9
    assert abs(area - expect) < 0.04 * expect
    assert at(m, 0, 0) == 255 and at(m, 10, 1) == 255 and at(m, 22.5, 1) == 255
    assert at(m, 10, -0.5) == 127 and at(m, 23.2, 1) == 127
    assert components(m.free) == 3


def test_hatch_is_solid_wall(tmp_path):
    doc = ezdxf.new(units=6)
    msp = doc.modelspace()
    room(msp, 0, 0, 4, 4)
    hatch = msp.add_hatch()
    hatch.paths.add_polyline_path([(1.5, 1.5), (2.5, 1.5), (2.5, 2.5), (1.5, 2.5)], is_closed=True)
    m = load_dxf(save(doc, tmp_path), resolution=RES)
    assert at(m, 2, 2) == 0 and at(m, 1, 1) == 255
    assert m.occupied[m.world_to_pixel(2.2, 2.2)] and m.meta["entities"]["HATCH"] == 1


def test_blocks_are_expanded_with_their_insert_layer(tmp_path):
    doc = ezdxf.new(units=6)
    doc.layers.add("WALLS")
    doc.layers.add("FURNITURE")
    block = doc.blocks.new("ROOM")
    room(block, 0, 0, 2, 1)  # on layer 0: takes the INSERT's layer
    msp = doc.modelspace()
    msp.add_blockref("ROOM", (10, 5), dxfattribs={"layer": "WALLS", "rotation": 90, "xscale": 2})
    room(msp, 0, 0, 1, 1, layer="FURNITURE")
    m = load_dxf(save(doc, tmp_path), resolution=RES, layers=["walls"])
    # rotated by 90 degrees and stretched 2x along x: the room spans x 9..10, y 5..9
    assert at(m, 9.5, 7) == 255 and at(m, 10.5, 7) == 127
    assert m.meta["layers"] == ["WALLS"]
    assert not m.contains(*m.world_to_pixel(0.5, 0.5))  # furniture layer left out
    both = load_dxf(tmp_path / "plan.dxf", resolution=RES)
    assert at(both, 0.5, 0.5) == 255 and at(both, 9.5, 7) == 255


def test_double_line_walls_have_no_free_cavity(tmp_path):
    doc = ezdxf.new(units=6)
    msp = doc.modelspace()
    room(msp, 0, 0, 4, 3)
    room(msp, 0.2, 0.2, 3.8, 2.8)  # inner face: the wall is drawn as two lines 0.2 m apart
    m = load_dxf(save(doc, tmp_path), resolution=RES, wall_thickness=0.02)
    assert at(m, 0.1, 1.5) == 0 and at(m, 2, 1.5) == 255
    assert components(m.free) == 1


def test_thin_slanted_wall_still_separates_rooms(tmp_path):
    doc = ezdxf.new(units=6)
    msp = doc.modelspace()
    room(msp, 0, 0, 4, 4)
    msp.add_line((0, 0.3), (4, 3.7))  # a slanted wall 1 cm thick, far thinner than a pixel
    m = load_dxf(save(doc, tmp_path), resolution=RES, wall_thickness=0.01)
    assert components(m.free) == 2


@pytest.mark.parametrize("seed", range(5))
def test_segment_pixels_is_an_exact_4_connected_supercover(seed):
    rng = np.random.default_rng(seed)
    p0, p1 = rng.uniform(0, 20, (2, 2))
    rows, cols = segment_pixels(p0[None], p1[None])
    got = set(zip(rows.tolist(), cols.tolist(), strict=True))
    t = np.linspace(0, 1, 200001)
    pts = p0 + t[:, None] * (p1 - p0)
    crossed = set(
        zip(
            np.floor(pts[:, 1]).astype(int).tolist(),
            np.floor(pts[:, 0]).astype(int).tolist(),
            strict=True,
        )
    )
    assert crossed <= got and len(got - crossed) <= 2
    mask = trace((21, 21), [np.array([p0, p1])])
    assert ndi.label(mask)[1] == 1  # 4-connected


# ------------------------------------------------------------------ bad input
def test_no_entities_on_chosen_layers(tmp_path):
    doc = ezdxf.new(units=6)
    doc.layers.add("TEXT")
    msp = doc.modelspace()
    room(msp, 0, 0, 4, 3)
    msp.add_text("Kitchen", dxfattribs={"layer": "TEXT"})
    path = save(doc, tmp_path)
    with pytest.raises(InputError, match="no drawable entities"):
        load_dxf(path, layers=["TEXT"])
    with pytest.raises(InputError, match="no layer named nope"):
        load_dxf(path, layers=["nope"])
    empty = ezdxf.new()
    with pytest.raises(InputError, match="no drawable entities"):
        load_dxf(save(empty, tmp_path, "empty.dxf"))


def test_bad_files_and_parameters(tmp_path):
    with pytest.raises(InputError, match="file not found"):
        load_dxf(tmp_path / "absent.dxf")
    (tmp_path / "junk.dxf").write_bytes(b"\x00\x01 certainly not a drawing \xff" * 10)
    with pytest.raises(InputError, match="not a readable DXF"):
        load_dxf(tmp_path / "junk.dxf")
    doc = ezdxf.new()
    doc.header["$INSUNITS"] = 0
    room(doc.modelspace(), 0, 0, 40000, 30000)  # millimetres without units: 40 km wide
    with pytest.raises(InputError, match="give the right --units"):
        load_dxf(save(doc, tmp_path, "huge.dxf"))
    with pytest.raises(InputError, match="resolution must be > 0"):
        load_dxf(tmp_path / "huge.dxf", resolution=0)
    with pytest.raises(InputError, match="units must be one of"):
        load_dxf(tmp_path / "huge.dxf", units="furlong")
