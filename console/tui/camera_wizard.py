"""The Camera screen's touch-calibration wizard and background capture (a mixin of
``CameraPane``): the wizard lives in the session (``console.session.calibration``), the
screen shows its step or result and forwards its keys; ``S`` is in the footer while a
result waits to be saved. ``b`` takes the background from the recent frames, unless a
hand is in any of them (the vision counted one, or a bright blob: held still or passing
through, ``console.session.background_check``): then it asks to take the hands off and
press ``b`` again (``b`` twice within ``BACKGROUND_AGAIN_S`` takes it anyway)."""

from __future__ import annotations

import time
from typing import Any

from console.core.errors import UserError
from console.core.words import counted
from console.session.background_check import describe_in_view
from console.session.calibration import SAVE_KEY, TOPIC
from console.session.events import Failed
from console.tui.lapse import lapse
from console.tui.question_hold import answered
from console.tui.said import log_said, shows_now
from console.tui.text import escape
from console.tui.util import short_path
from console.tui.wrap_paths import break_paths

#: a second ``b`` within this many seconds takes a background with a hand in view
BACKGROUND_AGAIN_S = 3.0


class CameraWizardMixin:
    """Calibration and background keys of the Camera screen."""

    _saved_to: Any = None  # the path S saved the calibration to
    _background_asked = -1e9  # when b last warned of a hand in the background

    def says(self, ev: Any) -> bool:
        """The wizard's refusal (``k`` before the first frame ...) is in this screen's
        panel: no toast of the app's too while the screen is in view (one place)."""
        if isinstance(ev, Failed) and ev.topic == TOPIC and shows_now(self):
            log_said("panel Camera", ev.message, ev.severity)
            return True
        return False

    @property
    def wizard(self):
        """The session's touch-calibration wizard (the pane only shows it)."""
        return self.app.session.calibration

    @property
    def calibration(self):
        return self.wizard.active

    @property
    def cal_result(self):
        return self.wizard.result

    @property
    def unsaved(self) -> bool:
        """A finished calibration waits for ``S`` (its line asks for it)."""
        w = self.wizard
        return w.result is not None and w.message.endswith(SAVE_KEY)

    def side_width(self, widget_id: str) -> int:
        """The cells a line of the side panel's ``widget_id`` has (before layout: the
        panel's least)."""
        found = self._part(widget_id)  # kept: a query matches CSS on every redraw
        width = found.content_region.width if found is not None else 0
        return width if width >= 8 else self.SIDE_COLS - 2

    @property
    def cal_message(self) -> str:
        w = self.wizard
        text = w.message
        if self._saved_to is not None:  # paths shown one way on the screens
            text = text.replace(str(self._saved_to), short_path(self._saved_to))
        text = break_paths(text, self.side_width("camera-wizard"))  # a path whole
        return f"[red]{escape(text)}[/]" if w.failed else escape(text)

    #: a finished result that asks for nothing, said in one line (``short_result``): the
    #: side panel has no room for it whole under newer replies
    _wizard_short = False

    def short_result(self) -> str:
        """A finished calibration's result in one line: ``touch calibration: 12 targets,
        saved to ~/.config/.../touch_calibration.json (k: again)`` (where: as the log)."""
        w = self.wizard
        head = w.message.split(":", 1)[0].strip() if ":" in w.message else ""
        if w.failed:
            said = "failed"
        else:
            saved = ""
            if "saved to " in w.message:
                saved = "saved to " + short_path(w.message.rsplit("saved to ", 1)[1].strip())
            said = ", ".join(p for p in (head, saved) if p)
        said = break_paths(said or "done", self.side_width("camera-wizard"))  # a path whole
        return f"[b]touch calibration[/b]: {escape(said)} (k: again)"

    def wizard_text(self, short: bool | None = None) -> str:
        """The touch-calibration wizard's step or result and the keys it takes ("" when
        it has nothing to say); ``short`` (else as the side panel fits it): a finished
        result that asks for nothing in one line."""
        if self.calibration is None and self.cal_result is None and not self.cal_message:
            return ""
        short = self._wizard_short if short is None else short
        if short and self.calibration is None and not self.unsaved:
            return self.short_result()
        lines = ["[b]touch calibration[/b]", self.cal_message]
        if self.calibration is not None:
            note = self.wizard.projector_note  # where the targets show (a projector?)
            lines += [escape(note)] if note else []
            lines.append("n: skip target  x: cancel")
        return "\n".join(lines)

    def _target_px(self):
        return self.wizard.target_px()

    def action_calibrate(self) -> None:
        if not self._borrowed("k"):
            self.wizard.start()
            self._status_still_true()  # at once: a cancel may follow before a redraw

    def action_skip_target(self, _shown: bool = False) -> None:
        if not self._borrowed("n"):
            self.wizard.skip()
            self._status_still_true()

    def action_cancel(self, _shown: bool = False) -> None:
        if self._assisting is not None:
            self._assisting.set()  # the assistant puts the values back and says so
        elif not self._borrowed("x"):
            self.wizard.cancel()
            self._status_still_true()

    def action_save_calibration(self, _shown: bool = False) -> None:
        if self._borrowed("S"):
            return
        try:
            path = self.wizard.save()
        except UserError as exc:
            self.say(f"S: {exc}", "warning")
            return
        self._saved_to = path
        # the wizard's block says where it was saved (its result whole, no status line
        # repeating it below: at 80 x 24 the two did not fit under the live numbers)
        self.say("")
        self.refresh_bindings()  # S leaves the footer: nothing waits for it

    def _status_shown(self) -> str:
        """What the status line shows now (as ``say`` laid it out)."""
        found = self.query("#camera-status")
        return str(found.first().content) if found else ""

    def action_background(self) -> None:
        """``b``: the background from the recent frames; a hand in any of them (counted
        by the vision, or a bright blob) is named and the background kept as it was,
        unless ``b`` is pressed again within ``BACKGROUND_AGAIN_S``."""
        answered(self)  # b again answers its question (or b asks anew)
        if self._borrowed("b"):
            return
        svc = self.service
        image = svc.median_background()
        if image is None:
            self.say("b: no frames yet: wait for the view, then b again", "warning")
            return
        now = time.monotonic()
        again = now - self._background_asked <= BACKGROUND_AGAIN_S
        found = None if again else svc.hand_in_view(image)
        if found is not None and found.any():
            self._background_asked = now
            self.say(
                f"b: {describe_in_view(found)}: the background is as before: take your "
                f"hands off the glass, then b (b again within {BACKGROUND_AGAIN_S:g} s "
                "takes it anyway)",
                "warning",
            )
            # the question leaves the line when its window ends (``console.tui.lapse``)
            then = "b: the background is as before: take your hands off the glass, then b"
            shown = self._status_shown
            lapse(self, shown, shown(), self.say, BACKGROUND_AGAIN_S, then=then)
            return
        self._background_asked = -1e9
        n = svc.capture_background(image)
        self.say(
            f"background captured from {counted(n, 'frame')}"
            + (" (kept as asked)" if again else "")
        )
