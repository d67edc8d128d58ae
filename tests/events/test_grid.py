"""The cell grid plan: cells at least one diameter wide, bounded in number, and at least three
per periodic axis (each neighbour is then met in exactly one image)."""

import numpy as np
import pytest

from hsgran.events.grid import MIN_PERIODIC_CELLS, plan_grid


@pytest.mark.parametrize("n_particles", [1, 2, 10, 1000])
def test_periodic_axes_keep_three_cells_for_any_number_of_spheres(n_particles):
    _, size, n = plan_grid([0, 0, 0], [0.1, 0.1, 0.1], [True, True, True], 0.02,
                           n_particles)
    assert np.all(n >= MIN_PERIODIC_CELLS)
    assert np.all(size >= 0.02)
    np.testing.assert_allclose(size * n, 0.1)


def test_open_axes_are_coarsened_first():
    _, size, n = plan_grid([0, 0, 0], [1.0, 1.0, 0.1], [False, False, True], 0.02, 100)
    assert n[2] == 5  # the periodic axis keeps its full resolution
    assert np.prod(n) <= 4 * 100  # MAX_CELLS_PER_PARTICLE
    assert np.all(size >= 0.02)
