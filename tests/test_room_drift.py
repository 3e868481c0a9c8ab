"""Room-wise rigid drift (map2map.learn.ab.room_drift): rooms from the plan, seeded draws,
nearly rigid inside rooms, walls not torn, wired into drift_params / drift_field /
apply_drift. No torch needed."""

import numpy as np
import pytest
from scipy import ndimage

from map2map.core.errors import InputError
from map2map.core.grid import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from map2map.learn.ab.drift import DriftParams, apply_drift, drift_field, drift_params, drift_rng
from map2map.learn.ab.room_drift import (
    RoomDriftParams,
    apply_room_drift,
    collapse_shift,
    room_adjacency,
    room_drift_field,
    segment_rooms,
    shared_walls,
    solenoidal,
)
from map2map.maps.floorplan import generate_floorplan
from map2map.parametric.field import DisplacementField, warp_map


def _three_rooms() -> np.ndarray:
    """Three rooms in a row joined by doors, 40 x 100 px."""
    p = np.full((44, 104), UNKNOWN, np.uint8)
    p[2:42, 2:102] = FREE
    p[2, 2:102] = p[41, 2:102] = OCCUPIED
    p[2:42, 2] = p[2:42, 101] = OCCUPIED
    for c in (35, 68):
        p[2:42, c] = OCCUPIED
        p[18:26, c] = FREE
    return p


def _wall_parts(m: np.ndarray) -> int:
    return ndimage.label(m == OCCUPIED, structure=np.ones((3, 3)))[1]


def test_segment_rooms_and_doors():
    p = _three_rooms()
    lab = segment_rooms(p, h_px=2.0)
    assert lab.max() == 3 and (lab > 0).all()              # walls and outside filled
    r = [int(lab[20, c]) for c in (15, 50, 85)]
    assert len(set(r)) == 3
    doors = room_adjacency(lab, p == FREE)
    a, b, c = r
    assert set(doors) == {tuple(sorted((a, b))), tuple(sorted((b, c)))}   # a-c not adjacent
    x, y = doors[tuple(sorted((a, b)))]
    assert abs(x - 35) < 2 and abs(y - 21.5) < 2          # at the door
    assert segment_rooms(np.full((5, 5), UNKNOWN, np.uint8)).max() == 0


def test_a_step_across_zero_slides_the_next_room_along_the_doors_wall():
    """``across=0``: with no rotation, each room's shift from its parent lies along the
    wall of the door between them (here vertical walls: no x shift at all); with the
    default ``across=1`` the shift has both components."""
    p = _three_rooms()
    _, axes = room_adjacency(segment_rooms(p, h_px=2.0), p == FREE, axes=True)
    assert all(abs(u[0]) < 1e-9 and abs(abs(u[1]) - 1) < 1e-9 for u in axes.values())
    for seed in range(5):
        d = room_drift_field(p, np.random.default_rng(seed),
                             RoomDriftParams(rot_deg=0.0, across=0.0, h_px=2.0,
                                             parametric=False))
        assert np.abs(d.transforms[:, 0, 2]).max() < 1e-9
        assert np.abs(d.transforms[:, 1, 2]).max() > 1e-3
    iso = room_drift_field(p, np.random.default_rng(0),
                           RoomDriftParams(rot_deg=0.0, h_px=2.0, parametric=False))
    assert np.abs(iso.transforms[:, 0, 2]).max() > 1e-3
    with pytest.raises(InputError, match="across"):
        RoomDriftParams(across=-1.0)


def test_seeded_same_bytes_and_other_seed_differs():
    plan = generate_floorplan(1, size=(12, 9))
    rp = RoomDriftParams()
    a = room_drift_field(plan.data, np.random.default_rng(5), rp)
    b = room_drift_field(plan.data, np.random.default_rng(5), rp)
    c = room_drift_field(plan.data, np.random.default_rng(6), rp)
    assert np.array_equal(a.field.dx, b.field.dx) and np.array_equal(a.field.dy, b.field.dy)
    assert not np.array_equal(a.field.dx, c.field.dx)
    out_a, out_b = apply_room_drift(plan.data, a), apply_room_drift(plan.data, b)
    assert out_a.tobytes() == out_b.tobytes()
    assert not np.array_equal(out_a, apply_room_drift(plan.data, c))
    # through the drift module's entry points, per hypothesis stream
    d1 = drift_field(plan, drift_rng(2, 0), rp)
    d2 = drift_field(plan, drift_rng(2, 0), rp)
    assert apply_drift(plan.data, d1).tobytes() == apply_drift(plan.data, d2).tobytes()


def test_field_is_rigid_inside_rooms_and_scales():
    p = _three_rooms()
    rp = RoomDriftParams(rot_deg=0.5, lin=0.01, spread=0.0, blend_px=2.0, h_px=2.0)
    rd = room_drift_field(p, np.random.default_rng(0), rp)
    assert rd.amplitude == pytest.approx(1.0)
    start = rd.order[0]
    inner = ndimage.binary_erosion(rd.rooms == start, iterations=8)
    assert inner.any()
    assert np.abs(rd.field.dx[inner]).max() < 1e-3 and np.abs(rd.field.dy[inner]).max() < 1e-3
    for r in rd.order[1:]:                        # other rooms: one rigid transform each
        inner = ndimage.binary_erosion(rd.rooms == r, iterations=8)
        A = rd.transforms[r - 1]
        yy, xx = np.nonzero(inner)
        dx = A[0, 0] * xx + A[0, 1] * yy + A[0, 2] - xx
        assert np.allclose(rd.field.dx[inner], dx, atol=1e-3)
        assert np.linalg.det(A[:, :2]) == pytest.approx(1.0)   # a rotation: no stretch
    # scale 0: no drift, the map itself; the field grows with the scale
    zero = room_drift_field(p, np.random.default_rng(0), RoomDriftParams(scale=0.0, h_px=2.0))
    assert np.abs(zero.field.magnitude).max() < 1e-4
    assert np.array_equal(apply_room_drift(p, zero), p)
    one = room_drift_field(p, np.random.default_rng(0), RoomDriftParams(h_px=2.0, spread=0.0))
    two = room_drift_field(p, np.random.default_rng(0), RoomDriftParams(h_px=2.0, spread=0.0,
                                                                       scale=2.0))
    assert two.stats()["mean"] > 1.5 * one.stats()["mean"] > 0
    # the spread makes a heavy tail across maps: some draws far above the median
    plan = generate_floorplan(0, size=(12, 9)).data
    means = [room_drift_field(plan, np.random.default_rng(s), RoomDriftParams(spread=0.7))
             .stats()["mean"] for s in range(12)]
    assert max(means) > 2.5 * np.median(means)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_walls_stay_connected(seed):
    """A generated plan's walls under the room-wise drift: at most a few more wall
    components (the parametric field scaled to the same size breaks them into >100)."""
    plan = np.pad(generate_floorplan(seed, size=(14, 10)).data, 60,
                  constant_values=UNKNOWN)                   # room to move: nothing leaves
    before = _wall_parts(plan)
    rd = room_drift_field(plan, np.random.default_rng(seed),
                          RoomDriftParams(rot_deg=2.0, lin=0.03))
    assert rd.stats()["mean"] > 2.0                          # it does move the rooms
    out = apply_room_drift(plan, rd)
    assert _wall_parts(out) <= before + 4
    assert set(np.unique(out).tolist()) <= {OCCUPIED, UNKNOWN, FREE}
    # no fold: the field's slope stays below 1 px/px, and wall pixels are kept (splatted)
    slope = max(np.abs(g).max() for g in np.gradient(rd.field.dx) + np.gradient(rd.field.dy))
    assert slope < 0.5
    assert np.count_nonzero(out == OCCUPIED) >= 0.95 * np.count_nonzero(plan == OCCUPIED)


def test_drift_params_rooms_and_parametric_sum():
    assert drift_params("rooms") == RoomDriftParams()
    assert drift_params("rooms", "additive", 0.5) == RoomDriftParams(scale=0.5)
    assert drift_params(RoomDriftParams(), "ekf").method == "ekf"
    assert drift_params(RoomDriftParams(parametric=False), "ekf").method == "additive"
    with pytest.raises(InputError, match="drift_method"):
        drift_params("rooms", "rigid")
    with pytest.raises(InputError):
        RoomDriftParams(blend_px=0.0)
    with pytest.raises(InputError, match="drift"):
        drift_params("wobble")
    # parametric=True adds the default parametric field, drawn first from the same stream
    data = _three_rooms()
    plan = OccupancyMap(data, resolution=0.1)
    rp = RoomDriftParams(h_px=2.0, parametric=False)
    alone = drift_field(plan, drift_rng(0, 0), rp)
    summed = drift_field(plan, drift_rng(0, 0), RoomDriftParams(h_px=2.0, parametric=True,
                                                                smooth_m=0.0))
    assert alone.extra is None and summed.extra is not None
    par = drift_field(plan, drift_rng(0, 0), DriftParams())
    assert np.array_equal(summed.extra.dx, par.field.dx)
    smooth = drift_field(plan, drift_rng(0, 0), RoomDriftParams(h_px=2.0, conserve=False))
    par = drift_field(plan, drift_rng(0, 0), DriftParams(smooth_m=0.2))
    assert np.array_equal(smooth.extra.dx, par.field.dx)
    kept = drift_field(plan, drift_rng(0, 0), RoomDriftParams(h_px=2.0, conserve=True))
    assert np.array_equal(kept.extra.dy, solenoidal(par.field).dy)  # its divergence-free part
    zero = drift_field(plan, drift_rng(0, 0), RoomDriftParams(h_px=2.0, scale=0.0))
    assert np.array_equal(apply_drift(data, zero), data)          # scale 0: both parts off
    out = apply_drift(data, summed)
    assert out.shape == data.shape and not np.array_equal(out, apply_drift(data, alone))


@pytest.mark.parametrize("seed", [0, 2])
def test_default_rooms_drift_keeps_walls_whole_where_the_parametric_tears_them(seed):
    """The default room-wise drift (rooms + the parametric field smoothed 0.2 m) on a
    generated plan: wall components stay within 3 of the plan's; the default parametric
    drift alone breaks the same walls into more than 50 pieces."""
    p = generate_floorplan(seed, size=(14, 10))
    plan = OccupancyMap(np.pad(p.data, 40, constant_values=UNKNOWN), p.resolution)
    before = _wall_parts(plan.data)
    rooms = drift_field(plan, drift_rng(seed, 0), RoomDriftParams())
    assert rooms.extra is not None and rooms.stats()["mean"] > 1.0
    assert _wall_parts(apply_drift(plan.data, rooms)) <= before + 3
    torn = apply_drift(plan.data, drift_field(plan, drift_rng(seed, 0), DriftParams()))
    assert _wall_parts(torn) > before + 50


def _face_divergence(dx: np.ndarray, dy: np.ndarray) -> np.ndarray:
    """Divergence per pixel of the field averaged onto the faces between pixels."""
    ux, uy = 0.5 * (dx[:, 1:] + dx[:, :-1]), 0.5 * (dy[1:] + dy[:-1])
    div = np.zeros(dx.shape)
    div[:, :-1] += ux
    div[:, 1:] -= ux
    div[:-1] += uy
    div[1:] -= uy
    return div


def test_solenoidal_removes_growth_keeps_turns():
    """solenoidal(): no divergence left inside the square; a local growth (source)
    vanishes, a local turn (what bends walls) stays."""
    rng = np.random.default_rng(0)
    dx, dy = (ndimage.gaussian_filter(rng.normal(0, 5, (60, 80)), 4) for _ in range(2))
    out = solenoidal(DisplacementField(dx, dy))
    div = _face_divergence(out.dx.astype(float), out.dy.astype(float))
    before = _face_divergence(dx, dy)
    assert np.abs(div[2:-2, 2:-2]).max() < 0.05 * np.abs(before[2:-2, 2:-2]).max()
    yy, xx = np.mgrid[:50, :60] - np.array([24.5, 29.5])[:, None, None]
    gy, gx = np.gradient(30 * np.exp(-(xx**2 + yy**2) / (2 * 5.0**2)))
    grow = solenoidal(DisplacementField(gx, gy))
    assert grow.magnitude.max() < 0.03 * np.hypot(gx, gy).max()
    turn = DisplacementField(gy, -gx)
    kept = solenoidal(turn)
    assert np.abs(kept.dx - turn.dx).max() < 0.01 and np.abs(kept.dy - turn.dy).max() < 0.01


@pytest.mark.parametrize("seed", [1, 3])
def test_default_rooms_drift_conserves_free_space_and_walls(seed):
    """Session 12: the added parametric field (thesis eqs. 3.83-3.90: a positive range
    error pushes what every pose sees away from it, summed over poses) grew the drifted
    maps' free space and squeezed walls; its divergence-free part (``conserve=True``)
    moves them without growing or shrinking them. Fails on the code
    before (no ``conserve``; the field as drawn, still the default, grows free space by
    4-7 % here)."""
    p = generate_floorplan(seed, size=(14, 10))
    plan = OccupancyMap(np.pad(p.data, 40, constant_values=UNKNOWN), p.resolution)
    d = plan.data
    free, walls = int((d == FREE).sum()), int((d == OCCUPIED).sum())
    new = drift_field(plan, drift_rng(seed, 0), RoomDriftParams(conserve=True))
    old = drift_field(plan, drift_rng(seed, 0), RoomDriftParams())
    assert not RoomDriftParams().conserve and new.extra is not None
    one = np.ones(d.shape, bool)
    par_new, par_old = warp_map(d, new.extra, one), warp_map(d, old.extra, one)
    assert abs((par_new == FREE).sum() / free - 1) < 0.01          # the field alone
    assert abs((par_new == OCCUPIED).sum() / walls - 1) < 0.02
    assert (par_old == FREE).sum() / free > 1.03                     # the old one grew it
    out = apply_drift(d, new)                                        # rooms + field
    assert abs((out == FREE).sum() / free - 1) < 0.01
    assert abs((out == OCCUPIED).sum() / walls - 1) < 0.03
    assert (apply_drift(d, old) == FREE).sum() / free > 1.03
    assert _wall_parts(out) <= _wall_parts(d) + 3


def test_jumps_turn_a_few_steps_and_every_room_after_them():
    """``jump_share``: most steps keep their parent's rotation (rot_deg 0), a jump turns
    the room and every room reached from it; no jumps drawn when the share is 0 (the
    draws, and so the maps, as before)."""
    plan = generate_floorplan(5, size=(16, 12)).data
    still = RoomDriftParams(rot_deg=0.0, lin=0.0, spread=0.0, parametric=False)
    rot = room_drift_field(plan, np.random.default_rng(1), still).transforms[:, 1, 0]
    assert np.allclose(rot, 0.0)
    jumpy = RoomDriftParams(rot_deg=0.0, lin=0.0, spread=0.0, parametric=False,
                            jump_share=0.3, jump_deg=3.0)
    d = room_drift_field(plan, np.random.default_rng(1), jumpy)
    angles = np.round(np.degrees(np.arctan2(d.transforms[:, 1, 0], d.transforms[:, 0, 0])), 6)
    n = len(angles)
    assert n >= 6 and 1 < len(np.unique(angles)) < n     # some rooms share a rotation
    assert "jumps 0.3 x 3 deg" in jumpy.describe()
    base = RoomDriftParams(parametric=False)
    a = room_drift_field(plan, np.random.default_rng(2), base).transforms
    b = room_drift_field(plan, np.random.default_rng(2), RoomDriftParams(
        parametric=False, jump_share=0.0, jump_deg=9.0)).transforms
    assert np.array_equal(a, b)
    with pytest.raises(InputError):
        RoomDriftParams(jump_share=1.5)


def test_a_drift_along_a_path_starts_unmoved_and_chains_rooms_in_the_order_entered():
    """``path``: the room the robot starts in keeps the identity; each room steps once from
    the room the robot came from when it first entered it (a revisit adds no step); the
    draws are seeded; without a path the random walk is unchanged."""
    p = _three_rooms()
    rp = RoomDriftParams(rot_deg=2.0, lin=0.05, spread=0.0, h_px=2.0, parametric=False)
    lab = segment_rooms(p, h_px=2.0)
    left, mid, right = (int(lab[20, c]) for c in (15, 50, 85))
    cols = np.r_[np.linspace(85, 50, 20), np.linspace(50, 15, 20), np.linspace(15, 85, 40)]
    path = (np.full(cols.shape, 21.0), cols)               # right -> middle -> left -> back
    d = room_drift_field(p, np.random.default_rng(4), rp, path)
    assert list(d.order) == [right, mid, left]
    T = {r: np.vstack([d.transforms[r - 1], [0, 0, 1]]) for r in (left, mid, right)}
    assert np.allclose(T[right], np.eye(3))
    assert not np.allclose(T[mid], np.eye(3)) and not np.allclose(T[left], T[mid])
    again = room_drift_field(p, np.random.default_rng(4), rp, path)
    assert np.array_equal(again.transforms, d.transforms)
    # no path: the random walk as it was before paths existed (values from d63bbe8)
    free = room_drift_field(p, np.random.default_rng(4), rp)
    assert list(free.order) == [2, 3, 1]
    assert np.allclose(free.transforms, [
        [[0.999763, 0.021761, -0.214574], [-0.021761, 0.999763, -1.908535]],
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        [[0.999735, -0.023007, -2.195666], [0.023007, 0.999735, -1.567341]]], atol=1e-6)
    # a path from the left room: that one is now unmoved
    back = room_drift_field(p, np.random.default_rng(4), rp,
                            (np.full(40, 21.0), np.linspace(15, 85, 40)))
    assert list(back.order) == [left, mid, right]
    assert np.allclose(back.transforms[left - 1], np.eye(3)[:2])


def _thick_rooms(t: int = 5) -> np.ndarray:
    """Three rooms in a row, the two walls between them ``t`` px thick, doors in both."""
    p = np.full((44, 110), UNKNOWN, np.uint8)
    p[2:42, 2:108] = FREE
    p[2, 2:108] = p[41, 2:108] = OCCUPIED
    p[2:42, 2] = p[2:42, 107] = OCCUPIED
    for c in (35, 70):
        p[2:42, c:c + t] = OCCUPIED
        p[18:26, c:c + t] = FREE
    return p


def test_shared_walls_have_their_thickness_and_point_from_room_to_room():
    p = _thick_rooms(5)
    lab = segment_rooms(p, h_px=2.0)
    a, b, c = (int(lab[20, x]) for x in (15, 55, 90))
    w = shared_walls(p, lab, shortest=5)
    n, t, ln = w[(a, b)]
    assert n.round(6).tolist() == [1.0, 0.0] and t == 5.0 and ln >= 25
    assert w[(b, a)][0].round(6).tolist() == [-1.0, 0.0] and w[(b, a)][1] == 5.0
    assert (a, c) not in w and (c, a) not in w                  # no wall between them
    assert collapse_shift(w, b, [a]).round(6).tolist() == [-5.0, 0.0]
    assert collapse_shift(w, b, []).tolist() == [0.0, 0.0]
    assert len(shared_walls(p, lab, thickest=4, shortest=5)) == 0     # too thick to count


def test_a_collapsing_step_lays_the_new_rooms_face_on_the_mapped_one():
    """``collapse=1`` with no random step: entering each room along the route moves it
    towards the room the robot came from by the shared wall's thickness, so the wall seen
    from both rooms is drawn as one face; ``collapse=0`` moves nothing."""
    p = _thick_rooms(3)        # the thickest wall counted is 10 px of a 256 px square
    path = (np.full(100, 21.0), np.linspace(10, 100, 100))
    still = dict(rot_deg=0.0, lin=0.0, h_px=2.0, parametric=False)
    d = room_drift_field(p, np.random.default_rng(0), RoomDriftParams(**still, collapse=1.0),
                         path)
    lab = d.rooms
    shifts = [float(d.transforms[int(lab[20, x]) - 1, 0, 2]) for x in (15, 55, 90)]
    assert np.allclose(shifts, [0.0, -3.0, -6.0])
    assert np.abs(d.transforms[:, 1, 2]).max() < 1e-9
    d0 = room_drift_field(p, np.random.default_rng(0), RoomDriftParams(**still), path)
    assert np.abs(d0.transforms[:, :, 2]).max() < 1e-9
    with pytest.raises(InputError, match="collapse"):
        RoomDriftParams(collapse=1.5)
