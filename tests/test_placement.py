"""Sphere placement: fills never overlap each other, placed spheres, planes or the box (periodic
images included), depend on the seed alone, find through the cell grid exactly what an all-pairs
search finds, and a fill that cannot be placed is refused in one line naming the fill."""

import numpy as np
import pytest

import hsgran.placement as placement
from hsgran.errors import InputError
from hsgran.placement import Fill, Space, fill_spheres, overlapping_pairs

#: A tilted plane through the middle of the region, normal pointing up and towards +y.
SLOPE = (np.array([0.03, 0.03, 0.02]), np.array([0.0, 0.6, 0.8]))


def box_space(lower, upper, periodic=(False, False, False), planes=()):
    """Space of a box (faces on its non-periodic axes) and extra (point, normal) planes."""
    lower = np.asarray(lower, dtype=float)
    upper = np.asarray(upper, dtype=float)
    points, normals = [p for p, _ in planes], [n for _, n in planes]
    for i in range(3):
        if not periodic[i]:
            e = np.zeros(3)
            e[i] = 1.0
            points += [lower, upper]
            normals += [e, -e]
    return Space(plane_point=np.array(points, dtype=float).reshape(-1, 3),
                 plane_normal=np.array(normals, dtype=float).reshape(-1, 3),
                 origin=lower, period=np.where(periodic, upper - lower, 0.0))


def a_fill(count=200, radius=(0.002, 0.004), lower=(0.0, 0.0, 0.0), upper=(0.06, 0.06, 0.06),
           speed=0.5):
    return Fill("fill[0]", count, "glass", radius, np.array(lower, dtype=float),
                np.array(upper, dtype=float), speed, np.zeros(3))


def all_pair_gaps(position, radius, period=None):
    """Centre distance minus sum of radii of every pair i < j [m] (minimum image)."""
    delta = position[:, None, :] - position[None, :, :]
    if period is not None:
        on = period > 0
        delta[..., on] -= period[on] * np.round(delta[..., on] / period[on])
    gap = np.sqrt((delta**2).sum(-1)) - (radius[:, None] + radius[None, :])
    return gap[np.triu_indices(len(radius), 1)]


def test_fill_clears_itself_the_placed_spheres_the_planes_and_its_region():
    space = box_space([0, 0, 0], [0.06, 0.06, 0.06], planes=[SLOPE])
    placed_pos = np.array([[0.03, 0.04, 0.045]])
    placed_rad = np.array([0.01])
    fill = a_fill()
    pos, vel, rad = fill_spheres(np.random.default_rng(1), fill, placed_pos, placed_rad, space)
    assert pos.shape == (200, 3)
    assert not np.isnan(pos).any()
    everything = np.concatenate([placed_pos, pos]), np.concatenate([placed_rad, rad])
    assert all_pair_gaps(*everything).min() >= 0.0
    for point, normal in zip(space.plane_point, space.plane_normal, strict=True):
        assert np.all((pos - point) @ normal >= rad)
    assert np.all(pos - rad[:, None] >= fill.lower)
    assert np.all(pos + rad[:, None] <= fill.upper)
    assert np.all((rad >= 0.002) & (rad <= 0.004))
    np.testing.assert_allclose(np.linalg.norm(vel, axis=1), 0.5, rtol=1e-12)


def test_fill_in_a_periodic_box_clears_the_images():
    period = np.array([0.06, 0.06, 0.0])
    space = box_space([0, 0, 0], [0.06, 0.06, 0.06], periodic=(True, True, False))
    # a sphere straddling the x and y boundaries: the fill must avoid its images
    placed_pos = np.array([[0.001, 0.059, 0.03]])
    placed_rad = np.array([0.008])
    pos, _, rad = fill_spheres(np.random.default_rng(2), a_fill(count=150), placed_pos,
                               placed_rad, space)
    gaps = all_pair_gaps(np.concatenate([placed_pos, pos]), np.concatenate([placed_rad, rad]),
                         period)
    assert gaps.min() >= 0.0
    assert np.all(pos[:, 2] - rad >= 0.0)
    assert np.all(pos[:, 2] + rad <= 0.06)


def test_fill_depends_on_the_seed_alone():
    space = box_space([0, 0, 0], [0.06, 0.06, 0.06], planes=[SLOPE])
    runs = []
    for seed in (7, 7, 8):
        rng = np.random.default_rng(seed)
        placed = fill_spheres(rng, a_fill(), np.empty((0, 3)), np.empty(0), space)
        runs.append((*placed, rng.random()))  # and the generator is left in the same state
    for a, b in zip(runs[0], runs[1], strict=True):
        np.testing.assert_array_equal(a, b)
    for a, c in zip(runs[0], runs[2], strict=True):
        assert not np.array_equal(a, c)


def reference_rsa(u, radii, lower, upper, placed_pos, placed_rad, space):
    """Random sequential addition consuming candidate rows ``u`` in order, every candidate
    compared with every sphere (no grid), with the kernel's arithmetic (sums over x, y, z in
    that order, squared distances)."""
    order = np.argsort(-radii, kind="stable")
    pos = list(placed_pos)
    rad = list(placed_rad)
    out = np.full((len(radii), 3), np.nan)
    period = space.period
    row = 0
    for s in order:
        r = radii[s]
        while True:
            x = lower + r + u[row] * (upper - lower - 2.0 * r)
            row += 1
            t = (x - space.plane_point) * space.plane_normal
            if np.any(t[:, 0] + t[:, 1] + t[:, 2] < r):
                continue
            if pos:
                e = x - np.array(pos)
                on = period > 0
                e[:, on] -= period[on] * np.round(e[:, on] / period[on])
                reach = r + np.array(rad)
                if np.any(e[:, 0] * e[:, 0] + e[:, 1] * e[:, 1] + e[:, 2] * e[:, 2]
                          < reach * reach):
                    continue
            break
        out[s] = x
        pos.append(x)
        rad.append(r)
    return out, row


@pytest.mark.parametrize("periodic", [(False, False, False), (True, True, False),
                                      (True, True, True)])
def test_grid_search_finds_what_an_all_pairs_search_finds(periodic):
    """The cell grid only chooses which spheres are compared: the spheres placed are those an
    all-pairs search places from the same candidates, to the last bit."""
    lower, upper = np.zeros(3), np.full(3, 0.05)
    space = box_space(lower, upper, periodic=periodic)
    radii = np.random.default_rng(0).uniform(0.001, 0.003, 250)
    placed_pos = np.array([[0.0005, 0.025, 0.025], [0.025, 0.0495, 0.0495]])
    placed_rad = np.array([0.004, 0.002])
    if not periodic[0]:
        placed_pos[0, 0] = 0.004  # inside the box faces
    if not periodic[2]:
        placed_pos[1, 2] = 0.045
    if not periodic[1]:
        placed_pos[1, 1] = 0.045
    got, attempts = placement.random_sequential_addition(
        np.random.default_rng(5), radii, lower, upper, placed_pos, placed_rad, space, 100_000)
    u = np.random.default_rng(5).random((attempts, 3))
    want, used = reference_rsa(u, radii, lower, upper, placed_pos, placed_rad, space)
    assert used == attempts
    np.testing.assert_array_equal(got, want)


def test_fill_kernel_compiled_and_python_agree(monkeypatch):
    """The compiled placement and its plain-Python source consume the same numbers alike."""
    kernel = placement._rsa_kernel
    if not hasattr(kernel, "py_func"):
        pytest.skip("numba JIT disabled: only the Python kernel exists")
    args = dict(radii=np.random.default_rng(0).uniform(0.002, 0.004, 200),
                lower=np.zeros(3), upper=np.full(3, 0.06),
                placed_position=np.array([[0.03, 0.03, 0.03]]),
                placed_radius=np.array([0.01]),
                space=box_space(np.zeros(3), np.full(3, 0.06), periodic=(True, True, False),
                                planes=[(np.array([0.0, 0.0, 0.01]), np.array([0.0, 0.0, 1.0]))]),
                budget=100_000)
    fast, n_fast = placement.random_sequential_addition(np.random.default_rng(3), **args)
    monkeypatch.setattr(placement, "_rsa_kernel", kernel.py_func)
    slow, n_slow = placement.random_sequential_addition(np.random.default_rng(3), **args)
    assert n_fast == n_slow
    np.testing.assert_array_equal(fast, slow)
    assert not np.isnan(fast).any()


def test_fill_that_cannot_fit_says_how_many_it_placed():
    # 0.46 of the region's volume: above what random placement reaches, below the refusal limit
    space = box_space([0, 0, 0], [0.06, 0.06, 0.06])
    with pytest.raises(InputError) as info:
        fill_spheres(np.random.default_rng(5), a_fill(radius=(0.0049, 0.0049)),
                     np.empty((0, 3)), np.empty(0), space)
    message = str(info.value)
    assert info.value.key == "fill[0].count"
    assert "\n" not in message
    assert message.startswith("fill[0].count: placed only ")
    assert f"of 200 spheres after {placement.FILL_MIN_ATTEMPTS} random attempts" in message


def test_fill_beyond_the_packing_limit_is_refused_without_trying():
    space = box_space([0, 0, 0], [0.06, 0.06, 0.06])
    rng = np.random.default_rng(5)
    with pytest.raises(InputError, match=r"^fill\[0\]\.count: 2000 spheres would fill 1\.05 "):
        fill_spheres(rng, a_fill(count=2000, radius=(0.003, 0.003)), np.empty((0, 3)),
                     np.empty(0), space)
    assert rng.random() == np.random.default_rng(5).random()  # monodisperse: nothing drawn


def test_overlapping_pairs_sees_periodic_images_and_accepts_touching_spheres():
    space = box_space([0, 0, 0], [0.1, 0.1, 0.1], periodic=(True, False, False))
    position = np.array([[0.001, 0.05, 0.05],    # overlaps the next one through x = 0
                         [0.098, 0.05, 0.05],
                         [0.05, 0.05, 0.05],     # touches the next one exactly
                         [0.05, 0.05, 0.07]])
    radius = np.array([0.002, 0.002, 0.01, 0.01])
    pairs, dist = overlapping_pairs(position, radius, space)
    np.testing.assert_array_equal(pairs, [[0, 1]])
    np.testing.assert_allclose(dist, [0.003], rtol=1e-9)
    no_period = box_space([0, 0, 0], [0.1, 0.1, 0.1])
    assert overlapping_pairs(position, radius, no_period)[0].shape == (0, 2)
