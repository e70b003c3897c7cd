"""The Camera screen's vision settings: ``[``/``]`` choose one, ``-``/``+`` (and the
direct keys ``t/T c/C h/H``) change it by one step, its row being the feedback (a step
that would break the thresholds' order is refused, saying why; ``-``/``+`` change no
setting whose row is out of view: its row is shown and the line says the key again
changes it); ``R`` puts every one
back as the profile has it; ``W`` keeps them all for the profile (``W`` again within
3 s: it asks first, naming the saved ones it replaces)."""

from __future__ import annotations

from typing import Any

from console.core.errors import UserError
from console.core.words import listing
from console.tui.ask_again import AskAgain
from console.tui.lapse import lapse_on_change
from console.tui.question_hold import waits_for_question
from console.tui.text import escape
from console.tui.units import control_words
from console.tui.util import from_thread, short_path
from console.tui.workers import work

#: the reset key's words where a setting is refused or may hide the hand
RESET = "R: the profile's settings"


class CameraTuningMixin:
    """The tuning keys of the Camera screen (``CameraPane``: its camera service, its
    status line ``say``, ``_borrowed`` and ``_reveal``)."""

    chosen: int
    service: Any
    _keep_asked: AskAgain | None = None  # W's question (made on its first use)

    def action_tune(self, key: str, sign: int) -> None:
        """Change ``key`` by one step; it becomes the chosen setting: its row (``▸``, the
        new value) is the feedback, scrolled into view (no notification over the panel)."""
        if self._borrowed(key):
            return
        svc = self.service
        cur, rng = svc.params().get(key), svc.param_ranges().get(key)
        if cur is None or rng is None:
            return
        self.chosen = list(svc.params()).index(key)
        try:
            svc.set_param(key, cur + sign * rng.step)
        except UserError as exc:  # the thresholds' order: said, with the way back (the
            self._reveal()  # reply after the row: both keep their rows, ``fit_side``)
            self.say_tuning(f"{exc}; {RESET}", "warning")
            return
        self._reveal()

    def action_reset_tuning(self) -> None:
        """``R``: every setting back as the profile has it (as the vision started, or as
        ``W`` last kept them)."""
        if self._borrowed("R"):
            return
        changed = self.service.reset_params()
        if changed:
            them = "it" if len(changed) == 1 else "them"
            self.say_tuning(f"R: {listing(changed)} back as the profile has {them}")
        else:
            self.say_tuning("R: every setting is as the profile has it")
        self._reveal()

    @waits_for_question
    def say_tuning(self, text: str, severity: str = "information") -> None:
        """``text`` on the status line, answering a tuning key: the chosen setting's row
        stays in view beside it (``fit_side``: ``_answer_at``)."""
        self.say(text, severity)
        self._answer_at = self._spoken_at

    def chosen_key(self) -> str | None:
        keys = list(self.service.params())
        return keys[self.chosen % len(keys)] if keys else None

    def action_choose(self, step: int) -> None:
        keys = list(self.service.params())
        if keys:
            self.chosen = (self.chosen + step) % len(keys)
            self._reveal()

    def action_tune_chosen(self, sign: int) -> None:
        """``-``/``+``: the chosen setting by one step, only while its row (``▸``) is in
        view: else the row is shown and the line says the key again changes it (the
        direct keys, ``t/T c/C h/H``, name their setting: they change it anyway)."""
        key = self.chosen_key()
        if key is None:
            return
        if not self.row_in_view(key):  # never a value changed out of view
            self._reveal()
            self.say_tuning(f"{key} not changed: its row was out of view (▸); again changes it")
            return
        self.action_tune(key, sign)

    def action_save_tuning(self) -> None:
        """``W``: asks first (it overwrites the vision settings saved for the profile);
        ``W`` again within 3 s keeps them (``console.tui.ask_again``)."""
        if self._borrowed("W"):
            return
        if self._keep_asked is None:
            self._keep_asked = AskAgain()
        if self._keep_asked.confirmed("keep"):
            self._save_tuning()
            return
        does = "keeps these vision settings for the profile"
        if self.service.tuning_saved():  # only when some were saved before
            does += " (the saved ones replaced)"
        self._keep_asked.ask(self, "W", does, self._status_shown, self.say_tuning)

    @work(thread=True, exclusive=True, group="camera-tuning")
    def _save_tuning(self) -> None:
        try:
            path = self.service.save_tuning()
        except UserError as exc:
            from_thread(self.app, self.say_tuning, f"W: {exc}", "warning")
            return
        from_thread(self.app, self._said_kept, short_path(path))

    def _said_kept(self, where: str) -> None:
        """``vision settings kept in ...``: true until a setting changes (``t``, ``h``,
        ``+`` ...): the line then says they changed since, not a save they no longer are."""
        svc = self.service
        self.say_tuning(f"vision settings kept in {where}")
        shown = self._status_shown
        then = f"vision settings changed since kept in {where}: W keeps these"

        def tuning() -> tuple:
            return svc.params(), svc.control_values()

        lapse_on_change(self, shown, shown(), self.say, tuning, then=then)

    def settings_lines(self, svc) -> list[str]:
        """The side panel's settings (``▸`` the chosen one), switches and keys."""
        lines: list[str] = []
        cam = self._loop_status(svc)["camera"]
        chosen = self.chosen_key()
        controls = svc.control_values()  # the camera's: in its driver's words
        for k, v in svc.params().items():
            said = control_words(k, v, cam.get("driver", "?")) if k in controls else f"{k} {v:g}"
            lines.append(f"{'▸' if k == chosen else ' '} {escape(said)}")
        if not svc.camera_controls():
            lines.append(f"exposure, gain: not set by the {escape(cam.get('driver', '?'))} driver")
        else:
            lines.append("e: exposure assistant")
        lines += [
            "b: capture background",
            "[ ] - +: tune  W: keep settings",
            "R: the profile's settings",
        ]
        for name in svc.switches():
            on, target = svc.sink_state(name)
            if problem := svc.sink_problem(name):  # on in the profile, not sending: why
                lines.append(
                    f"{escape(name)}: [red]failed[/] -> {escape(target)}: {escape(problem)}"
                )
                continue
            lines.append(f"{name}: {'[green]on[/]' if on else 'off'} -> {escape(target)} (u/U)")
        if not self.wizard_text():  # else the wizard's block says where it stands
            lines.append("k: touch calibration")
        return lines
