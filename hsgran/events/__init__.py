"""Event bookkeeping (layer 3): the event kinds, the priority queue and the cell grid. Knows
motion, not collision physics."""
