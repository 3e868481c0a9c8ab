"""DXF floor plans built with ezdxf: entities, layers, blocks, units, inside/outside."""

import math

import ezdxf
import numpy as np
import pytest
from scipy import ndimage as ndi

from map2map.core.errors import InputError
from map2map.core.grid import OccupancyMap
from map2map.maps.dxf import load_dxf
from map2map.maps.formats import load_map, save_map

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


def test_mline_walls(tmp_path):
    doc = ezdxf.new(units=6)
    ml = doc.modelspace().add_mline([(0, 0), (4, 0), (4, 3), (0, 3)], close=True)
    ml.dxf.scale_factor = 0.2  # a 0.2 m thick wall drawn as two parallel lines
    ml.update_geometry()
    m = load_dxf(save(doc, tmp_path), resolution=RES, wall_thickness=0.02)
    assert at(m, 2, 1.5) == 255 and at(m, 0, 1.5) == 0 and at(m, -0.5, 1.5) == 127
    assert components(m.free) == 1


def test_wide_polylines_keep_their_width(tmp_path):
    doc = ezdxf.new(units=6)
    pl = room(doc.modelspace(), 0, 0, 4, 3)
    pl.dxf.const_width = 0.3  # drawn 30 cm wide in the CAD file
    m = load_dxf(save(doc, tmp_path), resolution=RES, wall_thickness=0.1)
    row = m.data[m.world_to_pixel(2, 1.5)[0]]
    assert (row == 0).sum() == 2 * 6  # two walls of 0.3 m = 6 px
    assert int(m.free.sum()) == round(3.7 * 2.7 / RES**2)


def test_double_line_walls_have_no_free_cavity(tmp_path):
    doc = ezdxf.new(units=6)
    msp = doc.modelspace()
    room(msp, 0, 0, 4, 3)
    room(msp, 0.2, 0.2, 3.8, 2.8)  # inner face: the wall is drawn as two lines 0.2 m apart
    m = load_dxf(save(doc, tmp_path), resolution=RES, wall_thickness=0.02)
    assert at(m, 0.1, 1.5) == 0 and at(m, 2, 1.5) == 255
    assert components(m.free) == 1


def test_walls_drawn_as_two_lines_keep_their_faces(tmp_path):
    """A 10 x 6 m room inside 0.2 m walls drawn as their two faces: widened both ways
    like centre lines (before 2026-11-29) each face moved half the thickness into its
    room, and the room read 9.9 x 5.9 m."""
    doc = ezdxf.new(units=6)
    msp = doc.modelspace()
    room(msp, 0, 0, 10, 6)
    room(msp, -0.2, -0.2, 10.2, 6.2)
    m = load_dxf(save(doc, tmp_path), resolution=RES, wall_thickness=0.1)
    assert m.meta["face_lines"] == 8
    assert at(m, 0.025, 3) == 255 and at(m, -0.025, 3) == 0 and at(m, -0.175, 3) == 0
    assert at(m, -0.225, 3) == 127 and at(m, 9.975, 3) == 255 and at(m, 10.025, 3) == 0
    assert at(m, 5, 5.975) == 255 and at(m, 5, 6.025) == 0
    assert int(m.free.sum()) == round(10 * 6 / RES**2)
    # a centre line alone is widened both ways, as before
    one = ezdxf.new(units=6)
    room(one.modelspace(), 0, 0, 10, 6)
    c = load_dxf(save(one, tmp_path, "one.dxf"), resolution=RES, wall_thickness=0.2)
    assert c.meta["face_lines"] == 0 and at(c, 0.075, 3) == 0 and at(c, 0.125, 3) == 255


def test_a_door_between_jambs_of_a_two_line_wall_is_sealed_and_kept_open(tmp_path):
    """Jambs (short lines closing the cavity at a door) touch the faces, so no loose
    end sealed the door: the outside flooded the flat, which read no free cell at all
    (before 2026-11-29). The jambs are widened into the wall only."""
    doc = ezdxf.new(units=6)
    line = doc.modelspace().add_line
    for a, b in [((0, 6), (10, 6)), ((-0.2, 6.2), (10.2, 6.2)), ((0, 0), (0, 6)),
                 ((-0.2, -0.2), (-0.2, 6.2)), ((10, 0), (10, 6)), ((10.2, -0.2), (10.2, 6.2)),
                 ((0, 0), (7, 0)), ((7.9, 0), (10, 0)), ((-0.2, -0.2), (7, -0.2)),
                 ((7.9, -0.2), (10.2, -0.2)), ((7, 0), (7, -0.2)), ((7.9, 0), (7.9, -0.2)),
                 # a 0.1 m partition with a door at y 2.0-2.9
                 ((5, 0), (5, 2)), ((5.1, 0), (5.1, 2)), ((5, 2), (5.1, 2)),
                 ((5, 2.9), (5, 6)), ((5.1, 2.9), (5.1, 6)), ((5, 2.9), (5.1, 2.9))]:
        line(a, b)
    m = load_dxf(save(doc, tmp_path), resolution=RES, wall_thickness=0.1)
    assert components(m.free) == 1
    # 10 x 6 less the partition, plus the entrance's doorway through the outer wall
    assert abs(float(m.free.sum()) * RES**2 - (60 - 0.1 * 5.1 + 0.9 * 0.2)) < 0.1
    assert at(m, 4.975, 1) == 255 and at(m, 5.025, 1) == 0 and at(m, 5.125, 1) == 255
    # the doorways are as wide as drawn: no jamb widened into them
    assert at(m, 7.025, -0.1) == 255 and at(m, 6.975, -0.1) == 0 and at(m, 7.875, -0.1) == 255
    assert at(m, 5.05, 2.025) == 255 and at(m, 5.05, 1.975) == 0 and at(m, 5.05, 2.875) == 255
    assert at(m, 7.45, -0.3) == 127                 # outside the door: still outside


def test_a_centre_line_ends_where_it_is_drawn_and_corners_stay_closed(tmp_path):
    """A partition drawn as its centre line with a 0.9 m door gap: square caps on the
    free ends narrowed the doorway by the wall's thickness (0.8 m at 0.1 m, before
    2026-11-29). Where two lines meet, the cap still closes the corner."""
    doc = ezdxf.new(units=6)
    line = doc.modelspace().add_line
    for a, b in [((0, 0), (10, 0)), ((10, 0), (10, 6)), ((10, 6), (0, 6)), ((0, 6), (0, 0)),
                 ((5, 0), (5, 2)), ((5, 2.9), (5, 6))]:
        line(a, b)
    m = load_dxf(save(doc, tmp_path), resolution=RES, wall_thickness=0.1)
    assert at(m, 5, 2.025) == 255 and at(m, 5, 2.875) == 255       # the gap as drawn
    assert at(m, 5, 1.975) == 0 and at(m, 5, 2.925) == 0
    for x, y in ((-0.025, -0.025), (10.025, 6.025), (-0.025, 6.025), (10.025, -0.025)):
        assert at(m, x, y) == 0                                      # corners closed


def test_door_swings_are_left_out_and_the_doorway_stays_open(tmp_path):
    """A door block (a leaf drawn as a thin outline, open at 90 degrees, and its swing
    arc) in a partition's doorway: drawn as walls, the arc closed the doorway and cut a
    quarter disc out of the room (before 2026-11-29)."""
    doc = ezdxf.new(units=6)
    msp = doc.modelspace()
    room(msp, 0, 0, 10, 6)
    msp.add_line((5, 0), (5, 2))
    msp.add_line((5, 2.9), (5, 6))
    blk = doc.blocks.new("DOOR90")
    blk.add_lwpolyline([(0, 0), (0.9, 0), (0.9, 0.04), (0, 0.04)], close=True)
    blk.add_arc((0, 0), 0.9, 0, 90)
    msp.add_blockref("DOOR90", (5, 2.0))             # hinge on the jamb, opening east
    m = load_dxf(save(doc, tmp_path), resolution=RES, wall_thickness=0.1)
    assert m.meta["door_entities"] == {"ARC": 1, "LWPOLYLINE": 1}
    assert components(m.free) == 1
    assert at(m, 5.0, 2.45) == 255 and at(m, 5.45, 2.05) == 255 and at(m, 5.6, 2.6) == 255
    # the same door inserted mirrored (xscale -1: its arc's centre and angles come in a
    # flipped coordinate system), opening west: its leaf is found too
    msp.add_blockref("DOOR90", (5, 2.0), dxfattribs={"xscale": -1})
    both = load_dxf(save(doc, tmp_path, "both.dxf"), resolution=RES, wall_thickness=0.1)
    assert both.meta["door_entities"] == {"ARC": 2, "LWPOLYLINE": 2}
    assert at(both, 4.55, 2.05) == 255 and components(both.free) == 1
    msp.delete_entity(msp.query("INSERT")[-1])
    kept = load_dxf(save(doc, tmp_path, "kept.dxf"), resolution=RES, wall_thickness=0.1,
                    door_swings=False)
    assert "ARC" in kept.meta["entities"] and components(kept.free) == 2   # rooms apart
    # an arc that is no door (a curved wall of radius 3 m) stays a wall
    curved = ezdxf.new(units=6)
    room(curved.modelspace(), 0, 0, 10, 6)
    curved.modelspace().add_arc((5, 0), 3.0, 0, 90)
    c = load_dxf(save(curved, tmp_path, "curved.dxf"), resolution=RES, wall_thickness=0.1)
    assert c.meta["door_entities"] == {} and at(c, 5 + 3 * 0.7071, 3 * 0.7071) == 0


def test_a_tiled_floor_hatch_is_no_wall(tmp_path):
    """A pattern hatch over a room's floor (tiles) was filled as wall: the room became
    a block of wall. A hatched wall and a solid fill stay walls."""
    doc = ezdxf.new(units=6)
    msp = doc.modelspace()
    room(msp, 0, 0, 10, 6)
    msp.add_line((5, 0), (5, 2))
    msp.add_line((5, 2.9), (5, 6))
    tiles = msp.add_hatch()
    tiles.set_pattern_fill("ANSI37", scale=0.5)
    tiles.paths.add_polyline_path([(5, 0), (10, 0), (10, 6), (5, 6)], is_closed=True)
    wall = msp.add_hatch()                          # a hatched wall, 0.3 m, in the west room
    wall.set_pattern_fill("ANSI31", scale=0.2)
    wall.paths.add_polyline_path([(1, 3), (4, 3), (4, 3.3), (1, 3.3)], is_closed=True)
    m = load_dxf(save(doc, tmp_path), resolution=RES, wall_thickness=0.1)
    assert m.meta["floor_hatches"] == 1 and m.meta["entities"]["HATCH"] == 1
    assert at(m, 7.5, 3) == 255 and at(m, 2.5, 3.15) == 0
    solid = ezdxf.new(units=6)
    room(solid.modelspace(), 0, 0, 10, 6)
    core = solid.modelspace().add_hatch()           # a solid fill: a wall, however wide
    core.paths.add_polyline_path([(6, 1), (9, 1), (9, 5), (6, 5)], is_closed=True)
    c = load_dxf(save(solid, tmp_path, "solid.dxf"), resolution=RES, wall_thickness=0.1)
    assert c.meta["floor_hatches"] == 0 and at(c, 7.5, 3) == 0


def test_thin_slanted_wall_still_separates_rooms(tmp_path):
    doc = ezdxf.new(units=6)
    msp = doc.modelspace()
    room(msp, 0, 0, 4, 4)
    msp.add_line((0, 0.3), (4, 3.7))  # a slanted wall 1 cm thick, far thinner than a pixel
    m = load_dxf(save(doc, tmp_path), resolution=RES, wall_thickness=0.01)
    assert components(m.free) == 2


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
    with pytest.raises(InputError, match="give the right `units` or a coarser `resolution`"):
        load_dxf(save(doc, tmp_path, "huge.dxf"))
    with pytest.raises(InputError, match="resolution must be > 0"):
        load_dxf(tmp_path / "huge.dxf", resolution=0)
    with pytest.raises(InputError, match="wall thickness must be > 0"):
        load_dxf(tmp_path / "huge.dxf", wall_thickness=-0.1)
    with pytest.raises(InputError, match="units must be one of"):
        load_dxf(tmp_path / "huge.dxf", units="furlong")


# ------------------------------------------------------------------ writing
def flat_map(origin=(-1.234, 5.678, 0.0)):
    """A walled flat: 1 px and 3 px walls, a door, a staircase (diagonal) wall, a column."""
    data = np.full((60, 90), 127, np.uint8)
    data[5:55, 5:85] = 0
    data[8:52, 8:82] = 255  # 3 px outer walls
    data[8:52, 40] = 0  # 1 px interior wall ...
    data[25:33, 40] = 255  # ... with a door
    for k in range(15):  # a staircase wall, 8-connected steps made 4-connected
        data[10 + k, 55 + k] = 0
        data[10 + k, 56 + k] = 0
    data[40:44, 65:69] = 0  # a column
    return OccupancyMap(data, RES, origin)


def aligned(a, b):
    """b's cells on a's grid (both on one lattice): rows/cols offset of b in a."""
    r, c = a.world_to_pixel(*b.pixel_to_world(0, 0))
    return int(r), int(c)


def test_export_round_trip_keeps_every_wall_cell(tmp_path):
    m = flat_map()
    save_map(m, tmp_path / "flat.dxf")
    back = load_map(tmp_path / "flat.dxf")
    assert back.resolution == m.resolution
    r, c = aligned(back, m)
    window = back.data[r : r + m.height, c : c + m.width]
    assert np.array_equal(window == 0, m.occupied)  # every wall cell, no more, no less
    assert np.array_equal(window == 255, m.free)  # enclosed free space comes back free
    outside = np.ones(back.shape, bool)
    outside[r : r + m.height, c : c + m.width] = False
    assert (back.data[outside] == 127).all()


def test_export_writes_a_hatch_in_metres_with_the_map_frame(tmp_path):
    m = flat_map(origin=(10.0, 20.0, 0.0))
    save_map(m, tmp_path / "flat.dxf")
    doc = ezdxf.readfile(tmp_path / "flat.dxf")
    hatches = doc.modelspace().query("HATCH")
    assert len(hatches) == 1 and hatches[0].dxf.layer == "WALLS"
    assert doc.header["$INSUNITS"] == 6
    lo, hi = np.full(2, np.inf), np.full(2, -np.inf)
    for path in hatches[0].paths:
        pts = np.array([v[:2] for v in path.vertices])
        lo, hi = np.minimum(lo, pts.min(0)), np.maximum(hi, pts.max(0))
    # walls span cells 5..84 x 5..54: metres from the origin, 1 % of a cell inside
    assert np.allclose(lo, [10 + 5 * RES, 20 + 5 * RES], atol=0.02 * RES)
    assert np.allclose(hi, [10 + 85 * RES, 20 + 55 * RES], atol=0.02 * RES)


def test_the_same_map_gives_the_same_dxf_bytes(tmp_path):
    """ezdxf stamps dates and random GUIDs unless told; map2map's writer tells it, and
    leaves ezdxf's own option as it found it."""
    from map2map.maps.dxf import save_segments_dxf

    m = flat_map()
    save_map(m, tmp_path / "a.dxf")
    save_map(m, tmp_path / "b.dxf")
    assert (tmp_path / "a.dxf").read_bytes() == (tmp_path / "b.dxf").read_bytes()
    segs = np.array([[0.0, 0.0, 4.0, 0.0], [4.0, 0.0, 4.0, 3.0]])
    save_segments_dxf(segs, tmp_path / "c.dxf")
    save_segments_dxf(segs, tmp_path / "d.dxf")
    assert (tmp_path / "c.dxf").read_bytes() == (tmp_path / "d.dxf").read_bytes()
    assert ezdxf.options.write_fixed_meta_data_for_testing is False
    doc = ezdxf.new()
    doc.saveas(tmp_path / "e.dxf")  # a caller's own drawing still gets its GUIDs
    assert ezdxf.readfile(tmp_path / "e.dxf").header["$FINGERPRINTGUID"] != (
        ezdxf.readfile(tmp_path / "c.dxf").header["$FINGERPRINTGUID"])


def test_export_of_a_rotated_map_is_drawn_rotated(tmp_path):
    m = flat_map(origin=(0.3, -0.2, math.pi / 2))  # a quarter turn: still on a lattice
    save_map(m, tmp_path / "rot.dxf")
    back = load_map(tmp_path / "rot.dxf")
    turned = OccupancyMap(np.rot90(m.data).copy(), RES, (0.3 - m.height * RES, -0.2, 0.0))
    r, c = aligned(back, turned)
    window = back.data[r : r + turned.height, c : c + turned.width]
    assert np.array_equal(window == 0, turned.occupied)
