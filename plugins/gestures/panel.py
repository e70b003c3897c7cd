"""The console's Gestures panel (registered as the ``gestures`` panel): the dataset and
model files (where, how big, subjects and repetitions, the model's cross-validated
accuracy from its metadata); synthesize a twin dataset and train + evaluate the
classifier, each in a thread worker with a progress bar, cancelled with ``x``.

Nothing half-written stays behind a cancel: the dataset is written beside its folder
and renamed into place, the model is written to a temporary file and renamed.
"""

from __future__ import annotations

import contextlib
import re
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, VerticalScroll
from textual.screen import ModalScreen
from textual.widgets import Button, Input, Label, Static

from console.plugin_api import UserError, load_profile
from console.plugin_api import data_dir as console_data_dir
from console.plugin_api.tui import (
    ConsoleFooter,
    LongWork,
    NumberField,
    PathField,
    SafetyBar,
    answered,
    from_thread,
    lapse_on_change,
    name_field,
    run_worker,
    said_here,
    short_path,
)

from .jobs import (
    dataset_refusal,
    describe_files,
    model_refusal,
    synth_atomic,
    synth_target,
    train_and_evaluate,
)
from .live_model import use_model
from .model import GestureModel
from .panel_fields import kept_fields
from .panel_text import describe, fold_lines, in_panel, mb
from .settings import model_file
from .synth import estimate as synth_estimate
from .train_ask import train_confirmed

#: seconds in which a second ``s`` starts the synthesis whose size was shown
CONFIRM_S = 20.0
#: the work's line once that question lapsed
ESTIMATE_LAPSED = "the estimate lapsed: s says the size and time again"
#: the final fit on every sample against one cross-validation fold's training (which
#: fits (k-1)/k of the samples): measured on the twin (2fold, 1 subject x 10 x 4 and x 6,
#: a loaded 2-core machine) the final fit took 0.7, 1.1, 1.6 and 7.7 x a fold's mean
#: (median 1.4 = 2^0.5); a step over its estimate says its seconds instead (LongWork)
FINAL_FIT_POWER = 0.5
#: the fields a synthesis's size and time were measured for
_SYNTH_FIELDS = ("gp-dataset", "gp-subjects", "gp-reps")
#: what a cancelled job left as it was (said once, after "NAME cancelled": LongWork)
_CANCELLED_KEPT = {
    "train": ": no model was written",
    "synth": ": the dataset folder is unchanged",
}

#: the panel's buttons (label, id), left to right: one stop of the Tab order
_BUTTONS = (
    ("synthesize (s)", "gp-synth"),
    ("train+eval (t)", "gp-train"),
    ("cancel (x)", "gp-cancel"),
)
#: seconds in which a second ``Esc`` (work under way) cancels it
ESC_AGAIN_S = 3.0
#: seconds a refusal said while work runs stays under its progress
REFUSAL_S = 5.0
#: samples of each gesture training needs: the harmonics and frames are chosen inside
#: each 2-fold training half, which must hold 2 of each (``selection.select_settings``)
MIN_PER_GESTURE = 4


def _does(target: dict[str, Any], ds: Path) -> str:
    """What a synthesis does to the folder ``ds`` (``synth_target``'s ``target``)."""
    where = short_path(ds)
    if not target["replace"]:
        return f"a new dataset in {where}"
    if target.get("samples") is None:
        return f"replaces the synthesized dataset in {where}, not added to"
    subjects = target["subjects"]
    return (
        f"replaces the {target['samples']} samples in {where} ({subjects} "
        f"{'subject' if subjects == 1 else 'subjects'} x {target['reps']} reps), not added to"
    )


def too_few(info: dict[str, Any], cv: str) -> str:
    """Why the dataset ``info`` (``describe_files``'s) is too small to train with ``cv``,
    in the panel's words (its fields, s), or "" when it is big enough or unknown."""
    subjects = len(info.get("subjects") or ())
    gestures, samples = info.get("gestures"), info.get("samples")
    if not subjects or not gestures or not samples:
        return ""
    per = samples // gestures
    reps = per // subjects
    has = (
        f"the dataset has {per} of each gesture ({subjects} "
        f"{'subject' if subjects == 1 else 'subjects'} x {reps} reps)"
    )
    if cv == "loso" and subjects < 2:
        return f"cv loso leaves a subject out and {has}: type 2fold in cv, or more subjects and s"
    if cv == "loso" and subjects == 2 and reps < 2:
        return f"{has}: loso trains on one subject, which needs 2 reps; reps 2 and s make them"
    if cv != "loso" and per < MIN_PER_GESTURE:
        need = -(-MIN_PER_GESTURE // subjects)
        return (
            f"{has}: training chooses its harmonics and frames on half of them and needs "
            f"{MIN_PER_GESTURE}; type {need} in reps and s synthesizes a bigger one"
        )
    return ""


def train_refusal(text: str, info: dict[str, Any], cv: str) -> str:
    """A training error worded for the command line (its switches) said in the panel's
    words: the dataset is too small for what ``cv`` asks."""
    if "--harmonics" in text or "--cv" in text:
        return too_few(info, cv) or (
            "the dataset is too small to choose the harmonics and frames on: raise reps "
            "and s synthesizes a bigger one"
        )
    return text


HELP = (
    "s: synthesize a twin dataset (subjects x 10 gestures x reps) into the dataset folder:\n"
    "   first its size and time and whether it replaces the dataset there, then s again\n"
    "t: train + evaluate (`haptable gestures eval`'s cross-validation, then the model on\n"
    "   every sample, as `haptable gestures train`): first its size and time, then t again\n"
    "x: cancel (nothing half-written stays)   r: refresh   escape: back\n"
    "tab: edit the fields (enter returns here)   left/right: between the buttons\n"
    "PageUp/PageDown: scroll the panel"
)


def data_dir() -> Path:
    """Where the panel keeps twin datasets by default."""
    return console_data_dir("gestures")


def saved_profile(ctx: Any) -> Any:
    """The console's profile read again from its file and override file, as a
    ``haptable`` command started now reads it (the console keeps the one it started
    with); a broken file is the one-line error it would be there."""
    prof = ctx.profile
    return load_profile(prof.path, ctx.pm)


def _same(a: Path | str | None, b: Path | str | None) -> bool:
    """The same file, as typed or resolved."""
    if a is None or b is None:
        return False
    try:
        return Path(a).expanduser().resolve() == Path(b).expanduser().resolve()
    except OSError:
        return str(a) == str(b)


def count(text: str, what: str, lo: int = 1, hi: int = 1000) -> int:
    """A whole number from a field, or a one-line ``UserError`` naming the field."""
    try:
        n = int(text.strip())
    except ValueError:
        n = None
    if n is None or not lo <= n <= hi:
        raise UserError(f"{what} {text.strip()!r}: give a whole number from {lo} to {hi}")
    return n


#: the rows of the screen below left in view: its title row and its tab bar (two rows)
TOP_ROWS = 3


class GesturesPanel(ModalScreen):
    """Datasets and training of the gesture classifier, over the screen it opened on
    below that screen's title row and tab bar (``TOP_ROWS``), which stay in view: where a
    notification shows and which screen this is on (a new operator found them covered)."""

    HELP_TEXT = HELP
    DEFAULT_CSS = (
        (
            "GesturesPanel { background: $background 0%; }\n"  # the screen below shows
            f"GesturesPanel > VerticalScroll {{ margin-top: {TOP_ROWS}; background: $background; }}"
        )
        + """
    GesturesPanel > VerticalScroll { height: 1fr; padding: 0 1; }
    GesturesPanel .gp-row { height: 1; }
    GesturesPanel .gp-row > Label { width: 10; }
    GesturesPanel .gp-row > Input { width: 1fr; }
    GesturesPanel .gp-row > Input.gp-num { width: 8; }
    GesturesPanel #gp-buttons { height: 1; }
    GesturesPanel #gp-buttons > Button { min-width: 10; height: 1; border: none; margin-right: 1; }
    GesturesPanel #gp-files { margin-top: 1; }
    GesturesPanel #gp-result { margin-top: 1; }
    GesturesPanel #gp-work { height: auto; }  /* the estimate's line whole, wrapped */
    """
    )
    BINDINGS = [
        Binding("s", "synth", "synthesize"),
        Binding("t", "train", "train+eval"),
        Binding("x", "cancel", "cancel"),
        Binding("escape", "back", "back"),  # before r: the footer keeps it at 80 columns
        Binding("r", "refresh", "refresh"),
        Binding("question_mark", "help", "help", show=False),
        Binding("left", "button(-1)", "previous button", show=False),
        Binding("right", "button(1)", "next button", show=False),
        Binding("pageup", "page(-1)", "scroll up", show=False),
        Binding("pagedown", "page(1)", "scroll down", show=False),
    ]

    def __init__(self, ctx) -> None:
        super().__init__()
        self.ctx = ctx
        self.default_model = model_file(ctx.profile)
        #: the synthesis the operator was told the size of: (dataset, subjects, reps),
        #: until when ``s`` starts it and what it does to the folder (``synth_target``)
        self._synth_asked: tuple[tuple[Path, int, int], float, dict] | None = None
        self._train_asked: tuple[object, float] | None = None  # the same for t
        self.files: dict[str, Any] = {}
        #: the model whose training result the result block shows (its one place)
        self._result_model: Path | None = None
        #: until when a second Esc cancels the work under way (it asked once)
        self._esc_until: float | None = None
        #: the fields as typed, by id: kept for the console's run (the next panel's)
        self.typed = kept_fields(ctx)

    def compose(self) -> ComposeResult:
        typed = self.typed  # what was typed since the console started, else the defaults
        # not a Tab stop of its own (the first Tab from the buttons edits the first
        # field): PageUp/PageDown scroll it, and a focused field scrolls into view
        with VerticalScroll(can_focus=False):
            yield Static("[b]Gestures[/b]: twin datasets, training and evaluation", id="gp-title")
            with Horizontal(classes="gp-row"):
                yield Label("dataset")
                dataset = typed.get("gp-dataset", short_path(data_dir() / "twin"))
                # a path: kept on focus, every key typed (``?`` too)
                yield PathField(dataset, id="gp-dataset", compact=True, select_on_focus=False)
            with Horizontal(classes="gp-row"):
                yield Label("subjects")
                subjects = typed.get("gp-subjects", "5")
                num = {"classes": "gp-num", "compact": True}
                # each as wide as its longest number: what it shows is what s checks
                yield NumberField(subjects, lo=1, hi=50, id="gp-subjects", **num)
                yield Label(" reps")
                yield NumberField(typed.get("gp-reps", "40"), lo=1, hi=500, id="gp-reps", **num)
                yield Label(" cv")
                yield Input(typed.get("gp-cv", "2fold"), id="gp-cv", classes="gp-num", compact=True)
            with Horizontal(classes="gp-row"):
                yield Label("model")
                model = typed.get("gp-model", short_path(self.default_model))
                yield PathField(model, id="gp-model", compact=True, select_on_focus=False)
            with Horizontal(id="gp-buttons"):
                for label, name in _BUTTONS:
                    button = Button(label, id=name, compact=True)
                    button.can_focus = name == _BUTTONS[0][1]  # the buttons: one Tab stop
                    yield button
            yield LongWork("s: synthesize   t: train + evaluate   x: cancel", id="gp-work")
            yield Static("", id="gp-files")
            yield Static("", id="gp-result")
        yield SafetyBar(id="safety")
        yield ConsoleFooter()  # E-STOP, f1-f10 and ? whatever the width

    def on_mount(self) -> None:
        self.query_one(SafetyBar).show(None)
        for field in self.query(Input):  # named first in the footer while focused
            # Enter and Esc both go back to the buttons (on_input_submitted, action_back)
            name_field(field, field.id.removeprefix("gp-"), enter="buttons", escape="buttons")
        self.to_buttons()
        self.action_refresh()

    def to_buttons(self, name: str | None = None) -> None:
        """Focus the buttons: ``name``, else the one last focused. The buttons are one
        stop of the Tab order (the focusable one of them), so the first Tab from them
        edits the first field and the Tab after the last field comes back to them."""
        buttons = list(self.query("#gp-buttons > Button").results(Button))
        target = next((b for b in buttons if b.id == name or (not name and b.can_focus)), None)
        target = target or buttons[0]
        for b in buttons:
            b.can_focus = b is target
        target.focus()

    def action_page(self, step: int) -> None:
        """PageUp/PageDown: scroll the panel (its files and results below the fold)."""
        scroll = self.query_one(VerticalScroll)
        (scroll.scroll_page_down if step > 0 else scroll.scroll_page_up)()

    def action_button(self, step: int) -> None:
        """Left/Right on the buttons: the previous or next one (the panel's keys s, t
        and x press them from anywhere)."""
        names = [name for _, name in _BUTTONS]
        at = getattr(self.focused, "id", None)
        if at in names:
            self.to_buttons(names[(names.index(at) + step) % len(names)])

    @property
    def work(self) -> LongWork:
        return self.query_one("#gp-work", LongWork)

    def field(self, name: str) -> str:
        return self.query_one(f"#gp-{name}", Input).value

    def paths(self) -> tuple[Path, Path]:
        ds, model = self.field("dataset").strip(), self.field("model").strip()
        if not ds:
            raise UserError("dataset: give a folder, e.g. ~/gestures/twin")
        if not model:
            raise UserError("model: give a file, e.g. gestures.skops")
        return Path(ds).expanduser(), Path(model).expanduser()

    # ------------------------------------------------------------------ actions
    def refuse(
        self, exc: UserError | str, fields: Callable[[], object] = tuple, said: bool = False
    ) -> None:
        """A refusal on the work line (``said``: shown already, a job's) is about the
        fields as they are: once one changes it goes, and what ``fields()`` says of them
        then (another refusal, or the idle line) shows: one rule for the fields' checks
        and the work's (``s`` with a folder it would not write to)."""
        text = str(exc)
        if not said:
            self.work.error(text)

        def verdict() -> str:
            try:
                fields()
            except UserError as now:
                return str(now)
            return ""

        def now_true(_then: str) -> None:
            said = verdict()
            if said:
                self.refuse(UserError(said), fields)
            else:
                self.work.show(self.work.idle_text)

        values = lambda: tuple(f.value for f in self.query(Input))  # noqa: E731
        lapse_on_change(self, lambda: self.work.text, text, now_true, values)

    def action_refresh(self) -> None:
        try:
            ds, model = self.paths()
        except UserError as exc:
            self.refuse(exc, self.paths)
            return
        self.query_one("#gp-files", Static).update("reading the files ...")
        run_worker(
            self,
            lambda: self._describe(ds, model),
            what="reading the files",
            thread=True,
            group="gp-files",
        )

    def _describe(self, ds: Path, model: Path) -> None:
        info = describe_files(ds, model)
        with contextlib.suppress(RuntimeError):  # the console is closing
            from_thread(self.app, self._show_files, info)

    def _show_files(self, info: dict) -> None:
        self.files = info
        below = self._result_model is not None and _same(
            self._result_model, info.get("model", {}).get("path")
        )
        for w in self.query("#gp-files").results(Static):  # none while the panel closes
            w.update(describe(info, evaluation_below=below))

    def action_synth(self) -> None:
        """``s``: first the size and time (measured on one sample of each kind) and what
        becomes of the folder (a new dataset, or the synthesized one there replaced),
        then ``s`` again within ``CONFIRM_S`` seconds, same fields, starts the synthesis,
        which does what was said (a folder changed since: nothing, and it says so)."""
        pending = self._synth_asked
        self._drop_question()  # s again answers it (or asks anew)
        try:
            ds, subjects, reps = self._synth_fields()
        except UserError as exc:
            self.refuse(exc, self._synth_fields)
            return
        if self.work.busy:  # its own line says it (console.tui.said: one place)
            self.work.say_busy()
            return
        self._train_asked = None  # another action: t's question lapses
        asked = (ds, subjects, reps)
        if pending is None or pending[0] != asked or time.monotonic() > pending[1]:
            self._estimate(asked)
            return
        said = pending[2]  # what the question said it does to the folder: it does that

        def job(progress, cancelled):
            try:
                if synth_target(ds) != said:
                    raise UserError(
                        f"{ds}: the dataset folder changed since its size and time were "
                        "said: s says them again"
                    )
                return synth_atomic(
                    ds, subjects, reps, replace=said["replace"], workers=1,
                    progress=progress, cancelled=cancelled,
                )  # fmt: skip
            except UserError as exc:
                raise UserError(in_panel(exc, ds)) from exc

        def summary(info) -> str:
            return (
                f"synthesized {info['samples']} samples ({len(info['subjects'])} x "
                f"{len(info['gestures'])} x {info['reps']}), {mb(info['bytes'])}, "
                f"{info['seconds']:.1f} s"
            )

        self._clear_result()
        self.work.start(
            f"synthesizing {subjects} x 10 x {reps}",
            job,
            summary,
            cancelled_says=_CANCELLED_KEPT["synth"],
        )

    def _synth_fields(self) -> tuple[Path, int, int]:
        """(dataset, subjects, reps) as typed, or a ``UserError`` naming the field."""
        ds, _ = self.paths()
        return ds, self.number("subjects"), self.number("reps")

    def number(self, name: str) -> int:
        """The whole number in field ``name``, checked against the field's own range."""
        f = self.query_one(f"#gp-{name}", NumberField)
        return count(f.value, name, int(f.lo), int(f.hi))

    def _estimate(self, asked: tuple[Path, int, int]) -> None:
        ds, subjects, reps = asked

        def job(progress, cancelled):
            try:  # a folder it would not write to is said before measuring
                target = synth_target(ds)
            except UserError as exc:
                raise UserError(in_panel(exc, ds)) from exc
            progress(0.1, "measuring one static and one dynamic sample")
            return target, synth_estimate(subjects, reps, workers=1)

        def summary(result) -> str:
            target, est = result
            self._synth_asked = (asked, time.monotonic() + CONFIRM_S, target)
            # the key first, then what becomes of the folder: a narrow screen cuts the end
            return f"s again within {CONFIRM_S:.0f} s to start: {_does(target, ds)}: {est['text']}"

        self._clear_result()
        # the question holds the work's line for its 20 s (a line said meanwhile waits)
        self.work.start("estimate", job, summary, asks_s=CONFIRM_S, lapsed=ESTIMATE_LAPSED)

    def _drop_question(self) -> None:
        """The synthesis's question is void (answered, another action, a field changed):
        ``s`` measures again, and the work's line is free at once."""
        self._synth_asked = None
        answered(self.work)

    def action_train(self) -> None:
        self._drop_question()  # another action: the estimate's s-again lapses
        try:
            ds, model, cv = self._train_fields()
        except UserError as exc:
            self.refuse(exc, self._train_fields)
            return
        refused = dataset_refusal(ds) or model_refusal(model)  # as the files block says
        if refused or not ds.is_dir():
            none = f"dataset {short_path(ds)}: none yet, s synthesizes one"
            self.refuse(in_panel(refused, ds, model) or none, self._train_fields)
            return
        known = self.files.get("dataset", {})  # the files block's: too small is said now
        known = known if _same(known.get("path"), ds) else {}
        if too_few(known, cv):
            self.refuse(too_few(known, cv), self._train_fields)
            return
        if not train_confirmed(self, (ds, model, cv), known, CONFIRM_S):  # size, time first
            return
        live = model.resolve() == Path(self.default_model).resolve()

        def job(progress, cancelled):
            progress = self._final_fit_paced(progress)
            # `haptable gestures eval DATASET --cv CV`'s procedure, with its defaults, on
            # the profile as saved (what that command reads: vision settings kept with W
            # on the Camera screen since the console started count)
            profile = saved_profile(self.ctx)
            try:
                res = train_and_evaluate(
                    ds, model, profile=profile, cv=cv, progress=progress, cancelled=cancelled
                )
            except UserError as exc:
                said = in_panel(exc, ds, model)
                if "--" in said:  # a command line's switches: the dataset is too small
                    said = train_refusal(said, describe_files(ds, None).get("dataset", {}), cv)
                raise UserError(said) from exc
            if live:  # the profile's model: the running classifier switches to it
                res["loaded"] = GestureModel.load(res["model"])
            return res

        def summary(res) -> str:  # the numbers: the result block's, once
            return f"trained and evaluated in {time.monotonic() - t0:.0f} s: the result below"

        self._clear_result()
        t0 = time.monotonic()
        self.work.start("training", job, summary, cancelled_says=_CANCELLED_KEPT["train"])

    def _train_fields(self) -> tuple[Path, Path, str]:
        """(dataset, model, cv) as typed, or a ``UserError`` naming the field."""
        ds, model = self.paths()
        cv = self.field("cv").strip().lower()
        if cv not in ("2fold", "loso"):
            raise UserError(f"cv {cv!r}: use 2fold (as in the paper) or loso")
        return ds, model, cv

    def _final_fit_paced(self, progress):
        """``progress`` that, at the fit on every sample (a step with no report of its
        own), tells the work line how long it should take: a fold's training time
        scaled to every sample (``FINAL_FIT_POWER``), so the bar moves and the time
        left counts down."""
        folds: list[float] = []
        state: dict[str, Any] = {}

        def paced(frac: float, msg: str) -> None:
            progress(frac, msg)
            now = time.monotonic()
            m = re.match(r"fold (\d+)/(\d+): (\w+)", msg)
            if m and m.group(3) == "training":
                state["since"], state["k"] = now, int(m.group(2))
            elif m and "since" in state:
                folds.append(now - state.pop("since"))
            elif msg.startswith("training on every") and folds:
                k = max(state.get("k", 2), 2)
                expect_s = sum(folds) / len(folds) * (k / (k - 1)) ** FINAL_FIT_POWER
                from_thread(self.app, self.work.expect, 0.97, expect_s)

        return paced

    def _clear_result(self) -> None:
        """New work: the last result is past (the files block shows its model whole)."""
        self._result_model = None
        self.query_one("#gp-result", Static).update("")

    def action_cancel(self) -> None:
        self._drop_question()
        if not self.work.cancel():
            self.work.show("nothing to cancel")

    def action_back(self) -> None:
        """``Esc``: back to the Camera screen. With work under way it asks first, on the
        work's own line (a second ``Esc`` within ``ESC_AGAIN_S`` cancels the work); the
        panel stays and shows the cancel, so the next keys are still the panel's."""
        if isinstance(self.focused, Input):
            self.to_buttons()
            return
        if not self.work.busy:
            self.app.pop_screen()
            return
        name = self.work.name_running
        if self.work.cancelling:
            self.work.hold(f"cancelling the {name}: Esc goes back once it stopped", REFUSAL_S)
            return
        asked, self._esc_until = self._esc_until, None
        if asked is None or time.monotonic() > asked:
            self._esc_until = time.monotonic() + ESC_AGAIN_S
            question = f"Esc again within {ESC_AGAIN_S:g} s cancels the {name}; x cancels too"
            self.work.hold(question, ESC_AGAIN_S)
            return
        self.action_cancel()

    def leave_for_screen(self) -> bool:
        """An F-key (another screen, ``HapTableApp.action_show_tab``): the panel closes
        and the screen shows; while work runs here it stays and says why (on the work's
        own line, under its progress)."""
        if self.work.busy:
            name = self.work.name_running
            self.work.hold(f"{name} runs here: x cancels it, then the F-key again", REFUSAL_S)
            return False
        self.app.pop_screen()
        return True

    def action_help(self) -> None:
        self.app.notify(HELP, title="Gestures", timeout=10)

    # ------------------------------------------------------------------ events
    def on_button_pressed(self, event: Button.Pressed) -> None:
        event.stop()
        {"gp-synth": self.action_synth, "gp-train": self.action_train}.get(
            event.button.id or "", self.action_cancel
        )()

    def on_input_submitted(self, event: Input.Submitted) -> None:
        event.stop()
        self.to_buttons()  # leaving the field refreshes the files

    def on_input_changed(self, event: Input.Changed) -> None:
        """A field typed in is kept for the next time the panel opens; a synthesis field
        changed under its size and time: the line says they are for other fields now
        (what is true), and ``s`` measures again."""
        if event.input.id:
            self.typed[event.input.id] = event.value
            self._train_asked = None  # t's question was about the fields before
        if event.input.id in _SYNTH_FIELDS and self._synth_asked is not None:
            self._drop_question()
            self.work.show(f"{event.input.id[3:]} changed: s says the size and time again")

    def on_input_blurred(self, event: Input.Blurred) -> None:
        if event.input.id in ("gp-dataset", "gp-model"):
            self.action_refresh()  # the files block follows the fields

    def on_long_work_finished(self, event: LongWork.Finished) -> None:
        if event.outcome == "cancelled":  # x: the work line says it; the log keeps it
            said_here(self.work, "Gestures", self.work.text, "warning")
        elif event.outcome == "failed":  # about the fields it ran with: goes as they change
            self.refuse(self.work.text, said=True)
        if event.outcome == "done" and isinstance(event.result, dict) and "folds" in event.result:
            text = fold_lines(event.result)
            if "loaded" in event.result:
                text += "\n" + use_model(self.app.session, event.result["loaded"])
            self._result_model = Path(event.result["model"])
            self.query_one("#gp-result", Static).update(text)
        self.action_refresh()
