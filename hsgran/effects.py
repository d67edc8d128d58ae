"""The physical effects a scene asks for (layer 1).

A scene lists its effects; everything else is assembled from that list once, so the hot loops
never ask "is friction on?". An :class:`Effects` value is immutable and hashable: it is the key
of the compiled-kernel caches.

Effects and what they switch on:

===================== ==========================================================================
``gravity``           parabolic free flight (engine)
``rotation``          angular velocities exist at all
``friction``          sliding/rolling tangential impulse, MODEL §4 (needs ``rotation``)
``rolling_resistance`` rolling couple μ_r R* F_n, MODEL §5 (needs ``friction``)
``plasticity``        staged elastic / elastic–plastic / fully plastic normal model, MODEL §3;
                      without it the normal law is elastic Hertz (e_n = 1) or the pair's fixed
                      restitution
``adhesion``          Dunn's line force during recovery, MODEL §3.8
``tangential_compliance`` beyond the paper: the friction impulse of an elastic (Mindlin) contact
                      instead of rigid sticking, docs/model.md §4.5 (needs ``friction``)
``viscoelastic_damping`` beyond the paper: the restitution of viscoelastic spheres below the
                      yield speed, docs/model.md §3.11
===================== ==========================================================================

The last two are physics beyond the paper (docs/model.md says where each comes from); without
them every result is the paper's, bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

from hsgran.errors import InputError, did_you_mean

#: Effects of physics beyond the paper: never on unless a scene or call names them.
BEYOND_PAPER = ("tangential_compliance", "viscoelastic_damping")

#: Which effect needs which other effect to make sense.
REQUIRES = {
    "friction": ("rotation",),
    "rolling_resistance": ("friction",),
    "tangential_compliance": ("friction",),
}


@dataclass(frozen=True, slots=True)
class Effects:
    """A set of enabled effects (all off by default)."""

    gravity: bool = False
    rotation: bool = False
    friction: bool = False
    rolling_resistance: bool = False
    plasticity: bool = False
    adhesion: bool = False
    tangential_compliance: bool = False
    viscoelastic_damping: bool = False

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """All effect names, in a fixed order."""
        return tuple(f.name for f in fields(cls))

    @classmethod
    def parse(cls, names, key: str = "effects") -> Effects:
        """Build an effect set from a list of names, checking spelling and requirements.

        Args:
            names: Iterable of effect names (strings).
            key: Key path used in error messages.

        Raises:
            InputError: unknown or repeated name, or an effect whose requirement is missing.
        """
        if isinstance(names, str) or not hasattr(names, "__iter__"):
            raise InputError("must be a list of effect names", key)
        chosen: set[str] = set()
        for k, name in enumerate(names):
            if not isinstance(name, str):
                raise InputError(f"effect names are strings, got {name!r}", f"{key}[{k}]")
            if name not in cls.names():
                raise InputError(
                    f"unknown effect '{name}'{did_you_mean(name, cls.names())}; "
                    f"known: {', '.join(cls.names())}",
                    f"{key}[{k}]",
                )
            if name in chosen:
                raise InputError(f"effect '{name}' is listed twice", f"{key}[{k}]")
            chosen.add(name)
        for name, needs in REQUIRES.items():
            for need in needs:
                if name in chosen and need not in chosen:
                    raise InputError(f"effect '{name}' needs effect '{need}' as well", key)
        return cls(**{n: True for n in chosen})

    @classmethod
    def all(cls) -> Effects:
        """Every effect of the paper on (those of BEYOND_PAPER stay off: name them)."""
        return cls(**{n: n not in BEYOND_PAPER for n in cls.names()})

    def enabled(self) -> tuple[str, ...]:
        """Names of the enabled effects, in the fixed order of :meth:`names`."""
        return tuple(n for n in self.names() if getattr(self, n))

    def without(self, *names: str) -> Effects:
        """A copy with the given effects switched off (requirements are not re-checked)."""
        return Effects(**{n: getattr(self, n) and n not in names for n in self.names()})

    def __str__(self) -> str:
        return "+".join(self.enabled()) or "none"
