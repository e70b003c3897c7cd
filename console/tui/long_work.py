"""One long job at a time in a thread worker, with a progress bar, a one-line status and
cancellation (the console's rule: long work never blocks the screen and ``x`` stops it).

A job is a plain function ``job(progress, cancelled) -> result``: it calls
``progress(frac, msg)`` (0..1) as it goes and polls ``cancelled()``, raising any
exception to stop when that returns True. ``LongWork.start`` runs it; the status line
shows the progress, then ``summary(result)``, "NAME cancelled" or the error as one red
line (a ``UserError`` as written, anything else by the console's rule for a bug,
``console.tui.workers``: ``NAME failed: Type: message (details in ...)``, the outputs
stopped); the bar shows
only while a job runs. When it ends,
``LongWork.Finished`` is posted to the parents with the outcome.

While a job runs its line says the time left (``console.tui.time_left``: from the pace
so far) and, once a step reports nothing for a while, how long it has been in it, so a
line never stands still; ``expect(frac, seconds)`` says how long the current step should
take (the bar moves towards ``frac`` meanwhile). The line is wrapped on words, a number
kept with its unit (``console.tui.kept_text``).

A question or refusal said while a job runs (``hold``: "Esc again within 3 s cancels
the training") has a line of its own under the job's: progress never replaces it; it
goes when its window ends, when the job ends (that answers it) or with ``release``.

A timed question on the work's own line (``ask``, or a job whose summary asks:
``start(..., asks_s=...)``, "s again within 20 s to start ...") holds that line as every
screen's question does (``console.tui.question_hold``: ``show`` is the line's one setter
and waits for it): a line said meanwhile, a demo's progress too, shows once it lapses;
new work answers it.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any, Protocol, runtime_checkable

from textual.app import ComposeResult
from textual.containers import Horizontal, Vertical
from textual.message import Message
from textual.widgets import Label, ProgressBar, Static
from textual.worker import get_current_worker

from console.core.errors import UserError
from console.tui.kept_text import wrap_kept
from console.tui.lapse import ask
from console.tui.question_hold import NOTE_S, answered, waits_for_question
from console.tui.said import said_here, screen_name, status_said
from console.tui.time_left import Steady, left_words, seconds_left
from console.tui.util import from_thread
from console.tui.workers import contain, run_worker

#: a step silent this long (s) says how long it has been in it
QUIET_S = 2.0

Progress = Callable[[float, str], None]
Job = Callable[[Progress, Callable[[], bool]], Any]


def stop_check(stop: threading.Event) -> Callable[[], bool]:
    """In a worker thread: True once ``stop`` is set (x) or the console closes the worker.

    A flag rather than ``Worker.cancel`` alone: cancelling a worker whose thread has not
    started yet drops the job without a word."""
    worker = get_current_worker()
    return lambda: stop.is_set() or worker.is_cancelled


class LongWork(Vertical):
    DEFAULT_CSS = """
    LongWork { height: auto; }
    LongWork > .lw-row { height: auto; }
    LongWork ProgressBar { width: auto; margin-right: 1; }
    LongWork .lw-line { width: 1fr; height: auto; }
    LongWork .lw-line.error { color: $error; }
    LongWork > .lw-note { width: 1fr; height: auto; text-style: bold; }
    """

    class Finished(Message):
        """A job ended: ``outcome`` is ``done``, ``cancelled`` or ``failed``."""

        def __init__(self, work: LongWork, name: str, outcome: str, result: Any) -> None:
            super().__init__()
            self.work = work
            self.name = name
            self.outcome = outcome
            self.result = result

    def __init__(self, idle_text: str = "", **kw) -> None:
        super().__init__(**kw)
        self.idle_text = idle_text
        self.name_running: str | None = None
        self.last_name = ""  # of the last job (its error names it once it ended)
        self.outcome: str | None = None  # of the last job
        self.result: Any = None
        self.text = idle_text
        self._stop = threading.Event()
        self._t0 = 0.0  # when the running job started (monotonic s)
        #: the job's last report: (fraction, message, when), and the step's expected end
        #: (fraction, seconds) from ``expect``
        self._report: tuple[float, str, float] | None = None
        self._expect: tuple[float, float] | None = None
        self._shown = 0.0  # the bar's furthest point in the running job
        self._left = Steady()  # the time left shown: steady between reports
        #: the running job's lines say their own time left (a demo's start clock)
        self._timed_by_job = False
        self._ticker = None
        #: a question or refusal held on its own line (``hold``) and its lapse timer
        self.note = ""
        self._note_timer = None
        self._asks: tuple[float, str] | None = None  # the running job's summary asks

    def compose(self) -> ComposeResult:
        bar = ProgressBar(total=1.0, show_eta=False)
        bar.display = False
        with Horizontal(classes="lw-row"):
            yield bar
            yield Label(self.idle_text, markup=False, classes="lw-line")
        # ``hold``: a line of its own (a Static: ``query_one(Label)`` is the job's line)
        note = Static("", markup=False, classes="lw-note")
        note.display = False
        yield note

    @property
    def busy(self) -> bool:
        return self.name_running is not None

    @property
    def cancelling(self) -> bool:
        """A cancel was asked and the job has not stopped yet."""
        return self.busy and self._stop.is_set()

    @property
    def progress(self) -> float | None:
        """The bar's fraction while it shows, else None."""
        bar = self.query_one(ProgressBar)
        return float(bar.progress) if bar.display else None

    @waits_for_question(progress="frac")
    def show(
        self,
        text: str,
        frac: float | None = None,
        *,
        error: bool = False,
        severity: str = "information",
    ) -> None:
        """Status line (and the bar at ``frac``; hidden with None); its news in the log
        once, at ``severity`` (``console.tui.said.status_said``: its ticks not; a
        warning toasted when the screen is hidden); an error by ``error``."""
        self.text = text
        if not error:
            where = screen_name(self, self.name_running or self.last_name or "long work")
            status_said(self, where, text, severity)
        label = self.query_one(".lw-line", Label)
        label.set_class(error, "error")
        self._draw()
        bar = self.query_one(ProgressBar)
        bar.display = frac is not None
        if frac is not None:
            bar.update(total=1.0, progress=frac)

    def ask(self, text: str, after_s: float, then: str = "") -> None:
        """Ask the timed question ``text`` on the work's line: it holds the line
        ``after_s`` seconds (a line said meanwhile shows then, else ``then``)."""
        ask(self, lambda: self.text, text, self.show, after_s, then)

    def _draw(self) -> None:
        """The line, and the held note on its own line under it."""
        label = self.query_one(".lw-line", Label)
        label.update(wrap_kept(self.text, label.size.width))  # "45 MB" never split
        note = self.query_one(".lw-note", Static)
        note.display = bool(self.note)
        note.update(wrap_kept(self.note, note.size.width or self.size.width))

    def hold(self, text: str, seconds: float, severity: str = "warning") -> None:
        """Say ``text`` (a question, a refusal) on its own line under the job's until
        ``seconds`` pass, the job ends or ``release``: progress never replaces it. In
        the log as the screen's ``severity``; a toast when its screen is not in view."""
        self.note = text
        if self._note_timer is not None:
            self._note_timer.stop()
        self._note_timer = self.set_timer(seconds, lambda: self.release(text))
        self._draw()
        where = screen_name(self, self.name_running or self.last_name or "long work")
        said_here(self, where, text, severity)

    def release(self, text: str | None = None) -> None:
        """The held note goes (only when it is still ``text``, if given)."""
        if not self.note or (text is not None and text != self.note):
            return
        self.note = ""
        if self._note_timer is not None:
            self._note_timer.stop()
            self._note_timer = None
        if self.is_attached:
            self._draw()

    def error(self, text: str) -> None:
        """A one-line error on the status line (its one place; in the log too, and a
        toast only when its screen is not in view: ``console.tui.said``)."""
        self.show(text, error=True)
        said_here(self, screen_name(self, self.name_running or self.last_name or "long work"), text)

    def start(
        self,
        name: str,
        job: Job,
        summary: Callable[[Any], str] | None = None,
        *,
        cancelled_says: str = "",
        timed_by_job: bool = False,
        asks_s: float | None = None,
        lapsed: str = "",
    ) -> bool:
        """Run ``job`` in a thread worker; False (and a notice) when one already runs.
        ``cancelled_says``: what a cancel left as it was, said once after "NAME cancelled"
        (": no model was written"); ``timed_by_job``: the job's lines say their time
        left themselves (one estimate on the line, not two); ``asks_s``: the summary is
        a timed question (``ask``), holding the line that long, then ``lapsed``."""
        if self.busy:
            self.say_busy()
            return False
        answered(self)  # new work answers a question on its line
        self._asks = (asks_s, lapsed) if asks_s is not None else None
        self.release()  # new work: an older note is past
        self.name_running = self.last_name = name
        self.outcome = self.result = None
        self._stop = stop = threading.Event()
        self._t0, self._report, self._expect = time.monotonic(), None, None
        self._shown = 0.0  # the bar's furthest point: it never goes back
        self._left.reset()
        self._timed_by_job = timed_by_job
        if self._ticker is None:
            self._ticker = self.set_interval(1.0, self._tick)
        self.show(f"{name} ...", 0.0)
        run_worker(
            self,
            lambda: self._run(name, job, summary, stop, cancelled_says),
            name=name,
            group=f"long-work-{id(self)}",
            thread=True,
        )
        return True

    def say_busy(self) -> None:
        """A key that would start work while a job runs: a line of its own under the
        job's says so for ``NOTE_S`` (``hold``: the job's progress goes on above it)."""
        self.hold(f"{self.name_running} is running: x cancels it", NOTE_S)

    def cancel(self) -> bool:
        """Ask the running job to stop (it stops at its next check).

        A flag rather than ``Worker.cancel``: cancelling a worker whose thread has not
        started yet would drop the job without a word, leaving the work busy for ever."""
        if not self.busy:
            return False
        self._stop.set()
        self.release()  # what it asked is answered
        self.show(f"cancelling {self.name_running} ...", self.progress)
        self._report = None  # the line says the cancel until the job stopped
        return True

    def expect(self, frac: float, seconds: float) -> None:
        """The current step should take about ``seconds`` and end at ``frac``: the bar
        moves towards it meanwhile and the line counts the time down (UI thread)."""
        if self.busy and self._report is not None:
            self._expect = (frac, max(seconds, 0.1))
            self._progress(*self._report[:2], at=self._report[2])

    def on_resize(self) -> None:
        self.show(
            self.text, self.progress, error=self.query_one(".lw-line", Label).has_class("error")
        )

    def _progress(self, frac: float, text: str, at: float | None = None) -> None:
        """A report of the running job (``frac``, its line): the line with the time left."""
        now = time.monotonic()
        report = at is None
        if report:  # a new report: the last one's expectation is past
            self._expect, at = None, now
        self._report = (frac, text, at)
        shown, left = frac, seconds_left(now - self._t0, frac)
        quiet = now - at
        if self._expect is not None:
            end, seconds = self._expect
            shown = frac + (end - frac) * min(quiet / seconds, 0.99)
            rest = seconds_left(now - self._t0, shown)
            left = max(seconds - quiet, 0.0) + (rest or 0.0) * (1 - end) / max(1 - shown, 1e-9)
            if quiet > seconds:  # later than expected: the pace so far, the step's too
                left = rest
        left = self._left.left(left, report)  # counts down; rises by noise at reports only
        # the bar only moves forward (a report below what it showed keeps its place)
        shown = self._shown = max(shown, self._shown)
        if self._timed_by_job:  # its line has its own clock
            self.show(text, shown)
            return
        words = [w for w in (left_words(left),) if w]
        if quiet >= QUIET_S:
            words.append(f"{quiet:.0f} s in this step")
        self.show(text + (f" ({', '.join(words)})" if words else ""), shown)

    def _tick(self) -> None:
        if self.busy and self._report is not None:
            self._progress(*self._report[:2], at=self._report[2])

    # ------------------------------------------------------------------ worker thread
    def _run(
        self, name: str, job: Job, summary, stop: threading.Event, cancelled_says: str = ""
    ) -> None:
        cancelled = stop_check(stop)

        def progress(frac: float, msg: str) -> None:
            if not cancelled():
                self._call(self._progress, max(0.0, min(1.0, frac)), f"{name}: {msg}")

        try:
            result = job(progress, cancelled)
        except Exception as exc:  # noqa: BLE001 - every failure becomes one status line
            if cancelled():
                self._call(self._end, name, "cancelled", None, f"{name} cancelled{cancelled_says}")
            elif isinstance(exc, UserError):
                self._call(self._end, name, "failed", exc, str(exc))
            else:  # a bug: the console's rule (outputs stopped, traceback logged)
                self._call(self._end, name, "failed", exc, contain(self.app, name, exc))
            return
        text = summary(result) if summary is not None else f"{name} done"
        self._call(self._end, name, "done", result, text)

    def _call(self, fn, *args) -> None:
        from_thread(self.app, fn, *args)  # dropped if the app is closing

    def _end(self, name: str, outcome: str, result: Any, text: str) -> None:
        self.name_running = None
        self._report = self._expect = None
        if self._ticker is not None:  # idle: no timer
            self._ticker.stop()
            self._ticker = None
        self.outcome, self.result = outcome, result
        if not self.is_attached:
            return
        self.release()  # the job's end answers what it asked
        asks, self._asks = self._asks, None
        if outcome == "failed":
            self.error(text.splitlines()[0] if text else f"{name} failed")
        elif asks is not None and outcome == "done":
            self.ask(text, *asks)
        else:
            self.show(text)
        self.post_message(self.Finished(self, name, outcome, result))


@runtime_checkable
class RunsWork(Protocol):
    """A pane with work that quitting would stop (a study run): ``work_under_way()``
    says what ('' when none); the console asks before it quits."""

    def work_under_way(self) -> str: ...


@runtime_checkable
class KeepsTypedWork(Protocol):
    """A pane holding typed work nothing has saved (a signal expression):
    ``unsaved_work()`` names it ('' when none); the console asks before it quits."""

    def unsaved_work(self) -> str: ...
