"""The spoken command set: what the chair obeys, as a grammar that both the recogniser
and the typed-command path use.

The thesis (section 4.1.7, appendix A.4) first used single words (forward, reverse,
left, right, stop) and found that they fired on ordinary conversation, then changed to
two-word commands. We keep its two-word commands and add following and going to a
named place of the world:

    drive forward | drive reverse | turn left | turn right | stop | follow me
    | go to the <place>

``<place>`` is any named place of the world but ``start``, spoken with spaces for
underscores (``corridor_east`` is "go to the corridor east"). Every word must be in the
recogniser's pronunciation dictionary; ``THESIS_SINGLE_WORDS`` is the thesis's first set,
kept to measure the finding.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from abcwc.types import Twist

# What each motion command asks for, m/s and rad/s: a walking pace forward, a shuffle
# backward and a gentle turn on the spot, inside the safety filter's ComfortLimits
# (the thesis's A.4 sent the pots to full deflection, 0xFB: about 1.6 m/s).
MOTIONS: dict[str, Twist] = {
    "drive forward": Twist(0.5, 0.0),
    "drive reverse": Twist(-0.2, 0.0),
    "turn left": Twist(0.0, 0.4),
    "turn right": Twist(0.0, -0.4),
    "stop": Twist(0.0, 0.0),
}
FOLLOW = "follow me"
GO_TO = "go to the"
THESIS_SINGLE_WORDS = ("forward", "reverse", "left", "right", "stop")


@dataclass(frozen=True)
class SpokenCommand:
    """A command the chair understood: its ``phrase``, and what it asks for: a ``twist``
    (the motion commands), following (``follow``) or a ``place`` to go to."""

    phrase: str
    twist: Twist | None = None
    follow: bool = False
    place: str | None = None


def place_phrase(place: str) -> str:
    """How a place's name is spoken: lower case, spaces for underscores."""
    return " ".join(place.lower().replace("_", " ").split())


class CommandSet:
    """The phrases the chair obeys, with what each one asks for.

    ``CommandSet(places)`` is the house set (two-word motions, follow me, go to the
    <place> for each of ``places``, a world's ``places`` mapping or a list of names);
    ``CommandSet.from_phrases`` takes any list (the thesis's single words, for one)."""

    def __init__(self, places: Iterable[str] | Mapping[str, object] = ()) -> None:
        commands = [SpokenCommand(p, twist=t) for p, t in MOTIONS.items()]
        commands.append(SpokenCommand(FOLLOW, follow=True))
        for name in places:
            if name == "start":
                continue
            spoken = place_phrase(name)
            if not re.fullmatch(r"[a-z]+( [a-z]+)*", spoken):
                raise ValueError(f"place {name!r} cannot be spoken: use letters and "
                                 f"underscores only")
            commands.append(SpokenCommand(f"{GO_TO} {spoken}", place=name))
        self._commands = {c.phrase: c for c in commands}

    @classmethod
    def from_phrases(cls, phrases: Iterable[str]) -> CommandSet:
        """A set of bare ``phrases``; those of ``MOTIONS`` and the thesis's single words
        keep their motion (forward is drive forward, left is turn left, ...)."""
        single = {"forward": "drive forward", "reverse": "drive reverse",
                  "left": "turn left", "right": "turn right", "stop": "stop"}
        new = cls.__new__(cls)
        new._commands = {}
        for phrase in phrases:
            spoken = " ".join(phrase.lower().split())
            if not spoken:
                raise ValueError("a command phrase is empty")
            twist = MOTIONS.get(spoken, MOTIONS.get(single.get(spoken, ""), None))
            new._commands[spoken] = SpokenCommand(spoken, twist=twist,
                                                  follow=spoken == FOLLOW)
        return new

    @property
    def phrases(self) -> list[str]:
        """Every phrase, in the order they were made."""
        return list(self._commands)

    def __getitem__(self, phrase: str) -> SpokenCommand:
        return self._commands[phrase]

    def __contains__(self, phrase: object) -> bool:
        return phrase in self._commands

    def __len__(self) -> int:
        return len(self._commands)

    def words(self) -> set[str]:
        """Every word the phrases use."""
        return {w for p in self._commands for w in p.split()}

    def jsgf(self) -> str:
        """The set as a JSGF grammar (one public rule: exactly one phrase)."""
        alternatives = " | ".join(self._commands)
        return f"#JSGF V1.0;\ngrammar commands;\npublic <command> = {alternatives};\n"

    def parse(self, text: str) -> SpokenCommand:
        """The command a typed ``text`` names (case, spaces and a final full stop or
        exclamation mark do not matter). Raises ``ValueError`` listing what is allowed
        when the text is not exactly one of the phrases."""
        spoken = " ".join(re.sub(r"[.!?,]+\s*$", "", str(text)).lower().split())
        if spoken in self._commands:
            return self._commands[spoken]
        allowed = ", ".join(f'"{p}"' for p in self._commands)
        raise ValueError(f'"{text}" is not a command; say one of: {allowed}')
