"""A status line says what is true now: a line that is true only for a while leaves it
when that while ends.

Three kinds of such lines, one mechanism (``lapse``):

- a question with a time limit ("m again within 5 s ..."): it lapses ``after_s`` seconds
  after it was asked;
- a line true only while a condition holds ("refused: P01's study run holds the
  outputs"): re-checked every ``every_s`` seconds while it is shown (and only then: a
  line no longer shown stops the checks), it lapses once the condition is false;
- a line about a state ("vision settings kept in ...", "subjects 'abc': give a whole
  number"): it lapses once that state changes (``lapse_on_change``).

When it lapses, and only if the line still shows the same text (a newer message keeps
its line), ``replace`` puts what is true now in its place ("" clears it). A question
holds its line until it lapses or is answered (``console.tui.question_hold``: ``replace``
is its screen's status setter, marked ``@waits_for_question``; a line said meanwhile
waits and shows then, in place of ``then``). A question is
kept in view while it is asked (``question_in_view``: after every layout of its screen):
a screen left scrolled down and shown again by the key that asks (the palette's
"Measure vibration map") hid it.
"""

from __future__ import annotations

import time
import weakref
from collections.abc import Callable

from textual.widget import Widget
from textual.widgets import Static

from console.tui.question_hold import answered, held, hold, release, waits, wrote_over

#: how often a conditional line is re-checked while it is shown
RECHECK_S = 0.5


def lapse(
    owner: Widget,
    shown: Callable[[], str],
    text: str,
    replace: Callable[[str], None],
    after_s: float | None = None,
    *,
    while_true: Callable[[], bool] | None = None,
    then: str = "",
    every_s: float = RECHECK_S,
) -> None:
    """Let the status line ``text`` (``shown()`` reads the line now) lapse: after
    ``after_s`` seconds, or once ``while_true()`` is false; ``replace(then)`` writes what
    is true then, unless the line says something else by that time."""
    if after_s is None and while_true is None:
        raise ValueError("lapse needs after_s or while_true")
    ends_s = None if after_s is None else time.monotonic() + after_s
    question = while_true is None
    if question and not waits(replace):
        raise TypeError(
            f"{replace!r} says a timed question: mark it "
            "@waits_for_question (console.tui.question_hold) so that it holds its line"
        )

    def check() -> None:
        if shown() != text:  # a newer message took the line (an answer): nothing to do
            timer.stop()
            if question and release(owner, text) is not None:  # not answered: written over
                wrote_over(owner, text, shown())
            return
        over = ends_s is not None and time.monotonic() >= ends_s
        if over or (while_true is not None and not while_true()):
            timer.stop()
            waited = release(owner, text) if question else None
            if waited is not None and waited.later is not None:
                waited.later()  # the newest line said meanwhile: true now
            else:
                replace(then)

    if question:  # the operator answers what they see: it holds the line, in view
        hold(owner, text)
        question_in_view(owner, text)
    step = every_s if while_true is not None else after_s
    if ends_s is not None and while_true is not None:
        step = min(every_s, after_s)
    timer = owner.set_interval(step, check)


def ask(
    owner: Widget,
    shown: Callable[[], str],
    text: str,
    say: Callable[[str], None],
    after_s: float,
    then: str = "",
) -> None:
    """Ask the timed question ``text`` on ``owner``'s line with ``say`` (its status setter,
    marked ``@waits_for_question``): a question asked before is answered (over), this one
    holds the line for ``after_s`` seconds, then ``then`` (or a line said meanwhile)."""
    answered(owner)
    say(text)
    lapse(owner, shown, text, say, after_s, then=then)


def lapse_on_change(
    owner: Widget,
    shown: Callable[[], str],
    text: str,
    replace: Callable[[str], None],
    state: Callable[[], object],
    then: str = "",
) -> None:
    """A line ``text`` about a state (``state()``, compared with ``==``: settings, a
    field's verdict, the row a cursor is on) lapses once that state is no longer what it
    was when the line was said: ``replace(then)`` says what is true then ("vision
    settings kept in ..." after a setting changed, a field's refusal once it reads)."""
    was = state()
    lapse(owner, shown, text, replace, while_true=lambda: state() == was, then=then)


#: the line each question being kept in view is on, and a token for that question
_KEEPING: weakref.WeakKeyDictionary[Widget, object] = weakref.WeakKeyDictionary()


def question_in_view(owner: Widget, text: str, tries: int = 1) -> None:
    """The line under ``owner`` that shows the question ``text`` (its words, however
    wrapped) scrolled into view in every container that scrolls it, after every layout
    of its screen that leaves none of it in view, while the question holds its line
    (``console.tui.question_hold``).
    After a layout, not after a count of refreshes: a screen shown again by the key that
    asks (the palette's "Measure vibration map", run while the palette still closes) is
    laid out only once it is the current screen again, however many refreshes that
    takes on a loaded machine, and it keeps the scroll it was left with until then."""
    words = " ".join(text.split())
    line = next(
        (w for w in owner.query(Static) if w.display and words in " ".join(str(w.content).split())),
        None,
    )
    if line is None:  # not drawn yet: once more after the next refresh
        if tries > 0:
            owner.call_after_refresh(question_in_view, owner, text, tries - 1)
        return
    screen = owner.screen
    signal = screen.screen_layout_refresh_signal
    mine = _KEEPING[line] = object()  # the line's newest question: an older one stops

    def keep(_screen: object = None) -> None:
        if _KEEPING.get(line) is not mine:
            return
        now = held(owner)
        if now is None or now.text != words or not line.is_attached:
            del _KEEPING[line]
            signal.unsubscribe(line)  # answered, lapsed or gone: the operator scrolls
            return
        if screen.is_current and owner.region and out_of_view(line):  # shown, laid out
            line.scroll_visible(animate=False, immediate=True)

    signal.unsubscribe(line)
    signal.subscribe(line, keep)
    keep()


def out_of_view(line: Widget) -> bool:
    """Whether none of ``line`` shows: laid out, it lies outside what a container around
    it shows (a line partly in view, as one taller than its box, is left where it is;
    one not laid out yet waits for its layout)."""
    region = line.region
    return bool(region) and any(
        isinstance(box, Widget)
        and box.is_scrollable
        and bool(box.region)
        and not box.scrollable_content_region.overlaps(region)
        for box in line.ancestors
    )


HELD_ENDED = "the run that held the outputs has ended: plays work again"


def outputs_held(session) -> bool:
    """Whether a run or a demo holds the outputs now: the session's one check
    (``ConsoleSession.held_why``, read now, not as the output watch last read it), the
    one Relays' line above its rows follows (it goes when the hold ends)."""
    return bool(session.held_why())


def lapse_if_held(
    owner: Widget, session, shown: Callable[[], str], text: str, replace: Callable[[str], None]
) -> None:
    """A refusal ``text`` because a run holds the outputs ("... holds the outputs")
    lapses when the run lets them go (``outputs_held`` false, the check Relays' line
    follows; at the first check if it was over by the time the line showed): the line
    then says plays work again. Any other text: nothing to do."""
    if "holds the outputs" in text:
        lapse(
            owner,
            shown,
            text,
            replace,
            then=HELD_ENDED,
            while_true=lambda: outputs_held(session),
        )
