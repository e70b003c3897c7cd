"""A timed question holds its status line: it stays until it lapses or is answered.

A question with a time limit ("m again within 5 s ... replaces the kept map") is only
worth asking if it is on screen while it counts: a line said meanwhile on the same
screen (a play that ends, a refusal, progress) would hide it while the key still does
what it asked about. So while a question holds a screen's line (``hold``, done by
``console.tui.lapse.lapse`` for every question), that screen's status setter (marked
``@waits_for_question``) does not show other lines: each is logged at once (the log
view, ``ctrl+l``) and the newest is shown when the question lapses, in place of the
line the question would leave. ``answered`` (the key again, or a new question) lets
the line go at once.
"""

from __future__ import annotations

import functools
import weakref
from collections.abc import Callable
from dataclasses import dataclass
from types import MethodType
from typing import Any, TypeVar

from console.tui.said import log_said, screen_name

F = TypeVar("F", bound=Callable[..., Any])


@dataclass
class Held:
    """The question holding a screen's line and the newest line that waits for it."""

    text: str
    later: Callable[[], None] | None = None


_HOLDS: weakref.WeakKeyDictionary[Any, Held] = weakref.WeakKeyDictionary()
_WAITING: weakref.WeakSet[Callable[..., Any]] = weakref.WeakSet()  # marked setters


def _words(text: object) -> str:
    return " ".join(str(text).split())


def hold(owner: object, text: str) -> None:
    """``text``, a timed question just said on ``owner``'s status line, holds it."""
    _HOLDS[owner] = Held(_words(text))


def held(owner: object) -> Held | None:
    """The question holding ``owner``'s line, or None."""
    return _HOLDS.get(owner)


def release(owner: object, text: str | None = None) -> Held | None:
    """``owner``'s line held no more (only if ``text``, when given, is its question);
    the hold that ended (its ``later``: the line that waited), or None."""
    now = held(owner)
    if now is None or (text is not None and now.text != _words(text)):
        return None
    del _HOLDS[owner]
    return now


def answered(owner: object) -> None:
    """The operator answered ``owner``'s question (its key again, or another question
    asked): the line is free now; a line that waited is dropped (it is in the log)."""
    release(owner)


def waits_for_question(setter: F) -> F:
    """Mark a screen's status setter ``setter(self, text, ...)``: while a question
    holds ``self``'s line, another ``text`` is logged now and shown when it lapses (the
    newest only); the question's own text passes."""

    @functools.wraps(setter)
    def guarded(self: Any, text: str, *args: Any, **kw: Any) -> Any:
        now = held(self)
        if now is None or _words(text) == now.text:
            return setter(self, text, *args, **kw)
        now.later = lambda: setter(self, text, *args, **kw)
        where = screen_name(self, type(self).__name__)
        log_said(f"status {where}", f"{text} (shown once its question lapses)", "information")
        return None

    _WAITING.add(guarded)
    return guarded  # type: ignore[return-value]


def waits(setter: Callable[..., Any]) -> bool:
    """Whether ``setter`` (a bound status setter) waits while a question holds its line."""
    func = setter.__func__ if isinstance(setter, MethodType) else setter
    return func in _WAITING
