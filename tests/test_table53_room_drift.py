"""The room-drift diagnostic (experiments.table53.room_drift) on a hand-made map: three
rooms in a row, the middle one mapped 2 px too far right."""

from __future__ import annotations

import numpy as np

from map2map.experiments.table53.room_drift import fit_rooms, room_field, rooms, solve_rooms


def row_of_rooms(shift: int) -> np.ndarray:
    """Rooms A | B | C between 4 px walls; the middle room's faces ``shift`` px right
    (the wall on its left that much thicker, the one on its right thinner)."""
    m = np.full((70, 150), 127, np.uint8)
    m[10:60, 12:138] = 255
    m[8:10, 10:140] = 0
    m[60:62, 10:140] = 0
    m[8:62, 10:12] = 0
    m[8:62, 138:140] = 0
    m[8:62, 50:54 + shift] = 0
    m[8:62, 94 + shift:98] = 0
    return m


def test_the_middle_rooms_drift_is_fitted_to_the_plan_and_solved_from_the_map():
    slam, plan = row_of_rooms(2), row_of_rooms(0)
    lab, near = rooms(slam)
    a, b, c = (int(lab[35, x]) for x in (30, 75, 118))
    assert len({a, b, c, 0}) == 4
    T = fit_rooms(slam, plan, near)
    assert abs((T[b][0] - T[a][0]) + 2) <= 0.5 and abs(T[c][0] - T[a][0]) <= 0.5
    S = solve_rooms(slam, lab)
    assert (S[b, 0] - S[a, 0]) < -1 and abs(S[c, 0] - S[a, 0]) < 1
    u = room_field(near, T)
    assert u.shape == (2,) + slam.shape and np.isclose(u[0][35, 75], T[b][0])
