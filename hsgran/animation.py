"""What every frame of a movie shows, computed from a trajectory with numpy alone (layer 6).

:mod:`hsgran.render` draws; this module decides what to draw, so that all of it can be tested
without a GL context:

* :func:`sample_times`: the simulated time of every movie frame (``--fps``, ``--time-scale``,
  ``--start``/``--end``, ``--at``);
* :class:`Playback`: positions and velocities between stored frames (exact for free flight and
  for on-plane motion, whose acceleration is constant between frames), the orientation of every
  sphere integrated from its angular velocity (for the spin marker), and the colour variable;
* :func:`camera_at`: where the camera is (presets fitted to the scene's extent, or following a
  particle), and :func:`project`, the pinhole projection VTK applies, for tests and tools;
* :func:`wall_patches`: each plane wall as a finite rectangle sized to the scene.

Everything is in SI units; angles of view in degrees, as VTK takes them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hsgran.contact.tangential import REGIME_NONE, REGIME_ROLLING, REGIME_SLIDING
from hsgran.errors import InputError
from hsgran.events.kinds import EV_LAND, EV_PAIR, EV_STATE, EV_WALL, EV_WEDGE
from hsgran.onplane import (
    MOTION_STATE_NAMES,
    MS_ASLEEP,
    MS_FLIGHT,
    MS_REST,
    MS_ROLLING,
    MS_SLIDING,
    MS_SUPPORTED,
)
from hsgran.scene import Plane
from hsgran.wallspec import WK_FACE, cylinder_bounds

# ---- time sampling -----------------------------------------------------------------------

#: Most frames one movie may have. At 30 fps this is almost an hour of video; a time scale or
#: fps mistyped by orders of magnitude would otherwise start a render that never ends.
MAX_MOVIE_FRAMES = 100_000

#: Relative slack [-] (of the movie frame step) when a sampled time is matched to a stored frame
#: and to the end of the range: t0 + k·step differs from the stored frame times by rounding,
#: which must not move a frame's state colour to the previous frame or drop the last frame.
TIME_SLACK = 1e-6

# ---- interpolation -----------------------------------------------------------------------

#: Between two stored frames a particle is taken to move with constant acceleration (cubic
#: Hermite = the exact parabola) when x1 − x0 matches (v0 + v1)/2 · Δt within this fraction of
#: its radius; otherwise something (a collision) changed its velocity on the way and it moves
#: on the straight chord, which cannot overshoot into a wall the way the cubic would.
PARABOLA_TOLERANCE = 1e-3

# ---- camera ------------------------------------------------------------------------------

#: Vertical angle of view [deg] (VTK's default; a longer lens flattens piles less readably).
VIEW_ANGLE = 30.0
#: Direction from the scene to the camera of the ``iso`` preset: in front (−y), to the right
#: (+x) and above (+z), steeper in y than x so that the x and y walls of a box do not line up.
ISO_DIRECTION = (1.0, -1.6, 1.0)
#: Share of the picture's height and width the scene's extent may fill; the rest is margin for
#: the time label and the colour legend.
FRAME_FILL = 0.82
#: The ``follow`` camera shows this many diameters of the followed sphere across the picture's
#: height: enough floor around it to see it move.
FOLLOW_VIEW_DIAMETERS = 8.0
#: ``auto`` follows a lone sphere when its diameter is below this fraction of the longest edge
#: of the scene's extent; framing the whole path would draw it a few pixels wide.
AUTO_FOLLOW_FRACTION = 0.05

# ---- walls -------------------------------------------------------------------------------

#: A plane that is not a box face extends this fraction of the extent's longest in-plane half
#: edge beyond the particles on every side, so the spheres never sit on the patch's rim.
PATCH_MARGIN = 0.25
#: Aim for this many checker squares along a patch's longest edge (a reference for the eye
#: when everything moves; the follow camera uses the followed sphere's diameter instead).
CHECKERS_PER_PATCH = 16

# ---- spin marker -------------------------------------------------------------------------

#: Body-fixed direction of the spin marker (normalised at use). Pointing it at the iso camera
#: makes the marker face the viewer at t = 0, and it is still visible from the side and top.
MARKER_AXIS = ISO_DIRECTION

# ---- colours -----------------------------------------------------------------------------

#: Colour variables of ``--color-by``.
COLOR_BY = ("speed", "state", "material", "regime")

#: Motion-state categories (hsgran.onplane.MS_*) and one for "not known" (a file without
#: motion states and without an event log to rebuild them from).
STATE_UNKNOWN = len(MOTION_STATE_NAMES)
STATE_LABELS = {MS_FLIGHT: "flight", MS_SLIDING: "sliding", MS_ROLLING: "rolling",
                MS_REST: "at rest", MS_ASLEEP: "asleep", MS_SUPPORTED: "supported",
                STATE_UNKNOWN: "unknown"}
#: sRGB [0-1]; flight is a cool colour, the on-plane states run warm to neutral as the
#: sphere calms down (sliding orange, rolling green, rest grey-blue), asleep is violet,
#: supported (moving on several contacts) teal.
STATE_COLORS = {MS_FLIGHT: (0.33, 0.62, 0.90), MS_SLIDING: (0.95, 0.50, 0.10),
                MS_ROLLING: (0.20, 0.70, 0.30), MS_REST: (0.45, 0.50, 0.60),
                MS_ASLEEP: (0.58, 0.40, 0.74), MS_SUPPORTED: (0.10, 0.60, 0.60),
                STATE_UNKNOWN: (0.70, 0.70, 0.70)}

#: Categories of ``--color-by regime``: the tangential regime of each sphere's last collision
#: (hsgran.contact.tangential.REGIME_* + 1), or no collision yet.
REGIME_NO_COLLISION = 0
REGIME_LABELS = {REGIME_NO_COLLISION: "no collision yet",
                 REGIME_NONE + 1: "no tangential impulse",
                 REGIME_ROLLING + 1: "stick (leaves rolling)",
                 REGIME_SLIDING + 1: "sliding"}
REGIME_COLORS = {REGIME_NO_COLLISION: (0.75, 0.75, 0.75), REGIME_NONE + 1: (0.33, 0.62, 0.90),
                 REGIME_ROLLING + 1: (0.20, 0.70, 0.30), REGIME_SLIDING + 1: (0.90, 0.25, 0.20)}

#: Material colours (matplotlib's "tab10", which stays distinct for up to ten materials).
MATERIAL_COLORS = ((0.12, 0.47, 0.71), (1.00, 0.50, 0.05), (0.17, 0.63, 0.17),
                   (0.84, 0.15, 0.16), (0.58, 0.40, 0.74), (0.55, 0.34, 0.29),
                   (0.89, 0.47, 0.76), (0.50, 0.50, 0.50), (0.74, 0.74, 0.13),
                   (0.09, 0.75, 0.81))


# ---- sampling ----------------------------------------------------------------------------

def frame_interval(time: np.ndarray) -> float:
    """Typical time between stored frames [s] (the median step; 0 for a single frame)."""
    if time.shape[0] < 2:
        return 0.0
    return float(np.median(np.diff(time)))


def default_time_scale(time: np.ndarray, fps: float) -> float:
    """Simulated seconds per second of video that shows every stored frame once [-]."""
    dt = frame_interval(time)
    return dt * fps if dt > 0.0 else 1.0


def sample_times(time: np.ndarray, *, fps: float, time_scale: float | None = None,
                 start: float | None = None, end: float | None = None,
                 at: float | None = None) -> np.ndarray:
    """Simulated time of every movie frame.

    Args:
        time: Stored frame times [s], shape (F,), non-decreasing.
        fps: Movie frames per second of video [1/s].
        time_scale: Simulated seconds per second of video [-] (0.1: ten times slower than
            real time); ``None``: one movie frame per stored frame.
        start, end: Simulated time range [s]; default: the whole trajectory.
        at: One time [s] for a still; the other arguments are then ignored.

    Returns:
        Times [s], shape (M,), M ≥ 1, within the stored range.

    Raises:
        InputError: a time outside the stored range, ``start >= end``, or more than
            :data:`MAX_MOVIE_FRAMES` frames; the message names the option.
    """
    t_first, t_last = float(time[0]), float(time[-1])
    span = f"[{t_first:.6g}, {t_last:.6g}] s"
    slack = TIME_SLACK * max(frame_interval(time), abs(t_last), 1e-300)
    if at is not None:
        if not t_first - slack <= at <= t_last + slack:
            raise InputError(f"{at:g} s is outside the trajectory's time range {span}", "--at")
        return np.array([min(max(at, t_first), t_last)])
    for name, value in (("--start", start), ("--end", end)):
        if value is not None and not t_first - slack <= value <= t_last + slack:
            raise InputError(f"{value:g} s is outside the trajectory's time range {span}", name)
    t0 = t_first if start is None else max(start, t_first)
    t1 = t_last if end is None else min(end, t_last)
    if t1 < t0:
        raise InputError(f"must not be before --start ({t0:g} s), got {t1:g} s", "--end")
    scale = default_time_scale(time, fps) if time_scale is None else time_scale
    step = scale / fps
    count = math.floor((t1 - t0) / step * (1.0 + TIME_SLACK) + TIME_SLACK) + 1
    if count > MAX_MOVIE_FRAMES:
        raise InputError(
            f"{count:,} frames for {t1 - t0:g} s of simulated time at --fps {fps:g} and "
            f"--time-scale {scale:g}; the limit is {MAX_MOVIE_FRAMES:,} (raise --time-scale "
            "or narrow --start/--end)", "--time-scale")
    return np.minimum(t0 + step * np.arange(count), t1)


def time_label_decimals(times: np.ndarray, time: np.ndarray) -> int:
    """Decimals [-] that tell consecutive movie frames (or stored frames, for a still) apart."""
    step = float(np.min(np.diff(times))) if times.shape[0] > 1 else frame_interval(time)
    if step <= 0.0:
        return 3
    return min(9, max(0, math.ceil(-math.log10(step)) + 1))


# ---- rotations ---------------------------------------------------------------------------

def quaternion_from_rotation_vector(phi: np.ndarray) -> np.ndarray:
    """Unit quaternions (w, x, y, z), (..., 4), of the rotations by vectors ``phi`` [rad]."""
    angle = np.linalg.norm(phi, axis=-1)
    half = 0.5 * angle
    # sin(a/2)/a → 1/2 as a → 0; the series avoids 0/0 for spheres that do not spin
    small = angle < 1e-8
    factor = np.where(small, 0.5 - angle**2 / 48.0, np.sin(half) / np.where(small, 1.0, angle))
    return np.concatenate([np.cos(half)[..., None], phi * factor[..., None]], axis=-1)


def quaternion_multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton products a ⊗ b of quaternions (w, x, y, z), shape (..., 4)."""
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack([aw * bw - ax * bx - ay * by - az * bz,
                     aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw], axis=-1)


def rotation_matrices(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of unit quaternions (w, x, y, z), shape (..., 4)."""
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], axis=-2)


# ---- playback ----------------------------------------------------------------------------

@dataclass
class FrameState:
    """Everything drawn for one movie frame.

    Attributes:
        time: Simulated time [s].
        position: Sphere centres [m], shape (N, 3).
        velocity: Velocities [m/s], shape (N, 3).
        rotation: Orientation of every sphere since t = 0, rotation matrices (N, 3, 3).
        values: Colour variable: speed [m/s] (float) or a category index (int), shape (N,).
        shown: Whether each sphere is in the system, shape (N,) bool: one that has left
            through an outlet (or leaves before the next stored frame) is not drawn, and its
            position and velocity are zeros (docs/open-systems.md).
    """

    time: float
    position: np.ndarray
    velocity: np.ndarray
    rotation: np.ndarray
    values: np.ndarray
    shown: np.ndarray


class Playback:
    """Reads a trajectory at arbitrary times, in increasing order.

    Positions between stored frames follow the cubic Hermite curve through the frames' positions
    and velocities (the exact parabola when the acceleration is constant, see
    :data:`PARABOLA_TOLERANCE`). Orientations start at the identity at the first stored frame
    and follow dR/dt = [ω]× R with ω taken linear in time between frames (exact for a sphere
    sliding or rolling in a straight line); a sampled time earlier than the last one restarts the
    integration from the first frame.

    Args:
        traj: A :class:`hsgran.io.h5md.Trajectory`.
        color_by: One of :data:`COLOR_BY`.

    Raises:
        InputError: ``color_by`` unknown, or ``regime`` without an event log.
    """

    def __init__(self, traj, color_by: str = "speed"):
        check_color_by(color_by, traj)
        self.traj = traj
        self.color_by = color_by
        self.n = traj.n_particles
        # period of each axis [m], 0 where the axis is not periodic
        self._period = np.zeros(3)
        self._lower = np.zeros(3)
        if traj.box_lower is not None:
            self._period = np.where(traj.periodic, traj.box_upper - traj.box_lower, 0.0)
            self._lower = np.asarray(traj.box_lower, dtype=float)
        self._wrap = self._period > 0.0
        self._states = motion_states(traj) if color_by == "state" else None
        self._regime_events = _collision_events(traj) if color_by == "regime" else None
        self.speed_max = (float(np.nanmax(np.linalg.norm(traj.velocity, axis=-1)))
                          if color_by == "speed" else 0.0)
        self._restart()

    def _restart(self) -> None:
        self._k = 0                                  # stored frame the orientation refers to
        self._q = np.zeros((self.n, 4))
        self._q[:, 0] = 1.0
        self._regime = np.full(self.n, REGIME_NO_COLLISION, dtype=np.int64)
        self._next_event = 0
        self._t_last = -math.inf

    # -- positions ---------------------------------------------------------------------------

    def _bracket(self, t: float) -> tuple[int, float, float]:
        """Stored frame k with time[k] ≤ t (< time[k+1] unless k is the last), τ and Δt [s]."""
        time = self.traj.time
        f = time.shape[0]
        slack = TIME_SLACK * max(frame_interval(time), 1e-300)
        k = int(np.searchsorted(time, t + slack, side="right")) - 1
        k = min(max(k, 0), f - 1)
        if k == f - 1:
            return k, 0.0, 0.0
        return k, max(t - float(time[k]), 0.0), float(time[k + 1] - time[k])

    def positions(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Centres [m] and velocities [m/s] at time t [s], shapes (N, 3)."""
        k, tau, dt = self._bracket(t)
        x0, v0 = self.traj.position[k], self.traj.velocity[k]
        if dt <= 0.0 or tau <= 0.0:
            return x0.copy(), v0.copy()
        x1, v1 = self.traj.position[k + 1], self.traj.velocity[k + 1]
        dx = x1 - x0
        period = np.where(self._wrap, self._period, 1.0)
        if np.any(self._wrap):
            # the shorter way round a periodic axis: a sphere leaving through one side
            # re-enters through the other between the two frames
            dx = np.where(self._wrap, dx - period * np.round(dx / period), dx)
        s = tau / dt
        residual = np.linalg.norm(dx - 0.5 * (v0 + v1) * dt, axis=1)
        smooth = (residual <= PARABOLA_TOLERANCE * self.traj.radius)[:, None]
        # cubic Hermite basis on [0, 1] for x0, x0 + dx and the tangents v0·dt, v1·dt
        h10, h01, h11 = s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
        x_cubic = x0 + h01 * dx + (h10 * v0 + h11 * v1) * dt
        x = np.where(smooth, x_cubic, x0 + s * dx)
        v = np.where(smooth, v0 + (v1 - v0) * s, v0 if s < 0.5 else v1)
        if np.any(self._wrap):
            x = np.where(self._wrap, self._lower + np.mod(x - self._lower, period), x)
        return x, v

    # -- orientation ----------------------------------------------------------------------------

    def _omega(self, k: int) -> np.ndarray:
        # a sphere not in the system (NaN) does not turn
        return np.nan_to_num(self.traj.angular_velocity[k])

    def rotations(self, t: float) -> np.ndarray:
        """Orientation of every sphere at t [s] relative to the first frame, (N, 3, 3)."""
        if t < self._t_last:
            self._restart()
        self._t_last = t
        if self.traj.angular_velocity is None:
            return np.broadcast_to(np.eye(3), (self.n, 3, 3))
        k, tau, dt = self._bracket(t)
        time = self.traj.time
        while self._k < k:
            step = float(time[self._k + 1] - time[self._k])
            phi = 0.5 * (self._omega(self._k) + self._omega(self._k + 1)) * step
            self._q = quaternion_multiply(quaternion_from_rotation_vector(phi), self._q)
            self._q /= np.linalg.norm(self._q, axis=1, keepdims=True)
            self._k += 1
        q = self._q
        if dt > 0.0 and tau > 0.0:
            w0, w1 = self._omega(k), self._omega(k + 1)
            phi = w0 * tau + (w1 - w0) * (tau**2 / (2.0 * dt))
            q = quaternion_multiply(quaternion_from_rotation_vector(phi), q)
        return rotation_matrices(q)

    # -- colours ------------------------------------------------------------------------------

    def values(self, t: float, velocity: np.ndarray) -> np.ndarray:
        """The colour variable at t [s]: speed [m/s] or category index, shape (N,)."""
        if self.color_by == "speed":
            return np.linalg.norm(velocity, axis=1)
        if self.color_by == "material":
            return self.traj.material.astype(np.int64)
        if self.color_by == "state":
            k, _, _ = self._bracket(t)
            return self._states[k].astype(np.int64)
        ev_t, ev_i, ev_j, ev_r = self._regime_events
        slack = TIME_SLACK * max(frame_interval(self.traj.time), 1e-300)
        stop = int(np.searchsorted(ev_t, t + slack, side="right"))
        for e in range(self._next_event, stop):    # time order: the last one of each wins
            self._regime[ev_i[e]] = ev_r[e] + 1
            if ev_j[e] >= 0:
                self._regime[ev_j[e]] = ev_r[e] + 1
        self._next_event = max(self._next_event, stop)
        return self._regime.copy()

    def frame(self, t: float) -> FrameState:
        """Everything drawn at time t [s] (times must not decrease between calls, or the spin
        integration restarts from the first frame)."""
        rotation = self.rotations(t)
        x, v = self.positions(t)
        shown = np.isfinite(x).all(axis=1)  # absent spheres have NaN positions
        if not shown.all():
            x[~shown] = 0.0
            v[~shown] = 0.0
        return FrameState(time=t, position=x, velocity=v, rotation=rotation,
                          values=self.values(t, v), shown=shown)

    def categories(self) -> dict[int, tuple[str, tuple[float, float, float]]]:
        """Category index → (label, colour) of a categorical colour variable, in legend order
        (only the materials of the spheres; every state and regime)."""
        if self.color_by == "state":
            present = np.unique(self._states)
            return {c: (STATE_LABELS[c], STATE_COLORS[c]) for c in STATE_LABELS if c in present}
        if self.color_by == "regime":
            return {c: (REGIME_LABELS[c], REGIME_COLORS[c]) for c in REGIME_LABELS}
        if self.color_by == "material":
            names = self.traj.material_names
            return {int(m): (names[m], MATERIAL_COLORS[int(m) % len(MATERIAL_COLORS)])
                    for m in np.unique(self.traj.material)}
        return {}


def check_color_by(color_by: str, traj) -> None:
    """Raise :class:`InputError` (naming ``--color-by``) for an unknown colour variable, or
    ``regime`` for a trajectory without an event log."""
    if color_by not in COLOR_BY:
        raise InputError(f"unknown value '{color_by}'; choose one of {', '.join(COLOR_BY)}",
                         "--color-by")
    if color_by == "regime" and traj.events is None:
        raise InputError("'regime' needs the event log: run the scene with "
                         "'hsgran run --events'", "--color-by")


def motion_states(traj) -> np.ndarray:
    """Motion state of every particle at every stored frame, (F, N) int.

    Taken from the file when it has them; otherwise rebuilt from the event log (a landing or
    state change sets the new state, a collision sends the sphere into flight); without either,
    flight when the scene has no gravity (nothing else is possible) and :data:`STATE_UNKNOWN`
    otherwise.
    """
    stored = getattr(traj, "motion_state", None)
    if stored is not None:
        return np.asarray(stored, dtype=np.int64)
    f, n = traj.n_frames, traj.n_particles
    if traj.events is None:
        fill = MS_FLIGHT if "gravity" not in traj.effects else STATE_UNKNOWN
        return np.full((f, n), fill, dtype=np.int64)
    ev = traj.events
    order = np.argsort(ev["time"], kind="stable")
    state = np.full(n, MS_FLIGHT, dtype=np.int64)
    out = np.empty((f, n), dtype=np.int64)
    e, n_events = 0, order.shape[0]
    for k, t in enumerate(traj.time):
        while e < n_events and ev["time"][order[e]] <= t:
            i = order[e]
            kind = int(ev["kind"][i])
            if kind in (EV_STATE, EV_LAND, EV_WEDGE):
                state[ev["i"][i]] = int(ev["stage"][i])
            elif kind in (EV_PAIR, EV_WALL):
                state[ev["i"][i]] = MS_FLIGHT
                if kind == EV_PAIR and ev["j"][i] >= 0:
                    state[ev["j"][i]] = MS_FLIGHT
            e += 1
        out[k] = state
    return out


def _collision_events(traj):
    """Collisions (pair and wall) of the event log in time order: time, i, j, regime."""
    ev = traj.events
    kind = ev["kind"]
    keep = (kind == EV_PAIR) | (kind == EV_WALL)
    order = np.argsort(ev["time"][keep], kind="stable")
    return (ev["time"][keep][order], ev["i"][keep][order].astype(np.int64),
            np.where(kind[keep] == EV_PAIR, ev["j"][keep], -1)[order].astype(np.int64),
            ev["regime"][keep][order].astype(np.int64))


# ---- extent and camera -------------------------------------------------------------------

def scene_extent(traj) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper corners [m] of everything the spheres reach (at their radii) and of the
    box, over all stored frames (while they are in the system)."""
    r = traj.radius[None, :, None]
    lower = np.nanmin(traj.position - r, axis=(0, 1))
    upper = np.nanmax(traj.position + r, axis=(0, 1))
    if traj.box_lower is not None:
        lower = np.minimum(lower, traj.box_lower)
        upper = np.maximum(upper, traj.box_upper)
    walls = getattr(traj, "walls", None)  # (stand-ins in tests may have none)
    for k in range(0 if walls is None else len(walls)):
        if walls.is_cylinder(k):
            lo, hi = cylinder_bounds(walls.point[k], walls.cylinder[k])
            lower = np.minimum(lower, lo)
            upper = np.maximum(upper, hi)
    return lower, upper


@dataclass(frozen=True)
class CameraSpec:
    """A parsed ``--camera`` value.

    Attributes:
        kind: ``auto``, ``iso``, ``side``, ``top``, ``follow`` or ``position``.
        particle: Followed particle (``follow``).
        position: Camera position [m] (``position``).
        focal_point: Point looked at [m] (``position``; ``None``: the scene's centre).
    """

    kind: str
    particle: int | None = None
    position: tuple[float, float, float] | None = None
    focal_point: tuple[float, float, float] | None = None


#: Camera presets of ``--camera`` (besides follow:K and explicit positions).
CAMERA_PRESETS = ("auto", "iso", "side", "top")


def parse_camera(text: str) -> CameraSpec:
    """Parse ``--camera``: a preset, ``follow:K``, ``X,Y,Z`` or ``X,Y,Z:FX,FY,FZ`` (metres).

    Raises:
        InputError: naming ``--camera``.
    """
    value = text.strip().lower()
    if value in CAMERA_PRESETS:
        return CameraSpec(value)
    if value.startswith("follow:"):
        index = value.removeprefix("follow:")
        if not index.isdigit():
            raise InputError(f"follow:K needs a particle index K >= 0, got '{text}'", "--camera")
        return CameraSpec("follow", particle=int(index))
    if "," in value:
        parts = value.split(":")
        if len(parts) > 2:
            raise InputError(f"expected X,Y,Z or X,Y,Z:FX,FY,FZ, got '{text}'", "--camera")
        points = [_point(p, text) for p in parts]
        return CameraSpec("position", position=points[0],
                          focal_point=points[1] if len(points) == 2 else None)
    raise InputError(f"unknown value '{text}'; choose one of {', '.join(CAMERA_PRESETS)}, "
                     "follow:K (particle K), X,Y,Z (camera position in m) or X,Y,Z:FX,FY,FZ "
                     "(position and point looked at)", "--camera")


def _point(text: str, whole: str) -> tuple[float, float, float]:
    try:
        xyz = tuple(float(c) for c in text.split(","))
    except ValueError:
        xyz = ()
    if len(xyz) != 3 or not all(math.isfinite(c) for c in xyz):
        raise InputError(f"expected three finite numbers X,Y,Z (m), got '{whole}'", "--camera")
    return xyz


@dataclass(frozen=True)
class Camera:
    """A pinhole camera as VTK takes it.

    Attributes:
        position: Eye [m], shape (3,).
        focal_point: Point at the picture's centre [m], shape (3,).
        view_up: Up direction [-], shape (3,), orthogonal to the view direction.
        view_angle: Vertical angle of view [deg].
    """

    position: np.ndarray
    focal_point: np.ndarray
    view_up: np.ndarray
    view_angle: float = VIEW_ANGLE


def check_camera(spec: CameraSpec, traj) -> None:
    """Raise :class:`InputError` for a followed particle that does not exist or a camera
    placed at its own focal point."""
    if spec.kind == "follow" and spec.particle >= traj.n_particles:
        raise InputError(f"follow:{spec.particle}: the trajectory has {traj.n_particles} "
                         f"particles (0 to {traj.n_particles - 1})", "--camera")
    if spec.kind == "position":
        lower, upper = scene_extent(traj)
        focal = (0.5 * (lower + upper) if spec.focal_point is None
                 else np.array(spec.focal_point))
        if np.linalg.norm(np.array(spec.position) - focal) == 0.0:
            raise InputError("the camera position is the point it looks at", "--camera")


def resolve_camera(spec: CameraSpec, traj) -> CameraSpec:
    """Replace ``auto`` by ``iso``, or by ``follow:0`` for a lone sphere that would be drawn
    tiny (see :data:`AUTO_FOLLOW_FRACTION`)."""
    if spec.kind != "auto":
        return spec
    lower, upper = scene_extent(traj)
    if traj.n_particles == 1 and 2.0 * traj.radius[0] < AUTO_FOLLOW_FRACTION * np.max(
            upper - lower):
        return CameraSpec("follow", particle=0)
    return CameraSpec("iso")


def _basis(direction: np.ndarray, up_hint: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit right and up vectors of a camera looking along −direction."""
    d = direction / np.linalg.norm(direction)
    if abs(float(np.dot(d, up_hint / np.linalg.norm(up_hint)))) > 0.999:
        up_hint = np.array([0.0, 1.0, 0.0]) if abs(d[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    right = np.cross(up_hint, d)
    right /= np.linalg.norm(right)
    return right, np.cross(d, right)


def fit_distance(direction, right, up, lower, upper, aspect: float,
                 view_angle: float = VIEW_ANGLE, fill: float = FRAME_FILL) -> float:
    """Distance [m] from the extent's centre at which a perspective camera looking along
    −direction sees the whole box [lower, upper] within ``fill`` of the picture.

    A corner at (x, y) across and z towards the camera (relative to the centre) is inside
    when |x| ≤ (D − z) tan(h/2) and |y| ≤ (D − z) tan(v/2), h and v the horizontal and vertical
    angles of view; D is the smallest distance that satisfies this for all eight corners.
    """
    centre = 0.5 * (lower + upper)
    tan_v = math.tan(math.radians(view_angle) / 2.0) * fill
    tan_h = math.tan(math.radians(view_angle) / 2.0) * aspect * fill
    corners = np.array([[x, y, z] for x in (lower[0], upper[0]) for y in (lower[1], upper[1])
                        for z in (lower[2], upper[2])]) - centre
    x, y, z = corners @ right, corners @ up, corners @ direction
    need = z + np.maximum(np.abs(x) / tan_h, np.abs(y) / tan_v)
    return float(max(np.max(need), 1e-12))


def camera_at(spec: CameraSpec, traj, size: tuple[int, int],
              followed_position: np.ndarray | None = None) -> Camera:
    """The camera of one frame.

    Args:
        spec: A resolved :class:`CameraSpec` (not ``auto``, see :func:`resolve_camera`).
        traj: The trajectory (for its extent and radii).
        size: Picture width and height [px].
        followed_position: Centre [m] of the followed particle in this frame (``follow``).

    Returns:
        The :class:`Camera`.
    """
    lower, upper = scene_extent(traj)
    centre = 0.5 * (lower + upper)
    z_up = np.array([0.0, 0.0, 1.0])
    aspect = size[0] / size[1]
    if spec.kind == "position":
        position = np.array(spec.position, dtype=float)
        focal = centre if spec.focal_point is None else np.array(spec.focal_point, dtype=float)
        _, up = _basis(position - focal, z_up)
        return Camera(position, focal, up)
    if spec.kind == "follow":
        radius = float(traj.radius[spec.particle])
        direction = np.array(ISO_DIRECTION) / np.linalg.norm(ISO_DIRECTION)
        _, up = _basis(direction, z_up)
        distance = FOLLOW_VIEW_DIAMETERS * 2.0 * radius / (
            2.0 * math.tan(math.radians(VIEW_ANGLE) / 2.0))
        focal = np.asarray(followed_position, dtype=float)
        return Camera(focal + distance * direction, focal, up)
    direction, up_hint = {
        "iso": (np.array(ISO_DIRECTION), z_up),
        "side": (np.array([0.0, -1.0, 0.0]), z_up),
        "top": (np.array([0.0, 0.0, 1.0]), np.array([0.0, 1.0, 0.0])),
    }[spec.kind]
    direction = direction / np.linalg.norm(direction)
    right, up = _basis(direction, up_hint)
    distance = fit_distance(direction, right, up, lower, upper, aspect)
    return Camera(centre + distance * direction, centre, up)


def project(points: np.ndarray, camera: Camera, size: tuple[int, int]) -> np.ndarray:
    """Pixel coordinates (column, row from the top) of world points [m] (..., 3) in a picture
    of ``size`` (width, height) [px] taken by ``camera`` (VTK's perspective projection with a
    vertical angle of view; pixel centres at half-integers)."""
    width, height = size
    back = camera.position - camera.focal_point
    back = back / np.linalg.norm(back)
    right = np.cross(camera.view_up, back)
    right /= np.linalg.norm(right)
    up = np.cross(back, right)
    rel = np.asarray(points, dtype=float) - camera.position
    depth = -(rel @ back)
    focal_px = 0.5 * height / math.tan(math.radians(camera.view_angle) / 2.0)
    column = 0.5 * width + focal_px * (rel @ right) / depth
    row = 0.5 * height - focal_px * (rel @ up) / depth
    return np.stack([column, row], axis=-1)


# ---- walls -------------------------------------------------------------------------------

@dataclass(frozen=True)
class WallPatch:
    """A plane wall drawn as a rectangle.

    Attributes:
        corners: Corners [m], shape (4, 3), counter-clockwise seen from the side the normal
            points to (so the polygon's own normal is the wall's).
        normal: Unit normal [-] into the spheres' side, shape (3,).
        material: Material index of the wall.
        edge_u, edge_v: Lengths [m] of the edges corner 0→1 and 1→2.
    """

    corners: np.ndarray
    normal: np.ndarray
    material: int
    edge_u: float
    edge_v: float


def wall_patches(planes: list[Plane], lower: np.ndarray, upper: np.ndarray,
                 box_lower: np.ndarray | None = None,
                 box_upper: np.ndarray | None = None) -> list[WallPatch]:
    """Finite rectangles for plane walls: box faces exactly, other planes the extent
    [lower, upper] projected onto them plus :data:`PATCH_MARGIN` on every side.

    Args:
        planes: Plane walls (hsgran.scene.Plane: point, unit normal, material).
        lower, upper: Corners of the scene's extent [m].
        box_lower, box_upper: Corners of the box [m], or ``None``.

    Returns:
        One :class:`WallPatch` per plane.
    """
    patches = []
    for plane in planes:
        n = np.asarray(plane.normal, dtype=float)
        on_box = _box_face(plane, box_lower, box_upper)
        lo, hi = (box_lower, box_upper) if on_box else (lower, upper)
        centre = 0.5 * (lo + hi)
        centre = centre - float(np.dot(centre - plane.point, n)) * n
        axis = np.eye(3)[int(np.argmin(np.abs(n)))]
        u = np.cross(n, axis)
        u /= np.linalg.norm(u)
        v = np.cross(n, u)
        corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                            for z in (lo[2], hi[2])]) - centre
        half_u = float(np.max(np.abs(corners @ u)))
        half_v = float(np.max(np.abs(corners @ v)))
        if not on_box:
            margin = PATCH_MARGIN * max(half_u, half_v)
            half_u, half_v = half_u + margin, half_v + margin
        quad = np.array([centre - half_u * u - half_v * v, centre + half_u * u - half_v * v,
                         centre + half_u * u + half_v * v, centre - half_u * u + half_v * v])
        patches.append(WallPatch(quad, n, int(plane.material), 2.0 * half_u, 2.0 * half_v))
    return patches


@dataclass(frozen=True)
class PartSurface:
    """A face of a finite wall, to draw: its corners and polygons (pyvista's ``faces``
    layout: a count, then that many corner indices), its normal and material."""

    points: np.ndarray  #: corners [m], shape (K, 3)
    faces: np.ndarray  #: polygons (int)
    normal: np.ndarray  #: unit normal, to the side spheres meet [-]
    material: int


def part_surfaces(parts: list, lower: np.ndarray, upper: np.ndarray,
                  box_lower: np.ndarray | None = None,
                  box_upper: np.ndarray | None = None) -> list[PartSurface]:
    """The faces of finite walls to draw (hsgran.shapes.Part of kind WK_FACE; the other parts
    are not drawn): a polygon as itself; a plane with a hole as the plane's patch
    (:func:`wall_patches`) less the hole, in triangles between the two outlines (both convex,
    around the hole's middle)."""
    out = []
    for part in parts:
        if part.kind != WK_FACE:
            continue
        outline = part.outline()
        if len(outline):
            faces = np.concatenate([[len(outline)], np.arange(len(outline))])
            out.append(PartSurface(outline, faces, part.normal, part.material))
            continue
        hole = part.hole()
        plane = Plane(part.point, part.normal, part.material, part.key)
        quad = wall_patches([plane], lower, upper, box_lower, box_upper)[0].corners
        # the rectangle (in the face's axes) around the patch and the hole, with a margin
        e1, e2 = part.geo[0:3], part.geo[3:6]
        uv = np.concatenate([quad, hole]) - part.point
        u, v = uv @ e1, uv @ e2
        margin = PATCH_MARGIN * max(np.ptp(u), np.ptp(v))
        (u0, u1), (v0, v1) = (u.min() - margin, u.max() + margin), (v.min() - margin,
                                                                     v.max() + margin)
        outer = part.point + np.array([[a, b] for a, b in ((u0, v0), (u1, v0), (u1, v1),
                                                           (u0, v1))]) @ np.array([e1, e2])
        out.append(PartSurface(*_annulus(outer, hole, part.point, e1, e2), part.normal,
                               part.material))
    return out


def _annulus(outer: np.ndarray, inner: np.ndarray, centre, e1, e2) -> tuple:
    """Triangles between two convex outlines around ``centre`` (in the plane of axes e1, e2):
    both are walked once round by angle about the centre from the same ray, each step joining
    the next corner of the outline whose next corner comes first. Returns (points, faces)."""
    points = np.concatenate([outer, inner])

    def walk(corners, offset, start):
        d = corners - centre
        angle = np.mod(np.arctan2(d @ e2, d @ e1) - start, 2.0 * np.pi)
        order = np.argsort(angle, kind="stable")
        # once round, back to the first corner a turn later
        return (np.append(order, order[0]) + offset, np.append(angle[order],
                                                               angle[order[0]] + 2.0 * np.pi))

    d0 = outer[0] - centre
    start = math.atan2(float(d0 @ e2), float(d0 @ e1))
    o, ao = walk(outer, 0, start)
    h, ah = walk(inner, len(outer), start)
    faces = []
    i = j = 0
    while i < len(outer) or j < len(inner):
        if j == len(inner) or (i < len(outer) and ao[i + 1] <= ah[j + 1]):
            faces += [3, o[i], o[i + 1], h[j]]
            i += 1
        else:
            faces += [3, o[i], h[j + 1], h[j]]
            j += 1
    return points, np.array(faces, dtype=np.int64)


def _box_face(plane: Plane, box_lower, box_upper) -> bool:
    if box_lower is None:
        return False
    n = np.asarray(plane.normal, dtype=float)
    axis = int(np.argmax(np.abs(n)))
    if abs(abs(n[axis]) - 1.0) > 1e-12:
        return False
    face = box_lower[axis] if n[axis] > 0 else box_upper[axis]
    return bool(np.isclose(plane.point[axis], face, rtol=0.0,
                           atol=1e-9 * float(np.max(box_upper - box_lower))))


def nice_step_above(length: float) -> float:
    """The smallest number 1, 2 or 5 × 10^k that is >= ``length`` > 0."""
    exponent = math.floor(math.log10(length))
    for e in (exponent, exponent + 1):
        for m in (1, 2, 5):
            if m * 10.0**e >= length * (1.0 - 1e-12):
                return m * 10.0**e
    return 10.0 ** (exponent + 1)


def nice_spacing(length: float) -> float:
    """The number 1, 2 or 5 × 10^k closest in ratio to ``length`` [m] (1 for a bad length)."""
    if length <= 0.0 or not math.isfinite(length):
        return 1.0
    exponent = math.floor(math.log10(length))
    best = min((m * 10.0**e for e in (exponent - 1, exponent, exponent + 1) for m in (1, 2, 5)),
               key=lambda s: abs(math.log(s / length)))
    return best
