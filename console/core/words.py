"""How a message names the fix where the user is: at a shell (``AT_CLI``: the command's
flags) or in the console (``AT_CONSOLE``: its keys, fields and marks).

A refusal that a person fixes differently in each place carries its fix per place
(``Placed``); whoever shows it words it for the place it shows it in
(``worded(exc, AT_CONSOLE)``). ``str()`` of one is the command line's wording, so a
command that prints ``str(exc)`` keeps its flags. A message whose fix is the same
everywhere stays a plain ``UserError``. The Studies plugin words its messages the same
way, with a vocabulary per place (``plugins/studies/words.py``: ``--out`` at a shell,
"folder" on its screen).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from types import MappingProxyType

from console.core.errors import UserError

AT_CLI = "cli"
AT_CONSOLE = "console"
PLACES = (AT_CLI, AT_CONSOLE)

#: how Scenes and Latency both name the outputs a demo played once their plan was
#: computed off the frame loop (no frame's decision scheduled them: Latency's end to end
#: counts none of them; a demo snapshot's ``off_loop``)
OFF_LOOP = "planned outside the frame loop"


class Placed(UserError):
    """A ``UserError`` whose fix depends on where it shows: ``what`` happened, and
    ``fix[place]`` for each place that has one (a place without one gets ``what``
    alone, never another place's fix)."""

    def __init__(self, what: str, fix: Mapping[str, str]) -> None:
        unknown = sorted(set(fix) - set(PLACES))
        if unknown:
            raise ValueError(f"no place {unknown[0]!r}: use one of {', '.join(PLACES)}")
        self.what = what
        self.fix = MappingProxyType(dict(fix))
        super().__init__(self.at(AT_CLI))

    def at(self, where: str) -> str:
        fix = self.fix.get(where)
        return f"{self.what}; {fix}" if fix else self.what


def worded(exc: BaseException, where: str) -> str:
    """``exc`` as one line for ``where`` (``AT_CLI`` or ``AT_CONSOLE``)."""
    return exc.at(where) if isinstance(exc, Placed) else str(exc)


def counted(n: int, word: str) -> str:
    """``1 contact``, ``2 contacts``."""
    return f"{n} {word}" if n == 1 else f"{n} {word}s"


def listing(items: Iterable[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    items = list(items)
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]
