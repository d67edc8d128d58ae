"""Inflow: spheres inserted during a run (layer 4; docs/open-systems.md).

An ``[[inflow]]`` entry inserts spheres into a box-shaped region in batches: batch k at
t_k = start + k·interval brings the spheres inserted so far up to round(rate·interval·(k+1)),
so the mean rate is exact whatever the interval. Each batch places its spheres by random
sequential addition (hsgran.placement) clear of the walls and of every sphere in the system at
t_k, with velocity ``velocity`` plus ``speed`` in a random direction; a sphere that finds no room
waits for the next batch. The random draws of batch k come from a generator seeded by the
scene's seed, the inflow's index and k, so a run is reproducible and a resumed run continues
the same draws.

The spheres come from the particle table, which never grows:

- an inflow of ``count`` spheres owns ``count`` rows reserved at the end of the table (radius
  and material fixed when the scene is read), absent until inserted: a batch takes the lowest
  rows not yet inserted, and places the largest of them first;
- an inflow with ``recirculate = true`` owns no rows: it inserts again, lowest row first, the
  spheres that have left the system through an outlet, each with its own radius and material
  (steady discharge with a constant number of spheres).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hsgran.placement import Space, random_sequential_addition

#: Candidate centres a batch draws per sphere it wants: enough for a region up to the packing
#: fraction random sequential addition reaches easily (hsgran.placement); a batch that does not
#: find room for all places the rest at the next one.
ATTEMPTS_PER_SPHERE = 300


@dataclass(frozen=True, eq=False)
class Inflow:
    """A checked ``[[inflow]]`` entry.

    Attributes:
        key: Key path for messages (``inflow[0]``).
        index: Its position among the scene's inflows (part of its random seed).
        rows: The particle table rows it owns, [start, stop) (empty when recirculating).
        lower, upper: Corners of the region [m], shape (3,); every sphere lies wholly inside.
        rate: Spheres per second [1/s].
        interval: Time between batches [s].
        start: Time of the first batch [s].
        velocity: Mean velocity of an inserted sphere [m/s], shape (3,).
        speed: Speed added in a random direction [m/s].
        recirculate: Insert the spheres that left through outlets instead of its own rows.
    """

    key: str
    index: int
    rows: tuple[int, int]
    lower: np.ndarray
    upper: np.ndarray
    rate: float
    interval: float
    start: float
    velocity: np.ndarray
    speed: float
    recirculate: bool

    @property
    def count(self) -> int:
        """Spheres of its own (0 when recirculating)."""
        return self.rows[1] - self.rows[0]

    def batch_time(self, k: int) -> float:
        """Time of batch k [s]."""
        return self.start + k * self.interval

    def target(self, k: int) -> int:
        """Spheres inserted in all, once batch k is done (at most its own when not
        recirculating)."""
        total = round(self.rate * self.interval * (k + 1))
        return total if self.recirculate else min(total, self.count)

    def exhausted(self, inserted: int) -> bool:
        """Whether it has nothing left to insert (never, when recirculating)."""
        return not self.recirculate and inserted >= self.count


def place_batch(inflow: Inflow, k: int, seed: int, radius: np.ndarray,
                placed_position: np.ndarray, placed_radius: np.ndarray, space: Space):
    """Positions and velocities of the spheres of batch k.

    Args:
        inflow: The inflow.
        k: The batch.
        seed: The scene's seed.
        radius: Radii of the spheres to place [m], shape (m,).
        placed_position, placed_radius: The spheres in the system at the batch's time [m],
            (p, 3) and (p,).
        space: Walls and periodic box (hsgran.placement).

    Returns:
        (position [m] (m, 3), NaN rows for spheres that found no room; velocity [m/s] (m, 3)).
    """
    rng = np.random.default_rng([seed, inflow.index, k])
    m = radius.shape[0]
    budget = ATTEMPTS_PER_SPHERE * max(m, 1)
    position, _ = random_sequential_addition(rng, radius, inflow.lower, inflow.upper,
                                             placed_position, placed_radius, space, budget)
    direction = rng.standard_normal((m, 3))
    norm = np.linalg.norm(direction, axis=1, keepdims=True)
    norm[norm == 0.0] = 1.0  # probability zero; keeps the arithmetic finite
    velocity = inflow.velocity + inflow.speed * direction / norm
    return position, velocity

