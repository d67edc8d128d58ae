"""A pure-Python reference event loop: the test oracle of the compiled engine (layer 5).

What it is for: tests run a scene through :class:`hsgran.engine.Simulation` and through
:func:`run_reference` and compare the two collision logs event by event. It is deliberately the
plainest event-driven algorithm there is, so that it is easy to believe:

* every pair is tested against every other (O(N²) work per event, no cell grid);
* every predicted event goes into one :mod:`heapq` list, stamped with the event counters of its
  participants; an entry whose stamps no longer match is stale and dropped when popped (lazy
  invalidation); ties in time go to the earlier prediction (a sequence number);
* spheres are advanced only when they take part in an event (delayed states) and everybody is
  synchronised once, at the end.

It is an *independent* implementation: free flight, the minimum image and the sphere–sphere and
sphere–plane contact times are derived again here in plain Python (``math``) instead of being
taken from :mod:`hsgran.motion`, and the queue is :mod:`heapq` instead of the engine's indexed
heap, so a mistake in either shows up as a disagreement. Only the collision kernel
(:func:`hsgran.contact.model.make_resolver`) is shared, on purpose: it is tested on its own, and
sharing it makes the two loops comparable to the last bit.

Periodic axes use the nearest image, and a pair's prediction is trusted only as long as no
other image can come within reach (an *image horizon*); beyond it the pair is looked at again.

It is slow (several hundred collisions per second for tens of spheres) and has no frames, observers,
enduring contacts or output files: it is not for production runs.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np

from hsgran.contact.model import (
    REC_E_N,
    REC_ENERGY_LOST,
    REC_J_N,
    REC_J_T,
    REC_REGIME,
    REC_SIZE,
    REC_STAGE,
    make_resolver,
)
from hsgran.errors import HsgranError
from hsgran.events.kinds import EV_PAIR, EV_WALL
from hsgran.materials import SOLID_SPHERE_INERTIA

#: (queue only, never logged) look at a pair again: its nearest periodic image may change
KIND_RECHECK = 3

#: Fraction of the image horizon (see :meth:`_Reference.predict_pair`) after which a pair on
#: periodic axes is looked at again. The horizon is exact in exact arithmetic, so any fraction
#: below 1 keeps round-off in its computation from letting another image's contact slip
#: through; one half costs at most twice as many (cheap) rechecks.
IMAGE_HORIZON_FRACTION = 0.5

#: An event of a sphere less than NO_PROGRESS_ULPS units in the last place of max(t, 1 s) after
#: its previous event did not advance its clock: that is round-off of the clock itself.
NO_PROGRESS_ULPS = 4
#: Consecutive no-progress events of one sphere after which the reference stops with an error
#: (inelastic collapse or a rounding loop; a Newton's cradle needs only a handful).
MAX_NO_PROGRESS_EVENTS = 1000


class ReferenceLoopError(HsgranError):
    """The reference loop cannot continue (a sphere stopped advancing in time)."""


@dataclass
class ReferenceResult:
    """What a reference run did: the collision log and the final state.

    The log arrays have one entry per executed collision, in execution order, with the meaning
    (and dtypes) of :class:`hsgran.engine.EventBlock`.

    Attributes:
        time: Collision times [s], (C,).
        kind: ``EV_PAIR`` or ``EV_WALL`` (:mod:`hsgran.events.kinds`), (C,) int8.
        i: The sphere whose prediction found the event, (C,) int64.
        j: Partner sphere, or −1 − w for plane w, (C,) int64.
        normal_impulse: J_n [N s], (C,).
        tangential_impulse: J_t [N s], (C,).
        e_n: Normal restitution [-], (C,).
        stage: Normal-model stage code, (C,) int8.
        regime: Tangential regime code, (C,) int8.
        t_end: Time the final state refers to [s]: ``until`` if the run reached it, else the
            time of the last collision (the collision budget was spent).
        position: Sphere centres at ``t_end`` [m], (N, 3); on periodic axes wrapped into
            [lower, upper) of the box.
        velocity: Velocities at ``t_end`` [m/s], (N, 3).
        angular_velocity: Angular velocities [rad/s], (N, 3), or ``None`` without rotation.
        dissipated: Kinetic energy dissipated by the collisions [J].
        stale: Heap entries dropped because a participant had an event since they were
            predicted.
        missed: Predicted contacts at which the kernel found the bodies not approaching (a
            grazing contact that round-off turned around): not collisions, not logged.
    """

    time: np.ndarray
    kind: np.ndarray
    i: np.ndarray
    j: np.ndarray
    normal_impulse: np.ndarray
    tangential_impulse: np.ndarray
    e_n: np.ndarray
    stage: np.ndarray
    regime: np.ndarray
    t_end: float
    position: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray | None
    dissipated: float
    stale: int
    missed: int

    @property
    def collisions(self) -> int:
        """Number of executed collisions."""
        return int(self.time.shape[0])


# ---- kinematics, derived afresh (see the module notes) -----------------------------------

def _touch_time_pair(r, w, sigma):
    """Delay until two spheres in free flight first touch.

    The separation is r + w τ (gravity acts on both alike and cancels), so contact solves
    |r + w τ|² = σ², i.e. (w·w) τ² + 2 (r·w) τ + (r·r − σ²) = 0. Only an approaching pair
    (r·w < 0) can meet, at the smaller root τ = (−r·w − √D)/(w·w) with D = (r·w)² − (w·w)(r·r −
    σ²); written as (r·r − σ²)/(√D − r·w), which has no cancellation because −r·w > 0.

    Args:
        r: Separation x_i − x_j at a common instant [m], 3-tuple (minimum image).
        w: Relative velocity v_i − v_j [m/s], 3-tuple.
        sigma: Contact distance R_i + R_j [m].

    Returns:
        τ ≥ 0 [s]; 0 if the pair already overlaps (round-off) while approaching; ``inf`` if it
        never touches.
    """
    rr = r[0] * r[0] + r[1] * r[1] + r[2] * r[2]
    rw = r[0] * w[0] + r[1] * w[1] + r[2] * w[2]
    if rw >= 0.0:
        return math.inf
    room = sigma * sigma - rr  # < 0 while apart
    if room >= 0.0:
        return 0.0
    ww = w[0] * w[0] + w[1] * w[1] + w[2] * w[2]
    disc = rw * rw + ww * room
    if disc < 0.0:
        return math.inf  # the closest approach stays outside σ
    return -room / (math.sqrt(disc) - rw)


def _touch_time_plane(gap, vn, gn):
    """Delay until a sphere in free flight reaches a plane.

    The gap evolves as h(τ) = gap + vn τ + ½ gn τ²; contact is the first τ ≥ 0 at which h
    reaches 0 while decreasing (h′ = vn + gn τ < 0). With D = vn² − 2 gn gap the roots are
    τ = (−vn ∓ √D)/gn and h′ = ∓√D there, so the wanted root is τ = (−vn − √D)/gn, evaluated as
    2 gap/(√D − vn) when vn ≤ 0 (no cancellation) and as (vn + √D)/(−gn) when vn > 0 (then only
    a pull towards the plane, gn < 0, brings the sphere back).

    Args:
        gap: Distance of the centre from the plane minus the radius [m].
        vn: Velocity along the plane normal [m/s].
        gn: Gravity along the plane normal [m/s²].

    Returns:
        τ ≥ 0 [s], or ``inf`` if the sphere never reaches the plane.
    """
    gap = max(gap, 0.0)  # a round-off overlap counts as touching
    if gn == 0.0:
        return gap / -vn if vn < 0.0 else math.inf
    disc = vn * vn - 2.0 * gn * gap
    if disc < 0.0:
        return math.inf
    root = math.sqrt(disc)
    if vn <= 0.0:
        den = root - vn
        if den > 0.0:
            return 2.0 * gap / den
        return 0.0 if gn < 0.0 else math.inf  # touching at rest: gravity decides
    if gn < 0.0:
        return (vn + root) / -gn
    return math.inf


def _nearest_image(d, period):
    """Separation along a periodic axis moved to its nearest image (|d| ≤ period/2) [m]."""
    half = 0.5 * period
    while d > half:
        d -= period
    while d < -half:
        d += period
    return d


# ---- the loop ----------------------------------------------------------------------------

class _Reference:
    """State and event queue of one reference run (see :func:`run_reference`)."""

    def __init__(self, scene):
        eff = scene.effects
        self.n = n = scene.n
        self.rotation = bool(eff.rotation)
        self.parabolic = bool(eff.gravity)
        self.g = tuple(float(x) for x in scene.gravity)
        # the stored state of sphere i is its flight origin x0 at t_loc and its velocity there
        self.x0 = [[float(c) for c in p] for p in scene.position]
        self.v0 = [[float(c) for c in v] for v in scene.velocity]
        self.t_loc = [0.0] * n
        # the kernel updates velocities and spins in place in these arrays
        self.vel = np.array(scene.velocity, dtype=np.float64)
        self.omg = (np.array(scene.angular_velocity, dtype=np.float64) if self.rotation
                    else np.zeros((n, 3)))
        self.radius = [float(r) for r in scene.radius]
        mass = [float(m) for m in scene.mass()]
        self.inv_m = [1.0 / m for m in mass]
        self.inv_i = [1.0 / (SOLID_SPHERE_INERTIA * m * (r * r))
                      for m, r in zip(mass, self.radius, strict=True)]
        self.mat = [int(k) for k in scene.material]
        self.table = np.ascontiguousarray(scene.pair_table())
        self.planes = [(tuple(float(c) for c in p.point), tuple(float(c) for c in p.normal),
                        int(p.material)) for p in scene.planes]
        self.wall_vel = np.zeros(3)  # planes do not move
        self.wall_omg = np.zeros(3)
        self.periodic = [bool(p) for p in scene.periodic]
        if any(self.periodic):
            self.lower = [float(c) for c in scene.box_lower]
            self.upper = [float(c) for c in scene.box_upper]
            self.period = [u - lo for u, lo in zip(self.upper, self.lower, strict=True)]
        self.resolver = make_resolver(eff)
        self.rec = np.zeros(REC_SIZE)
        self.count = [0] * n
        self.no_progress = [0] * n
        self.queue: list = []
        self.seq = 0
        self.stale = 0
        self.missed = 0
        self.dissipated = 0.0

    # -- kinematics --

    def _wrap_origin(self, i, x):
        """Keep sphere i within one period of the box: when its position x at some time has
        left the box along a periodic axis, move its flight origin by whole periods (positions
        stay small, so they keep their precision, and one image shift is always enough)."""
        moved = False
        for k in range(3):
            if not self.periodic[k]:
                continue
            while x[k] >= self.upper[k]:
                self.x0[i][k] -= self.period[k]
                x[k] -= self.period[k]
                moved = True
            while x[k] < self.lower[k]:
                self.x0[i][k] += self.period[k]
                x[k] += self.period[k]
                moved = True
        return moved

    def state(self, i, t):
        """Position [m] and velocity [m/s] of sphere i at time t ≥ its stored time (lists)."""
        x, v = self._flight(i, t)
        if any(self.periodic) and self._wrap_origin(i, list(x)):
            x, v = self._flight(i, t)  # evaluated afresh from the shifted origin
        return x, v

    def _flight(self, i, t):
        """Sphere i's free flight from its stored origin: a parabola with gravity, else a line."""
        dt = t - self.t_loc[i]
        x0 = self.x0[i]
        v0 = self.v0[i]
        if self.parabolic:
            g = self.g
            return ([x0[k] + dt * (v0[k] + 0.5 * g[k] * dt) for k in range(3)],
                    [v0[k] + g[k] * dt for k in range(3)])
        return [x0[k] + v0[k] * dt for k in range(3)], list(v0)

    def separation(self, xi, xj):
        """x_i − x_j with the nearest image on periodic axes [m]."""
        d = [xi[k] - xj[k] for k in range(3)]
        for k in range(3):
            if self.periodic[k]:
                d[k] = _nearest_image(d[k], self.period[k])
        return d

    # -- prediction --

    def _push(self, t, kind, a, b):
        cb = self.count[b] if kind != EV_WALL else 0
        heapq.heappush(self.queue, (t, self.seq, kind, a, b, self.count[a], cb))
        self.seq += 1

    def predict(self, i, t, skip=()):
        """Queue every future collision of sphere i seen from time t (partners in ``skip``
        excluded: their own prediction covers the pair)."""
        xi, vi = self.state(i, t)
        g = self.g
        for w, (p, nrm, _) in enumerate(self.planes):
            gap = ((xi[0] - p[0]) * nrm[0] + (xi[1] - p[1]) * nrm[1]
                   + (xi[2] - p[2]) * nrm[2]) - self.radius[i]
            vn = vi[0] * nrm[0] + vi[1] * nrm[1] + vi[2] * nrm[2]
            gn = g[0] * nrm[0] + g[1] * nrm[1] + g[2] * nrm[2]
            tau = _touch_time_plane(gap, vn, gn)
            if tau < math.inf:
                self._push(t + tau, EV_WALL, i, w)
        for j in range(self.n):
            if j == i or j in skip:
                continue
            self.predict_pair(i, xi, vi, j, t)

    def predict_pair(self, i, xi, vi, j, t):
        """Queue the next contact of spheres i and j seen from time t (i's state x_i, v_i given).

        On periodic axes the contact is sought with the nearest image at time t. Another image
        lies at least L − |d_k| away along periodic axis k (d = the nearest separation), so it
        cannot touch before the relative motion has covered L − |d_k| − σ along k: until then the
        nearest image's contact is the earliest. A contact later than that horizon (or none)
        is replaced by a recheck of the pair at the horizon.
        """
        xj, vj = self.state(j, t)
        d = self.separation(xi, xj)
        w = (vi[0] - vj[0], vi[1] - vj[1], vi[2] - vj[2])
        sigma = self.radius[i] + self.radius[j]
        tau = _touch_time_pair(d, w, sigma)
        horizon = math.inf
        for k in range(3):
            if self.periodic[k] and w[k] != 0.0:
                horizon = min(horizon, (self.period[k] - abs(d[k]) - sigma) / abs(w[k]))
        if tau <= horizon:
            if tau < math.inf:
                self._push(t + tau, EV_PAIR, i, j)
        else:
            self._push(t + IMAGE_HORIZON_FRACTION * horizon, KIND_RECHECK, i, j)

    # -- execution --

    def advance(self, i, t):
        """Move sphere i's stored state along its flight to time t."""
        x, v = self.state(i, t)
        if self.no_progress_at(i, t):
            self.no_progress[i] += 1
            if self.no_progress[i] > MAX_NO_PROGRESS_EVENTS:
                raise ReferenceLoopError(
                    f"sphere {i} had more than {MAX_NO_PROGRESS_EVENTS} events without time "
                    f"advancing at t = {t:.9g} s (inelastic collapse or a rounding loop)")
        else:
            self.no_progress[i] = 0
        self.x0[i] = x
        self.v0[i] = v
        self.t_loc[i] = t
        self.vel[i] = v

    def no_progress_at(self, i, t):
        """Whether an event of sphere i at time t leaves its clock where it was."""
        return t - self.t_loc[i] <= NO_PROGRESS_ULPS * math.ulp(max(t, 1.0))

    def collide(self, kind, a, b, t):
        """Advance the participants to t and apply the collision kernel.

        Returns:
            The log row, or None if the kernel found the bodies not approaching: then nothing
            changed (velocities, spins and event counters stay as they were).
        """
        rotation = self.rotation
        rec = self.rec
        ra = self.radius[a]
        self.advance(a, t)
        wa = self.omg[a] if rotation else self.wall_omg
        if kind == EV_PAIR:
            self.advance(b, t)
            rb = self.radius[b]
            d = self.separation(self.x0[a], self.x0[b])
            dist = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
            wb = self.omg[b] if rotation else self.wall_omg
            applied = self.resolver(
                self.vel[a], wa, self.vel[b], wb, d[0] / dist, d[1] / dist, d[2] / dist,
                self.inv_m[a], self.inv_m[b], self.inv_i[a], self.inv_i[b], ra, rb,
                1.0 / ra + 1.0 / rb, self.table[self.mat[a], self.mat[b]], rec)
            other = b
        else:
            _, nrm, wmat = self.planes[b]
            applied = self.resolver(
                self.vel[a], wa, self.wall_vel, self.wall_omg, nrm[0], nrm[1], nrm[2],
                self.inv_m[a], 0.0, self.inv_i[a], 0.0, ra, 0.0, 1.0 / ra,
                self.table[self.mat[a], wmat], rec)
            other = -1 - b
        if not applied:
            return None
        self.v0[a] = [float(c) for c in self.vel[a]]
        self.count[a] += 1
        if kind == EV_PAIR:
            self.v0[b] = [float(c) for c in self.vel[b]]
            self.count[b] += 1
        self.dissipated += float(rec[REC_ENERGY_LOST])
        return (t, kind, a, other, float(rec[REC_J_N]), float(rec[REC_J_T]),
                float(rec[REC_E_N]), int(rec[REC_STAGE]), int(rec[REC_REGIME]))

    def pop_valid(self, t_stop):
        """Remove and return the earliest collision whose participants are unchanged (rechecks
        on the way are carried out), an entry later than ``t_stop``, or None."""
        queue = self.queue
        while queue:
            entry = heapq.heappop(queue)
            t, _, kind, a, b, ca, cb = entry
            if t > t_stop:
                return entry
            if ca == self.count[a] and (kind == EV_WALL or cb == self.count[b]):
                if kind != KIND_RECHECK:
                    return entry
                xa, va = self.state(a, t)
                self.predict_pair(a, xa, va, b, t)
                continue
            self.stale += 1
        return None

    def run(self, t_stop, max_collisions):
        for i in range(self.n):
            self.predict(i, 0.0, skip=range(i))  # each pair once, found by its lower index
        log = []
        t_end = t_stop
        while max_collisions is None or len(log) < max_collisions:
            entry = self.pop_valid(t_stop)
            if entry is None or entry[0] > t_stop:
                break
            t, _, kind, a, b, _, _ = entry
            row = self.collide(kind, a, b, t)
            if row is None:
                # a miss: the counters did not move, so every queued event stays valid, but the
                # participants look again from the contact (a sphere resting on a plane then
                # repeats the miss without advancing and trips the no-progress guard instead of
                # sinking through the plane)
                self.missed += 1
            else:
                log.append(row)
            self.predict(a, t)
            if kind == EV_PAIR:
                self.predict(b, t, skip=(a,))
        else:
            t_end = log[-1][0] if log else 0.0
        return log, t_end

    def final_state(self, t):
        """Positions, velocities and spins of every sphere at time t (numpy arrays)."""
        pos = np.empty((self.n, 3))
        vel = np.empty((self.n, 3))
        for i in range(self.n):
            x, v = self.state(i, t)
            pos[i] = x
            vel[i] = v
        return pos, vel, (self.omg.copy() if self.rotation else None)


def run_reference(scene, max_collisions: int | None = None,
                  until: float | None = None) -> ReferenceResult:
    """Run a scene through the pure-Python reference event loop.

    Args:
        scene: A validated :class:`~hsgran.scene.Scene`.
        max_collisions: Stop after this many collisions (sphere–sphere and sphere–plane).
        until: Stop before the first collision later than this time [s] (default: the scene's
            duration); collisions exactly at ``until`` are executed.

    Returns:
        :class:`ReferenceResult` with the collision log and the state at its ``t_end``.

    Raises:
        ReferenceLoopError: a sphere had more than :data:`MAX_NO_PROGRESS_EVENTS` consecutive
            events without its clock advancing.
    """
    driven = [w.key for w in scene.walls if getattr(w, "motion", None) is not None
              or not hasattr(w, "normal") or hasattr(w, "kind")]
    if driven:
        raise ValueError(f"the reference loop has fixed planes only ({driven[0]} is a moving "
                         "plane, a cylinder, a finite wall or a fixed sphere)")
    if getattr(scene, "outlets", ()):
        raise ValueError("the reference loop has a closed system only (the scene has outlets)")
    t_stop = scene.duration if until is None else float(until)
    ref = _Reference(scene)
    log, t_end = ref.run(t_stop, max_collisions)
    cols = list(zip(*log, strict=True)) if log else [()] * 9
    pos, vel, omg = ref.final_state(t_end)
    return ReferenceResult(
        time=np.array(cols[0], dtype=np.float64),
        kind=np.array(cols[1], dtype=np.int8),
        i=np.array(cols[2], dtype=np.int64),
        j=np.array(cols[3], dtype=np.int64),
        normal_impulse=np.array(cols[4], dtype=np.float64),
        tangential_impulse=np.array(cols[5], dtype=np.float64),
        e_n=np.array(cols[6], dtype=np.float64),
        stage=np.array(cols[7], dtype=np.int8),
        regime=np.array(cols[8], dtype=np.int8),
        t_end=float(t_end),
        position=pos,
        velocity=vel,
        angular_velocity=omg,
        dissipated=ref.dissipated,
        stale=ref.stale,
        missed=ref.missed,
    )


__all__ = ["ReferenceLoopError", "ReferenceResult", "run_reference"]
