"""Trajectory files (layer 5): H5MD 1.1 writer and reader, see ``docs/trajectory-format.md``."""

from hsgran.io.h5md import Trajectory, TrajectoryWriter, read_trajectory

__all__ = ["Trajectory", "TrajectoryWriter", "read_trajectory"]
