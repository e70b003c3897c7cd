"""The word meant, for a word mistyped: every "did you mean" of the console comes from here.

Matching ignores case (``sine-pa`` means ``sine-PA``, ``PLAY`` means ``play``) and the
suggestion is the name as it is written. tests/console/test_suggestions.py checks that
no other module calls ``difflib.get_close_matches``.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable

__all__ = ["did_you_mean", "suggestion"]

#: how alike a word and a name must be (``difflib``'s ratio) to be suggested
CUTOFF = 0.6


def did_you_mean(word: str, names: Iterable[str], *, cutoff: float = CUTOFF) -> str | None:
    """The name in ``names`` ``word`` most likely meant, as written there, or None.

    A name equal to ``word`` but for case wins; else the closest by ``difflib``'s ratio
    on the lower-cased words (at least ``cutoff``)."""
    if not isinstance(word, str) or not word:
        return None
    by_lower: dict[str, str] = {}
    for name in names:
        by_lower.setdefault(str(name).lower(), str(name))
    key = word.lower()
    if key in by_lower:
        return by_lower[key]
    close = difflib.get_close_matches(key, list(by_lower), n=1, cutoff=cutoff)
    return by_lower[close[0]] if close else None


def suggestion(word: str, names: Iterable[str], template: str = " (did you mean {!r}?)") -> str:
    """``template`` with the name meant (``" (did you mean 'sine-PA'?)"``), or ``""``."""
    meant = did_you_mean(word, names)
    return template.format(meant) if meant is not None else ""
