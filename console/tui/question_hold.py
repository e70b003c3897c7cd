"""A timed question holds its status line: it stays until it lapses or is answered.

A question with a time limit ("m again within 5 s ... replaces the kept map") is only
worth asking if it is on screen while it counts: a line said meanwhile on the same
screen (a play that ends, a refusal, progress) would hide it while the key still does
what it asked about. So while a question holds a screen's line (``hold``, done by
``console.tui.lapse.lapse`` for every question), that screen's status setter (marked
``@waits_for_question``) does not show other lines: each is logged at once (the log
view, ``ctrl+l``) and the newest is shown when the question lapses, in place of the
line the question would leave. A line answering a key the operator just pressed (not
the question's own key) is also shown at once as a toast: no key goes unanswered.
``answered`` (the key again, or a new question) lets the line go at once.

A line that is not progress (a key's answer, a refusal, news) holds the line the same
way against progress (a setter marked ``@waits_for_question(progress="frac")``: a call
giving that argument is a tick of work) for ``NOTE_S``: the newest tick waits and shows
when the hold ends; a key pressed after the line (the operator moved on), new work's
first line (its progress at 0) or ``answered`` ends it. A measurement's progress never takes a refusal before it was read.

A line written over its question by a path that does not wait (a widget's own setter
called directly, not the marked one) is a bug: the question vanished while its key
still acts. ``lapse`` notices it (the line changed while the question still held it)
and reports it (``wrote_over``: an error in the log, and ``OVERWRITTEN`` for tests).
"""

from __future__ import annotations

import functools
import inspect
import time
import weakref
from collections.abc import Callable
from dataclasses import dataclass
from types import MethodType
from typing import Any, TypeVar

from textual.message_pump import MessagePump

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


#: questions written over behind their hold: (where, the question, the line that replaced
#: it), newest last (tests check it stays empty)
OVERWRITTEN: list[tuple[str, str, str]] = []


def wrote_over(owner: object, question: str, line: str) -> None:
    """``owner``'s question ``question`` was replaced by ``line`` on its status line by a
    setter that does not wait for it (not marked ``@waits_for_question``): said as an
    error in the log, kept in ``OVERWRITTEN``."""
    where = screen_name(owner, type(owner).__name__)
    OVERWRITTEN.append((where, _words(question), _words(line)))
    del OVERWRITTEN[:-20]
    log_said(
        f"status {where}",
        f"a line replaced the question {_words(question)!r} before it lapsed, past its "
        f"hold (its setter is not marked @waits_for_question): {_words(line)!r}",
        "error",
    )


def answered(owner: object) -> None:
    """The operator answered ``owner``'s question (its key again, or another question
    asked): the line is free now; a line that waited is dropped (it is in the log)."""
    release(owner)
    _said_ends(owner)  # new work: its progress is what the line is for


#: seconds a line that is not progress holds its status line against progress
NOTE_S = 5.0


@dataclass
class Said:
    """The last line said on a screen that is not progress, when, and the newest tick
    of progress waiting for its ``NOTE_S`` to end."""

    text: str
    at: float
    later: Callable[[], None] | None = None
    timer: Any = None


_SAID: weakref.WeakKeyDictionary[Any, Said] = weakref.WeakKeyDictionary()


def _tick(setter: Callable[..., Any], progress: str, args: tuple, kw: dict) -> Any:
    """A call of ``setter``'s ``progress`` argument (None, False: not a tick of work)."""
    if not progress:
        return None
    try:
        return inspect.signature(setter).bind(None, "", *args, **kw).arguments.get(progress)
    except TypeError:
        return None


def _tick_waits(owner: Any, text: str, show: Callable[[], None]) -> bool:
    """A tick of progress ``text`` for ``owner``'s line: True (it waits, the newest
    shown when the hold ends) while a line that is not progress holds it."""
    said = _SAID.get(owner)
    if said is None or _words(text) == said.text:
        return False
    left = NOTE_S - (time.monotonic() - said.at)
    if left <= 0 or _key_since(owner, said.at):  # read, or the operator moved on
        _SAID.pop(owner, None)
        return False
    said.later = show
    if said.timer is None and isinstance(owner, MessagePump):
        said.timer = owner.set_timer(left + 0.05, lambda: _tick_shown(owner, said))
    return True


def _said_ends(owner: Any) -> None:
    """``owner``'s line held against progress no more (its waiting tick dropped)."""
    old = _SAID.pop(owner, None)
    if old is not None and old.timer is not None:
        old.timer.stop()


def _tick_shown(owner: Any, said: Said) -> None:
    """``said``'s hold ended: the newest tick that waited shows (if nothing replaced
    ``said`` meanwhile)."""
    if _SAID.get(owner) is not said:
        return
    del _SAID[owner]
    if said.later is not None and held(owner) is None:
        said.later()


def _key_since(owner: Any, at: float) -> bool:
    try:
        return float(owner.app.last_key_s) > at
    except Exception:  # not mounted, or a test's bare app: no key
        return False


def waits_for_question(setter: F | None = None, *, progress: str = "") -> Any:
    """Mark a screen's status setter ``setter(self, text, ...)``: while a question
    holds ``self``'s line, another ``text`` is logged now and shown when it lapses (the
    newest only); the question's own text passes. ``progress`` names its argument that
    makes a call a tick of work: a tick waits ``NOTE_S`` behind a line that is not one."""
    if setter is None:
        return lambda f: waits_for_question(f, progress=progress)

    @functools.wraps(setter)
    def guarded(self: Any, text: str, *args: Any, **kw: Any) -> Any:
        now = held(self)
        value = _tick(setter, progress, args, kw)
        tick = value is not None and value is not False
        if tick and not isinstance(value, bool) and value == 0:  # new work starts: its line
            _said_ends(self)  # (a build the answer's load began, a job started)
            tick = False
        if now is None or _words(text) == now.text:
            if tick and _tick_waits(self, text, lambda: setter(self, text, *args, **kw)):
                return None
            if (value is None or value is False) and progress and _words(text):
                _said_ends(self)
                _SAID[self] = Said(_words(text), time.monotonic())
            return setter(self, text, *args, **kw)
        now.later = lambda: setter(self, text, *args, **kw)
        where = screen_name(self, type(self).__name__)
        log_said(f"status {where}", f"{text} (shown once its question lapses)", "information")
        if _answers_a_key(self):  # the operator's key is answered now, the question kept
            self.app.notify(str(text), severity=_severity(args, kw), timeout=KEY_TOAST_S)
        return None

    _WAITING.add(guarded)
    return guarded


#: a line said this soon after a key answers that key: shown as a toast at once while a
#: question holds the line (the operator pressed another key: it must say something)
KEY_ANSWER_S = 0.5
KEY_TOAST_S = 5.0


def _answers_a_key(owner: Any) -> bool:
    try:
        last = float(owner.app.last_key_s)  # HapTableApp's (``on_event``)
    except Exception:  # not mounted, or a test's bare app: no key to answer
        return False
    return time.monotonic() - last <= KEY_ANSWER_S


def _severity(args: tuple[Any, ...], kw: dict[str, Any]) -> str:
    """The toast's severity from a status setter's arguments (``error=True``,
    ``severity=`` or a severity word given after the text)."""
    if kw.get("error") or (args and args[0] is True):
        return "error"
    for v in (kw.get("severity"), *args):
        if isinstance(v, str) and v in ("error", "warning", "information"):
            return v
    return "information"


def waits(setter: Callable[..., Any]) -> bool:
    """Whether ``setter`` (a bound status setter) waits while a question holds its line."""
    func = setter.__func__ if isinstance(setter, MethodType) else setter
    return func in _WAITING
