"""The engine's state by name (layer 5; used by :mod:`hsgran.engine` and the compiled loop).

The compiled event loop takes its arrays in seven groups. Each group is a named tuple: numba
compiles an attribute access (``flight.st``) to the same code as the positional one it replaces,
and a reader sees what each array is. The groups, and every field's role, are listed once here:

- which fields a checkpoint holds (``STORED``): everything the loop reads and writes between
  events; not the scratch space it overwrites before reading, nor the event calendar (rebuilt
  from the pending events) or the frame and log buffers (empty at every checkpoint);
- the checkpoint's dataset names: the field names, which are unique across groups.
"""

from __future__ import annotations

from collections import namedtuple

#: What a prediction needs of every sphere. ``st``: one 64-byte row per sphere (``S_*`` columns
#: of hsgran._loop: position [m], velocity [m/s], local time [s], radius [m]); ``counter``:
#: event counters; with gravity ``acc`` [m/s²], motion state ``mstate`` (hsgran.onplane MS_*),
#: plane ``mplane`` (or −2 − b when asleep on sphere b), end time ``seg_end`` [s] and kind
#: ``seg_code`` (END_*) of the on-plane motion segment; without gravity, each sphere's earliest
#: pair contact at its last prediction (``pc_t`` [s], ``pc_partner`` or −1, ``pc_count``: the
#: partner's counter then), which lets a cell crossing look at the new layer of cells only.
Flight = namedtuple("Flight", "st counter acc mstate mplane seg_end seg_code pc_t pc_partner "
                              "pc_count")
#: What a collision needs in addition. ``omg`` spins [rad/s]; ``inv_m`` [1/kg], ``inv_i``
#: [1/(kg m²)]; ``mat`` material index; ``zstreak`` events in succession without the clock
#: advancing (collapse guard); ``alpha`` [rad/s²] and ``seg_dir`` (the direction a segment's end
#: refers to) only with gravity; ``t_last`` time of the last collision [s] (TC model);
#: ``row_tc`` scratch pair row for an elastic TC collision; ``rapid`` collisions in succession
#: within the TC time (jams).
Dyn = namedtuple("Dyn", "omg inv_m inv_i mat zstreak alpha seg_dir t_last row_tc rapid")
#: The planes: a point [m], unit normal, material, velocity [m/s] and angular velocity [rad/s].
Walls = namedtuple("Walls", "planes_p planes_n planes_mat planes_vel planes_omg")
#: Gravity [m/s²], box lengths [m] (periodic axes) and which axes are periodic.
Space = namedtuple("Space", "gravity box_len periodic")
#: The cell grid (hsgran.events.grid): origin [m], cell size [m], cells per axis, each sphere's
#: cell, the linked lists (``head``, ``nxt``, ``prv``), and scratch space: 27 list heads and
#: their image shifts [m], the per-axis list coordinates ``ac`` and shifts ``ah`` [m] of a
#: prediction, and a stack for waking sleepers.
Grid = namedtuple("Grid", "origin csize ncell cell head nxt prv heads shifts ac ah stack")
#: One pending event per entry (sphere, and the frame tick last): time [s], sequence number,
#: kind (hsgran.events.kinds), partner, the partner's counter at prediction; ``cal`` the event
#: calendar (hsgran.events.calendar), whose keys are ``ev_t`` and ``ev_seq``.
Sched = namedtuple("Sched", "ev_t ev_seq ev_kind ev_partner ev_pcount cal")
#: Output buffers: frame times [s], positions [m], velocities [m/s], spins [rad/s], the event
#: log (floats ``log_f``: time, J_n, J_t, e_n; ints ``log_i``: kind, i, j, stage, regime) and
#: motion states per frame.
Out = namedtuple("Out", "fr_time fr_pos fr_vel fr_omg log_f log_i fr_ms")

#: The groups in the order the loop takes them.
GROUPS = (Flight, Dyn, Walls, Space, Grid, Sched, Out)

#: Fields the loop overwrites before it reads them (not stored in checkpoints).
SCRATCH = frozenset({"row_tc", "heads", "shifts", "ac", "ah", "stack"})
#: Fields rebuilt or emptied rather than stored: the calendar (rebuilt from ``ev_t``/``ev_seq``)
#: and the output buffers (handed to the observers before every checkpoint).
NOT_STORED = SCRATCH | {"cal"} | set(Out._fields)


def stored_fields(groups) -> dict:
    """The arrays a checkpoint holds, by field name (views of the live arrays).

    Args:
        groups: The seven group tuples (:data:`GROUPS` order).
    """
    return {name: array for group in groups
            for name, array in zip(group._fields, group, strict=True) if name not in NOT_STORED}


# ---- scalars and switches of the compiled loop -------------------------------------------


# float scalars
F_T_CUR = 0  #: time of the last popped event [s]
F_T_END = 1  #: stop before events later than this [s]
F_FRAME_DT = 2  #: frame interval [s]
F_DISSIPATED = 3  #: energy the collision model took so far (hops: negative) [J]
F_LANDING_SPEED = 4  #: rebound speed below which a sphere stays on a plane [m/s]
F_CHI = 5  #: rolling-torque convention while sliding (hsgran.onplane CONVENTION_A/_B)
#: TC model (Luding & McNamara 1998) [s]: a collision of a sphere less than this after its
#: previous collision is elastic (e_n = 1; friction still acts), which ends the infinite
#: sequences of ever-smaller collisions of inelastic collapse in clusters; 0 turns it off
F_TC_TIME = 6
F_SIZE = 7
# int scalars
I_SEQ = 0  #: next sequence number (tie-break)
I_N_FRAMES = 1  #: frames in the buffer
I_N_LOG = 2  #: event-log entries in the buffer
I_FRAME_INDEX = 3  #: index of the next frame (its time is index × frame_dt)
I_N_EVENTS = 4  #: events executed in total
I_COLLAPSED = 5  #: sphere that triggered the collapse guard, or −1
I_PEND_A = 6  #: a sphere whose next event must be predicted before the next pop, or −1
I_PEND_B = 7  #: a second one, or −1
I_PEND_LAYER = 8  #: the cell face that the sphere in I_PEND_A just crossed (EV_CELL), or −1
I_SIZE = 9

# effect and engine switches: the ``flags`` argument, a bool array of FL_SIZE entries. They are
# run-time values, so one compiled loop serves every scene with gravity and one every scene
# without (a cold compile costs tens of seconds; gravity alone is a compile-time constant, see
# run_loop); a disabled effect is skipped by one predictable branch and its code never runs.
FL_PLASTICITY = 0  #: staged normal model (MODEL §3); else elastic Hertz
FL_FRICTION = 1  #: tangential impulse (MODEL §4)
FL_ROLLING = 2  #: rolling resistance (MODEL §5)
FL_ADHESION = 3  #: adhesion in recovery (MODEL §3.8)
FL_ROTATION = 4  #: spins are tracked
FL_GRAVITY = 5  #: parabolic flight, on-plane motion states
FL_LOG = 6  #: record every event in the log buffer
FL_SIZE = 7

# What a prediction reads of a neighbour sits in one 64-byte row (one cache line) of ``st``:
S_X = 0  #: position x, y, z at the sphere's local time [m] (columns 0–2)
S_V = 3  #: velocity at the local time [m/s] (columns 3–5)
S_T = 6  #: local time: the stored state is valid at this instant [s]
S_R = 7  #: radius [m]
S_WIDTH = 8
