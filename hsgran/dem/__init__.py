"""Time-resolved (soft-sphere) reference integrators of hsgran's contact law (layer 5).

The impulse model of :mod:`hsgran.contact` replaces each collision by its outcome. This package
integrates the *same* staged force law through the contact with a small fixed time step, the
way a soft-sphere DEM code (LAMMPS granular, LIGGGHTS, MercuryDPM, Yade) advances every contact:

* :mod:`.law` — the force of one contact at one instant: the loading curve of MODEL §3.1,
  §3.3, §3.4, the elastic unloading of §3.7, Dunn's adhesion line force of §3.8, a
  restitution dashpot (the DEM way to prescribe e_n), and the tangential force (Coulomb with
  rigid sticking, as the impulse model assumes, or a Mindlin spring with a Coulomb cap, as
  DEM codes use).
* :mod:`.single` — one sphere–wall impact integrated with velocity Verlet: the "truth" the
  impulse model approximates, and a DEM code's cost per contact.
* :mod:`.many` — a small fixed-step soft-sphere integrator for many spheres (cell-list
  neighbour search, Hertz + restitution dashpot + history-free Coulomb friction): the DEM
  stand-in of the accuracy–cost study (``tools/accuracy_cost.py``, docs/accuracy-cost.md).

Nothing here is on the engine's hot path; it exists for studies and tests.
"""
