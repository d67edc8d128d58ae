"""hsgran: event-driven hard-sphere granular simulation with the impulse-based collision model
of Yu, Elghannay & Tafti (Powder Technology, 2017).

Public API (more in the submodules):

* :class:`hsgran.effects.Effects` — the effects a scene asks for;
* :class:`hsgran.materials.Material`, :class:`hsgran.materials.Contact`,
  :class:`hsgran.materials.MaterialLibrary` — materials and pair properties;
* :func:`hsgran.impact.sphere_wall_impact`, :func:`hsgran.impact.sphere_sphere_impact` —
  one collision, with a full record of what happened.

Where docs/model.md marks a formula as our own reconstruction ([OURS]) the docstring says so; the
main ones are the elastic–plastic pressure law (§3.3), the fully plastic stage (§3.4), the
line-force estimate from a work of adhesion (§3.8) and the rolling couple (§5).
"""

__version__ = "0.1.0"
