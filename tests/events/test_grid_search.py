"""Grid helpers for compiled searches: one point's cell coordinate agrees with
cell_coordinates, the cells next to a coordinate cover each list slot once, and insert_all
builds the lists one insert at a time would."""

import numpy as np
import pytest

from hsgran.events.grid import (
    axis_coordinate,
    axis_neighbours,
    cell_coordinates,
    insert,
    insert_all,
    plan_grid,
    slot_of,
)


@pytest.mark.parametrize("periodic", [(False, False, False), (True, False, True)])
def test_axis_coordinate_agrees_with_cell_coordinates(periodic):
    origin, size, n = plan_grid([0, 0, 0], [0.1, 0.07, 0.05], periodic, 0.011, 100)
    # inside, on cell faces, on the box faces, and (open axes) outside
    pos = np.random.default_rng(0).uniform(-0.02, 0.12, (500, 3))
    pos[:5] = [[0.0, 0.0, 0.0], [0.1, 0.07, 0.05], size, 2 * size, [0.0999999, 0.069999, 0.0]]
    for k in range(3):
        if periodic[k]:
            pos[5:, k] = np.clip(pos[5:, k], origin[k], origin[k] + size[k] * n[k])
    want = cell_coordinates(pos, origin, size, n, periodic)
    got = [[axis_coordinate(p[k], origin[k], size[k], n[k], periodic[k]) for k in range(3)]
           for p in pos]
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("n", [1, 2, 3, 7])
@pytest.mark.parametrize("c", [-4, -1, 0, 1, 5, 13])
def test_axis_neighbours_cover_each_slot_within_one_cell_once(n, c):
    out = np.full(3, 99, dtype=np.int64)
    m = axis_neighbours(c, n, out)
    slots = [int(v) % n for v in out[:m]]
    assert out[0] == c  # own cell first
    assert len(set(slots)) == m  # each slot once
    assert set(slots) == {(c + d) % n for d in (-1, 0, 1)}  # every slot within one cell


def test_insert_all_builds_the_lists_of_successive_inserts():
    ncell = np.array([3, 4, 5])
    cell = np.random.default_rng(1).integers(-6, 9, (200, 3))
    lists = []
    for build in ("one by one", "all"):
        head = np.full(int(np.prod(ncell)), -1, dtype=np.int32)
        nxt = np.full(200, -1, dtype=np.int32)
        prv = np.full(200, -1, dtype=np.int32)
        if build == "all":
            insert_all(cell, head, nxt, prv, ncell)
        else:
            for i in range(200):
                insert(i, slot_of(cell[i, 0], cell[i, 1], cell[i, 2], ncell), head, nxt, prv)
        lists.append((head, nxt, prv))
    for a, b in zip(*lists, strict=True):
        np.testing.assert_array_equal(a, b)
