"""The Studies screen (the studies plugin's tab, F10): pick a protocol and a participant,
start, pause, replay, abort; the experimenter's view of progress and the current trial;
analyse the folder's runs (the report written next to them, the ANOVA table shown).

Presentation only: a worker runs ``console_run.run`` (an adaptive protocol:
``adaptive_console.run``, its plot ``adaptive_view``; the participant prepared, the plan
run with the console session's outputs through the safety gate) or
``console_run.run_analysis``; both report through the session (topic ``study``:
``Started``, ``Snapshot`` per step, ``Stopped``, ``Failed``) and this screen shows what it
is told (``on_session_message``). A person answers with the arrow
keys (or 1 = left to right, 2 = right to left in experiment 1) or the answer buttons, a
questionnaire item with 1..7; a simulated participant answers by itself. Stopping a
run for any reason (abort, e-stop, quitting) leaves the trial in flight ``interrupted``;
start again with the same participant to resume at the next trial of the stored plan.
During an e-stop ``s`` is refused on the key (nothing is written). A flow study needs a
vibration map: the status says so before ``s`` when there is none, and the run measures
it first as ``haptable study run`` does (``console_run.study_map``, progress shown).

At 80 x 24 the analysis view shows its title line, the ANOVA table, the notes collapsed
to one line with their count (``o`` shows them all, in the table's place) and the
report's path; the buttons are one line each. An analysis shown while a run writes to
its folder is marked stale, and analysed again when the run stops.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical, VerticalScroll
from textual.widgets import (
    Button,
    DataTable,
    Input,
    Label,
    ProgressBar,
    Select,
    Static,
)

from console.plugin_api import UserError
from console.plugin_api.runtime import Failed, Snapshot, Started, Stopped
from console.plugin_api.tui import (
    AskAgain,
    Choice,
    LiteralTable,
    Pace,
    SessionMessage,
    Tick,
    chosen,
    escape,
    said_here,
    show_keys,
    status_said,
    waits_for_question,
    work,
)

from . import adaptive_console, panel_choice, panel_fit, panel_run_keys, panel_status, refusals
from . import protocol as protocols
from .adaptive_view import AdaptiveView, next_view
from .answer_hold import HeldAnswer
from .console_run import TOPIC, map_hint, run_analysis
from .panel_fields import FieldKeys
from .panel_text import (
    HELP,
    NUMBER_FIELDS,
    default_out,
    field_refusal,
    next_id,
    number_field,
    same_folder,
    space_held,
    status_lines,
)
from .record_switch import RECORD, folder_row, typed_field
from .responders import QueueResponder, parse_key
from .runner import Control
from .trials_table import TrialsTable

ANSWERS = {"up": "up", "down": "down", "left": "left", "right": "right"}
IDLE = "no study running: pick a protocol and a participant, then s"
#: ``s`` during an e-stop, in the console's words for it (``console.session.events``)
ESTOP_REFUSED = "refused: e-stop active, ctrl+r resets"
#: seconds within which a second ``a`` aborts the run
CONFIRM_S = 3.0


class StudiesPane(HeldAnswer, FieldKeys, Vertical):
    #: no Tab stop of its own (it would show nothing focused): its keys work from each of
    #: its fields and buttons, and ``focus()`` gives the focus to Start
    can_focus = False
    DEFAULT_CSS = """
    StudiesPane .study-row { height: 1; }
    StudiesPane .study-row Label { width: auto; padding: 0 1 0 0; }
    StudiesPane .study-row Input { margin-right: 2; }
    StudiesPane .study-row Checkbox { margin-right: 1; }
    StudiesPane #protocol { width: 14; margin-right: 2; }
    StudiesPane #participant { margin-right: 1; }
    StudiesPane #participant { width: 10; }
    StudiesPane #out { width: 1fr; margin-right: 1; }
    StudiesPane #age { width: 5; }
    StudiesPane #sex { width: 10; }
    StudiesPane #handedness { width: 13; }
    StudiesPane #hand_width_cm, StudiesPane #hand_length_cm { width: 6; }
    StudiesPane #study-buttons Button { min-width: 9; margin-right: 1; }
    StudiesPane #study-answers Button { min-width: 5; margin-right: 1; }
    StudiesPane #study-buttons { height: 1; }
    StudiesPane #study-answers { height: 1; }
    StudiesPane #study-status { height: auto; }
    StudiesPane #study-trials { height: 1fr; }
    StudiesPane #study-analysis { height: 1fr; display: none; }
    StudiesPane #analysis-head { height: auto; }
    StudiesPane #study-anova { height: 1fr; }
    StudiesPane #analysis-notes-box { height: 1; overflow-y: hidden; }
    StudiesPane #analysis-notes-box.-open { height: 1fr; overflow-y: auto; }
    StudiesPane #analysis-notes { text-wrap: nowrap; text-overflow: ellipsis; }
    StudiesPane #analysis-notes-box.-open #analysis-notes { text-wrap: wrap; }
    StudiesPane #analysis-report { height: auto; }
    """
    HELP_TEXT = HELP
    BINDINGS = [
        Binding("s", "start", "start"),
        Binding("p", "pause", "pause"),
        Binding("p", "resume", "resume"),  # in its place while paused (``check_action``)
        Binding("r", "replay", "replay"),  # in the footer while a run goes
        Binding("r", "replay_idle", show=False),  # else (``check_action``): says why not
        Binding("a", "abort", "abort"),
        Binding("n", "analyse", "analyse"),  # in the footer while no run goes
        Binding("n", "analyse_in_run", show=False),
        Binding("left_square_bracket", "track(-1)", "track", show=False),
        Binding("right_square_bracket", "track(1)", "track"),  # before t: an adaptive run's
        Binding("t", "toggle_view", "view"),
        Binding("o", "toggle_notes", "notes", show=False),
        Binding("escape", "leave_field", show=False),
        Binding("up", "answer('up')", show=False),
        Binding("down", "answer('down')", show=False),
        Binding("left", "answer('left')", show=False),
        Binding("right", "answer('right')", show=False),
        *(Binding(str(k), f"digit({k})", show=False) for k in range(1, 10)),
    ]

    def work_under_way(self) -> str:
        """What quitting would stop (the console asks first): a participant's run."""
        return f"{self.running}'s study run" if self.running is not None else ""

    def __init__(self, **kw) -> None:
        super().__init__(**kw)
        self.control: Control | None = None
        self.responder: Any = None
        self.running: str | None = None  # the participant being run
        self.asking: dict[str, Any] | None = None
        self.responses: list[str] = []
        self.last: dict[str, Any] = {}
        self.analysed: tuple[Path, str] | None = None  # (folder, experiment) shown
        self.run_out, self.run_study = None, None  # the run going on: folder, protocol
        self.pace = Pace()  # trials done over time: the time left
        self._show_result = True  # the analysis coming in switches to its view
        self.notes: list[str] = []
        self._shown: tuple = ()  # the analysis shown (the same again keeps o's choice)
        self._busy = False  # an analysis under way
        #: until when (monotonic s) a second ``a`` aborts the run; None: not asked
        self.abort_until: float | None = None
        #: the last key's or button's outcome (text, severity): the status's last line
        self.said = ("", "information")
        self._status_text = ""
        self.ask = AskAgain(panel_choice.LONG_AGAIN_S)  # s before a long run

    def compose(self) -> ComposeResult:
        names = protocols.available()
        # one labelled field per value, on rows that fit 80 columns
        with Horizontal(id="study-form", classes="study-row"):
            yield Label("protocol", markup=False)
            yield show_keys(  # its Enter in the footer while it has the focus
                Choice([(n, n) for n in names], id="protocol", compact=True),  # no blank
                enter="protocols",
            )
            yield Label("participant", markup=False)
            yield typed_field("P01", placeholder="id", id="participant")
            yield Tick("simulated", True, id="simulate", compact=True)
            yield Tick("projector", False, id="projector", compact=True)
        yield folder_row(str(default_out(str(names[0]) if names else "")), self.app.session.profile)
        with Horizontal(id="study-person", classes="study-row"):
            yield Label("age", markup=False)
            yield number_field("age")
            yield Label("sex", markup=False)
            yield Input(id="sex", compact=True)
            yield Label("handedness", markup=False)
            yield Input(id="handedness", compact=True)
        with Horizontal(id="study-hand", classes="study-row"):
            yield Label("hand width cm", markup=False)
            yield number_field("hand_width_cm")
            yield Label("hand length cm", markup=False)
            yield number_field("hand_length_cm")
            yield Tick("consent noted", False, id="consent", compact=True)
        with Horizontal(id="study-buttons"):
            yield Button("Start", id="start", variant="primary", compact=True)
            yield Button("Pause", id="pause", compact=True)
            yield Button("Replay", id="replay", compact=True)
            yield Button("Abort", id="abort", variant="error", compact=True)
            yield Button("Analyse", id="analyse", compact=True)
        with Horizontal(id="study-answers"):
            for label, value in (
                ("↑", "up"),
                ("↓", "down"),
                ("←", "left"),
                ("→", "right"),
                ("L→R", "left_to_right"),
                ("R→L", "right_to_left"),
            ):
                # no Tab stops: the arrow keys (and digits) answer from anywhere on the screen
                answer = Button(label, id=f"ans-{value}", classes="answer", compact=True)
                answer.can_focus = False
                yield answer
        yield ProgressBar(total=1, show_eta=False, id="study-progress")
        yield Static(IDLE, id="study-status")
        table = show_keys(TrialsTable(id="study-trials", cursor_type="row"), down="trials")
        for column in ("trial", "what", "response", "correct", "replays", "time"):
            table.add_column(column, key=column)
        yield table
        with Vertical(id="study-analysis"):
            yield Static("", id="analysis-head", markup=False)
            yield show_keys(LiteralTable(id="study-anova", cursor_type="row"), down="analysis")
            with VerticalScroll(id="analysis-notes-box"):
                yield Static("", id="analysis-notes", markup=False)
            yield Static("", id="analysis-report", markup=False)
        yield AdaptiveView(id="study-plot")

    def check_action(self, action: str, parameters: tuple) -> bool:
        """``p`` says what it does now (``pause``, or ``resume`` while paused). At 80
        columns the footer has room for ``]`` (an adaptive protocol's tracks) or ``n``
        (a fixed plan's analysis; an adaptive protocol has none), and for ``r`` (while a
        run goes) or ``n`` (while none does)."""
        if action in ("pause", "resume"):
            return panel_run_keys.p_does(self) == action
        running = self.running is not None
        if action in ("replay", "replay_idle"):  # r where it replays, else quietly
            return running == (action == "replay")
        if action not in ("track", "analyse", "analyse_in_run") or not self.query("#protocol"):
            return True
        if action != "track" and running == (action == "analyse"):
            return False  # n in the footer while no run goes (r takes its place)
        return (action == "track") == adaptive_console.is_adaptive(self._value("protocol"))

    def focus(self, scroll_visible: bool = True):
        """The screen's keys (Esc out of a field, a run started): Start takes the focus,
        the screen's own first stop."""
        self.query_one("#start", Button).focus(scroll_visible)
        return self

    @property
    def focus_target(self) -> Button:
        """Start, focused when the screen shows: the footer lists the screen's keys."""
        return self.query_one("#start", Button)

    def _value(self, wid: str) -> Any:
        """A field's value; the protocol's as text ("" with none: ``chosen``)."""
        w = self.query_one(f"#{wid}")
        return chosen(w.value) if isinstance(w, Select) else w.value

    def on_button_pressed(self, event: Button.Pressed) -> None:
        bid = event.button.id or ""
        event.stop()
        if bid.startswith("ans-"):
            self._answer(bid[4:])
        elif bid in ("start", "pause", "replay", "abort", "analyse"):
            getattr(self, f"action_{bid}")()

    def action_start(self) -> None:
        if self.running is not None:
            self._say(f"{self.running} is running: a twice aborts it", "warning")
            return
        out = self.app.session.outputs
        if out is not None and out.estopped:
            # refused on the key: a run would only write a start and its interruption
            self._say(ESTOP_REFUSED, "error")
            return
        study = self._value("protocol")  # "" with none (``_value``)
        if not study:
            self._say("no protocol in studies/", "error")
            return
        refused = "" if self._value("simulate") else self._bad_number()  # a person's only
        if refused:
            self._say(refused, "error")
            return
        spec = {
            "study": str(study),
            "pid": self._value("participant").strip(),
            "out": Path(self._value("out").strip() or default_out()).expanduser(),
            "simulate": bool(self._value("simulate")),
            "projector": bool(self._value("projector")),
            RECORD: bool(self._value(RECORD)),
            "details": {
                "age": self._value("age").strip() or None,
                "sex": self._value("sex").strip() or None,
                "handedness": self._value("handedness").strip() or None,
                "hand_width_cm": self._value("hand_width_cm").strip() or None,
                "hand_length_cm": self._value("hand_length_cm").strip() or None,
                "consent": True if self._value("consent") else None,
            },
        }
        if panel_choice.asks_first(self, self.ask, spec):  # a long run: s again starts it
            return
        self.control = Control()
        self.responder = None if spec["simulate"] else QueueResponder()
        self.running = spec["pid"]
        refusals.begin(self, spec["pid"])  # what shows stays until the run reports
        try:
            self.responses = adaptive_console.responses_of(str(study))
        except UserError as exc:
            self.running = None
            self._say(str(exc), "error")
            return
        self.said = ("", "information")  # a new run: the last key's outcome is history
        self.run_out, self.run_study = spec["out"], spec["study"]
        self.pace.stop()  # the pace of this run, from its first count
        if self.analysed is not None and same_folder(self.analysed[0], spec["out"]):
            self.query_one("#analysis-head", Static).update(
                f"stale: {spec['pid']}'s run is writing to {spec['out']}; analysed again "
                "when it stops"
            )
        self.query_one(AdaptiveView).reset()
        self._view("plot" if adaptive_console.is_adaptive(str(study)) else "trials")
        self._status(f"{escape(spec['pid'])}: preparing {spec['study']} ...")
        self.focus()
        self._run(spec, self.control, self.responder)

    def _bad_number(self) -> str:
        """The first of the participant's number fields holding what it does not take."""
        for wid in NUMBER_FIELDS:
            refused = field_refusal(wid, self._value(wid))
            if refused:
                return refused
        return ""

    def on_input_changed(self, event: Input.Changed) -> None:
        """A number field refuses what it does not take as it is typed (one line, for a
        person's run); the line goes once the field is right again."""
        wid = event.input.id or ""
        if wid in ("participant", "out"):  # another choice: what the folder holds of it
            return panel_choice.field_changed(self)
        if wid not in NUMBER_FIELDS or self._value("simulate"):  # a simulated one: unused
            return
        refused = field_refusal(wid, event.value)
        if refused:  # true while the field holds it
            self._say(refused, "warning", about=lambda: self._value(wid))
        elif self.said[0].startswith(f"{NUMBER_FIELDS[wid][0]} = "):
            self._say("")

    def action_leave_field(self) -> None:
        """Escape: out of a text field or the closed drop-down, to Start (text stays)."""
        if isinstance(self.app.focused, (Input, Select)):
            self.focus()

    def action_pause(self) -> None:
        panel_run_keys.pause(self)

    def action_resume(self) -> None:
        """``p`` while paused (the footer says ``p resume``)."""
        panel_run_keys.pause(self)

    def action_replay(self) -> None:
        panel_run_keys.replay(self)

    def action_replay_idle(self) -> None:
        """``r`` while no run goes (not in the footer): says there is nothing to replay."""
        panel_run_keys.replay(self)

    def action_abort(self) -> None:
        """``a`` (or Abort): the first asks on the status line, a second within
        ``CONFIRM_S`` seconds aborts the run."""
        if self.control is None or self.running is None:
            self.abort_until = None
            self._say("a: nothing to abort, no study running", "warning")
            return
        now = time.monotonic()
        if self.abort_until is not None and now <= self.abort_until:
            self.abort_until, self.said = None, ("", "information")  # "aborting" says it
            self.control.abort("aborted by the experimenter")
            self._show()  # at once, until the run stopped
            return
        self.abort_until, self.said = now + CONFIRM_S, ("", "information")  # the question
        self._show()
        self.set_timer(CONFIRM_S + 0.05, self._show)  # the question goes when it expires

    def action_analyse_in_run(self) -> None:
        """``n`` while a run goes (not in the footer: ``r`` is)."""
        self.action_analyse()

    def action_analyse(self) -> None:
        study = self._value("protocol")  # "" with none (``_value``)
        if not study:
            self._say("no protocol in studies/", "error")
            return
        try:
            experiment = protocols.load(str(study)).name
        except UserError as exc:
            self._say(str(exc), "error")
            return
        out = Path(self._value("out").strip() or default_out(str(study))).expanduser()
        self._start_analysis(out, experiment)

    def _start_analysis(self, out: Path, experiment: str, why: str = "", show: bool = True) -> None:
        """Analyse ``out`` (``show``: switch to its view, as ``n`` does; after a run: the
        view stays); one under way for the same folder is the one shown."""
        again = self.analysed == (out, experiment) and self._busy
        self.analysed, self._show_result = (out, experiment), show or (again and self._show_result)
        if again:
            return self._view("analysis") if show else None
        self._busy = True  # under way (its result, if the same as shown, keeps o's choice)
        self.query_one("#analysis-head", Static).update(f"analysing {experiment} in {out}{why} ...")
        if show:
            self._view("analysis")
        self._analyse(out, experiment)

    def action_toggle_view(self) -> None:
        now = next(
            v for v in ("analysis", "plot", "trials") if self.query_one(f"#study-{v}").display
        )
        view = next_view(now, self.query_one(AdaptiveView).has_plot)
        if view == "analysis" and self.analysed is None and self.check_action("analyse", ()):
            self.action_analyse()  # nothing analysed yet: the folder's runs, now
            return
        self._view(view)

    def action_track(self, step: int) -> None:
        """``[`` / ``]``: the plot's previous / next track (the plot shown)."""
        why = self.query_one(AdaptiveView).cycle(step)
        self._say(why, "warning") if why else self._view("plot")

    def action_toggle_notes(self) -> None:
        """``o``: the analysis's notes, all of them (in the table's place) or one line."""
        if not self.notes:
            self._say("o: no analysis notes yet (n analyses the folder)", "warning")
            return
        self._view("analysis")
        self._notes(open_=not self.query_one("#analysis-notes-box").has_class("-open"))

    def _notes(self, open_: bool) -> None:
        box = self.query_one("#analysis-notes-box")
        box.set_class(open_, "-open")
        has_rows = self.query_one("#study-anova", DataTable).row_count > 0
        self.query_one("#study-anova").display = has_rows and not open_
        n = len(self.notes)
        if not n:
            text = ""
        elif open_:
            more = "; o shows the table" if has_rows else "; o: one line"
            text = f"notes ({n}{more}):\n" + "\n".join(f"- {x}" for x in self.notes)
        else:
            text = f"{n} note{'s' if n > 1 else ''} (o shows all): {self.notes[0]}"
        self.query_one("#analysis-notes", Static).update(text)

    def _view(self, which: str) -> None:
        """Show the trials table or the analysis in the screen's lower half."""
        self.query_one("#study-analysis").display = which == "analysis"
        self.query_one("#study-trials").display = which == "trials"
        self.query_one("#study-plot").display = which == "plot"

    def on_select_changed(self, event: Select.Changed) -> None:
        """A new protocol: its own default folder, unless the folder was typed."""
        if event.select.id != "protocol" or not chosen(event.value):
            return
        self.refresh_bindings()  # ] or n in the footer (check_action)
        field = self.query_one("#out", Input)
        defaults = {str(default_out())} | {str(default_out(n)) for n in protocols.available()}
        if field.value.strip() in defaults:
            field.value = str(default_out(str(event.value)))
        panel_fit.protocol_changed(self, str(event.value))  # its status, now
        panel_choice.show_choice(self)  # its progress and trials, not the previous one's

    def action_answer(self, key: str) -> None:
        self._answer(ANSWERS.get(key, key), key)

    def action_digit(self, k: int) -> None:
        item = bool(self.asking and "item" in self.asking)
        if item and 1 <= k <= int(self.asking.get("scale", 7)) and self.responder is not None:
            self.asking = None  # one score per item: the next item asks again
            self.responder.put(int(k))
            return
        a = parse_key(str(k), self.responses)  # a keypad: 8 2 4 6 (exp2), 1 2 (exp1)
        self._answer(a.response if a is not None and a.response else None, str(k))

    def _answer(self, value: str | None, key: str = "") -> None:
        panel_run_keys.answer(self, value, key or value or "?")  # or says why not

    @work(thread=True, exclusive=True, group="study", what="the study run")
    def _run(self, spec: dict[str, Any], control: Control, responder: Any) -> None:
        adaptive_console.run(self.app.session, spec, control, responder)

    @work(thread=True, exclusive=True, group="study-analysis", what="the analysis")
    def _analyse(self, out: Path, experiment: str) -> None:
        run_analysis(self.app.session, out, experiment)

    def says(self, ev: Any) -> bool:
        """A run's or an analysis's failure: this screen's status says it (no toast of
        the console's too; one while the screen is not in view: ``said_here``)."""
        return isinstance(ev, Failed) and ev.topic == TOPIC

    def on_session_message(self, message: SessionMessage) -> None:
        ev = message.event
        if ev.topic == "vibration" and isinstance(ev, Started) and self.running is None:
            self._idle()  # a map now: the hint before s goes
            return
        if ev.topic == "estop" and isinstance(ev, Started | Stopped):
            self._estop_changed(reset=isinstance(ev, Started))
            return
        if ev.topic != TOPIC:
            return
        if isinstance(ev, Started):
            refusals.run_began(self)
            self.running = self.last["pid"] = ev.name
            self.refresh_bindings()  # p pauses it
            self._status(f"{escape(ev.name)}: {escape(ev.detail)}")
        elif isinstance(ev, Snapshot):
            self._snapshot(ev.data)
        elif isinstance(ev, Stopped):
            self.running = None
            self.refresh_bindings()  # p: pause, nothing paused any more
            self.asking = None
            self.abort_until = None
            if ev.reason.startswith("refused: "):  # it never began: shown as it was
                return refusals.refused(self, ev.name, ev.reason)
            self.last["pid"] = ev.name
            self.last["stopped"] = ev.reason
            out = self.app.session.outputs  # an e-stop reset before its stop came: said
            panel_status.estop_reset(self.last, out is not None and not out.estopped)
            self.query_one(AdaptiveView).run_stopped()  # "the run is on ..." no more
            if self.said[1] != "error":  # "resumed", "pausing ...": the run's, past now
                self.said = ("", "information")
            if ev.reason.startswith("finished"):  # ready for the next participant
                field = self.query_one("#participant", Input)
                if field.value.strip() == ev.name:
                    with field.prevent(Input.Changed):  # the status stays the run's
                        field.value = next_id(ev.name)
            self._show()
            panel_status.analyse_after_run(self, ev.name)  # t shows it at once
        elif isinstance(ev, Failed):
            said_here(self, "Studies", ev.message, ev.severity)  # the log has it too
            if ev.name == "study analysis":  # not a participant id (a space)
                self._analysis_failed(ev.message)
                return
            self.last["error"] = ev.message

    def _estop_changed(self, reset: bool) -> None:
        """The operator's reset (``reset``): a refusal of ``s`` and the line saying the
        e-stop stopped the run are past, the reset is said in their place; a new e-stop
        brings back what it says (``panel_status.estop_reset``)."""
        if reset and self.said[0] == ESTOP_REFUSED:
            self.said = ("", "information")
        if self.running is None and panel_status.estop_reset(self.last, reset):
            self._show()
        else:
            self._status(self._status_text)

    def _snapshot(self, d: dict[str, Any]) -> None:
        kind = d.get("kind")
        if kind == "analysis":
            self._analysis(d)
            return
        refusals.run_began(self)  # the bar and the trials are the run's now
        if kind in adaptive_console.PLOT_KINDS:
            self.query_one(AdaptiveView).snapshot(d)
        age_s = time.monotonic() - self.said_at
        if panel_status.said_lapses(self.said, kind, age_s):  # the run moved on: past
            self.said = ("", "information")
        elif panel_status.said_lapses(self.said, kind, panel_status.ANSWER_HOLD_S):
            self._past_after_hold(panel_status.ANSWER_HOLD_S - age_s)  # moved on meanwhile
        panel_status.pace_snapshot(self.pace, self.last, kind, d)
        if kind == "progress":
            bar = self.query_one("#study-progress", ProgressBar)
            bar.update(total=max(int(d["total"]), 1), progress=int(d["done"]))
            self.last["done"], self.last["total"] = int(d["done"]), int(d["total"])
        elif kind == "map":
            bar = self.query_one("#study-progress", ProgressBar)
            bar.update(total=100, progress=round(100 * float(d.get("fraction") or 0)))
            self.last["state"] = panel_status.map_state(self.last, d)  # with the time left
        elif kind == "start":
            self.asking = None
            self.last["trial"] = d["trial"]
            self.last["next"] = False
            self.last["state"] = "playing"
        elif kind == "waiting":
            left = d.get("replays_left")
            self.last["state"] = "waiting for the answer (" + (
                "replays unlimited)" if left is None else f"{left} replay(s) left)"
            )
        elif kind == "ask":
            self.asking = {"trial": d["trial"]}
        elif kind == "replay":
            self.asking = None  # answers count once the replay has played
            self.last["state"] = f"replay {d['replays']}"
        elif kind == "refused":  # the experimenter's answer or replay, refused
            self._say(d.get("why", "refused"), "warning")
        elif kind == "earlier":  # a resumed run: the trials done before it
            for r in d.get("records", []):
                self._add_row(r)
        elif kind == "done":
            self.asking = None
            self.last["state"] = "answered"
            self._add_row(d["record"])
        elif kind == "questionnaire":
            self.last["state"] = f"questionnaire after {d['condition']}"
        elif kind == "rate":
            self.asking = {"item": d["item"], "scale": d["scale"]}
            self.last["state"] = f"rate 1..{d['scale']}: {d['item']['text']}"
        elif kind == "paused":
            if isinstance(d.get("trial"), dict):  # the trial that comes, not the last one
                self.last["trial"], self.last["next"] = d["trial"], True
            self.last["state"] = "paused (p resumes)"
            if self.said[0].startswith("pausing"):  # it is paused now: the state says it
                self.said = ("", "information")
        elif kind == "aborted":
            self.last["state"] = f"aborted: {d.get('reason', '')}"
        elif kind == "finished":
            self.last["state"] = "finished"
        self._show()

    def _add_row(self, r: dict[str, Any]) -> None:
        """A done trial's row in the trials table (followed unless the cursor moved)."""
        self.query_one("#study-trials", TrialsTable).add_trial(*panel_status.trial_row(r))

    def _analysis(self, d: dict[str, Any]) -> None:
        panel_status.show_analysis(self, d)

    def _analysis_failed(self, message: str) -> None:
        panel_status.analysis_failed(self, message)

    def _show(self) -> None:
        if self.abort_until is not None and (
            not self.running or time.monotonic() > self.abort_until
        ):
            self.abort_until = None  # the question expired
        c = self.control if self.running else None
        paused, aborting = bool(c and c.paused), bool(c and c.aborted)
        asking = CONFIRM_S if self.abort_until is not None else None
        lines = status_lines(self.last, self.running, paused, asking, aborting)
        self._status("\n".join(lines) + ("" if self.running else self._map_hint()))

    def _status(self, text: str) -> None:
        """The status block (markup) and, last, what became of the last key."""
        self._status_text = text
        said, severity = self.said
        if said and severity == "error":
            text += f"\n[red]{escape(said)}[/]"
        elif said and severity == "warning":
            text += f"\n[yellow]{escape(said)}[/]"
        elif said:
            text += f"\n{escape(said)}"
        self.query_one("#study-status", Static).update(text)

    @waits_for_question
    def _say(self, text: str, severity: str = "information", about: Any = None) -> None:
        """The outcome of the experimenter's key or button on the status (logged, a toast
        while the screen is hidden); a refusal lapses as its ``about`` changes (``tie``)."""
        self.said = (text, severity)
        status_said(self, "Studies", text, severity)  # news logged, an error toasted if hidden
        self._status(self._status_text)
        if text and severity != "information":
            refusals.tie(self, text, about)

    def on_tick_space_held(self, event: Tick.SpaceHeld) -> None:
        self._say(space_held(event.tick.words), "warning")  # where the focus is

    def on_mount(self) -> None:
        panel_fit.mounted(self)  # its dropdown as wide as the names, its status

    def set_visible(self, shown: bool) -> None:
        """Shown again: what the folder holds now of the choice (``shown_again``)."""
        if shown:
            panel_choice.shown_again(self)

    def on_resize(self) -> None:
        panel_fit.fit_protocols(self)  # the first row laid out again at the new width

    def _idle(self) -> None:
        """No run going on: the last run's status (or what to do), and what the chosen
        flow study still needs (a vibration map)."""
        if self.running is not None:
            return
        if self.last:
            self._show()
        else:
            self._status(IDLE + self._map_hint())

    def _map_hint(self) -> str:
        """The status's line about the vibration map the chosen protocol needs, or ""."""
        study = self._value("protocol")  # "" with none (``_value``)
        if not study:
            return ""
        hint = map_hint(self.app.session, str(study))
        return f"\n[yellow]{escape(hint)}[/]" if hint else ""

    def on_unmount(self) -> None:
        if self.control is not None:
            self.control.abort("the console closed")
