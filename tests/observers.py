"""An observer shared by the engine tests: it keeps every frame and event block a run hands
out, and joins a field of them."""

import numpy as np


class Keep:
    """Observer keeping every frame and event block."""

    def __init__(self):
        self.frames = []
        self.events = []

    def on_frames(self, b):
        self.frames.append(b)

    def on_events(self, b):
        self.events.append(b)

    def cat(self, name):
        """A frame field of every block, joined along the frames."""
        return np.concatenate([getattr(b, name) for b in self.frames])

    def log(self, name):
        """An event-log field of every block, joined."""
        return np.concatenate([getattr(b, name) for b in self.events])
