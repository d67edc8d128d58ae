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
