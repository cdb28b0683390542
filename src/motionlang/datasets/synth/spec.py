"""Ground-truth description of a synthetic sample: a list of motion primitives.

A sample is a time-ordered list of *body* primitives (walk, turn, squat, ...). An
*upper*-body primitive (wave, punch, ...) may ride on top of the body primitive just before
it in the list (``layer="upper"``: "waves with the right hand while walking").

The same record is what the sentence grammar verbalises and what the parameter extractor
(:mod:`.extract`) recovers from English, so scoring a generated description is a
comparison of :meth:`Primitive.key` tuples.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, fields

#: Everything the generator can produce. ``stand`` is "stands still".
ACTIONS = ("walk", "run", "turn", "wave", "kick", "stomp", "squat", "jump", "raise_arms",
           "bow", "wipe", "punch", "stand")
#: Actions that move only the arms and may be layered over walking/standing.
UPPER_ACTIONS = ("wave", "punch", "wipe", "raise_arms")
LOCOMOTION = ("walk", "run")
SIDES = ("left", "right", "both")
#: walk/run: forward, backward, left, right (side-stepping), circle (side = turn sense);
#: jump: in_place, forward.
DIRECTIONS = ("forward", "backward", "left", "right", "circle", "in_place")
SPEEDS = ("slow", "normal", "fast")
#: The parameters a sentence can state; ``start``/``end`` are never verbalised.
PARAM_FIELDS = ("action", "side", "count", "direction", "speed", "angle")


@dataclass
class Primitive:
    """One primitive with its parameters.

    Attributes:
        action: one of :data:`ACTIONS`.
        side: "left"/"right"/"both" (hand, foot, turn sense or circle sense), or None.
        count: steps (walk/run), repetitions (wave, squat, kick, ...), or None.
        direction: one of :data:`DIRECTIONS`, or None.
        speed: one of :data:`SPEEDS`, or None.
        angle: turn angle in degrees (90 or 180; 360 for a circle), or None.
        start, end: frame range [start, end) in the sample (100 Hz), filled by the generator.
        layer: "body" or "upper" (overlaid on the preceding body primitive).
    """

    action: str
    side: str | None = None
    count: int | None = None
    direction: str | None = None
    speed: str | None = None
    angle: int | None = None
    start: int = 0
    end: int = 0
    layer: str = "body"

    def key(self) -> tuple:
        """The verbalisable parameters as a tuple (action, side, count, direction, speed, angle)."""
        return tuple(getattr(self, f) for f in PARAM_FIELDS)

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> Primitive:
        names = {f.name for f in fields(cls)}
        return cls(**{k: v for k, v in d.items() if k in names})

    def masked(self, keep: set[str]) -> Primitive:
        """A copy that keeps only the parameters in ``keep`` (others None); frames kept."""
        out = Primitive(**asdict(self))
        for f in PARAM_FIELDS[1:]:
            if f not in keep:
                setattr(out, f, None)
        return out


def keys(prims: list[Primitive]) -> list[tuple]:
    return [p.key() for p in prims]
