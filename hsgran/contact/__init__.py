"""The collision model of MODEL §2–§6 (layer 2: one pair at one instant).

Modules, each one stage of the fixed order of MODEL §6 (applied in :mod:`.model`):
:mod:`.normal` (compression stages and elastic recovery), :mod:`.adhesion` (Dunn's line force),
:mod:`.rolling` (rolling-resistance couple), :mod:`.tangential` (sliding or rolling impulse).
These modules know nothing of time, queues or grids. Imports: numpy, numba, ``hsgran.materials``.
"""
