"""The Camera screen's keys: its bindings (in the order the footer shows them), the keys
line under the view and its help."""

from __future__ import annotations

from typing import Any

from textual.binding import Binding

from console.core.contracts import AdvisesInField, SimulatedCamera
from console.tui.recording_keys import REPLAY_BINDINGS
from console.tui.refused_keys import RefusedKeys

#: the TUIO target field's label (what it takes) and its keys, on its borders as the
#: recording field (``o``) has them
TARGET_LABEL = "TUIO target: host:port"
TARGET_KEYS = "Enter sets  Esc back"


def advice_in_field(why: str, factory: Any) -> tuple[str, bool]:
    """A switchable sink's refusal ``why`` as it reads while its target field is open:
    the screen's keys it advises (``fix``) replaced by what works from the field
    (``fix_in_field``); True when it was (the advice then says how to leave the field)."""
    if isinstance(factory, AdvisesInField) and factory.fix and factory.fix in why:
        return why.replace(factory.fix, factory.fix_in_field), True
    return why, False


#: the keys under the view: what the footer leaves out at 80 columns (its keys come first)
KEYS_LINE = "g gestures  u U TUIO  b background  W keep"


HELP_TEXT = (
    "b        capture the background (show the empty table)\n"
    "t / T    body threshold down / up      c / C  contact threshold down / up\n"
    "h / H    high-pass blur down / up      v      view: camera, diff, high-pass, body\n"
    "[ / ]    choose a setting (thresholds, smoothing, blob sizes, background, rotation,\n"
    "         mirror, region of interest; exposure and gain where the driver takes them)\n"
    "- / +    change the chosen setting by one step (t/T c/C h/H choose theirs too):\n"
    "         its row (▸) shows the new value and stays in view; the thresholds keep\n"
    "         their order (body below contact below contact_level): a step past it is\n"
    "         refused, saying why\n"
    "R        every vision setting back as the profile has it (as started, or as W kept)\n"
    "e        exposure assistant: with a flat hand on the glass, steps the exposure (then\n"
    "         gain) down until touching skin is below 255; x stops (values as before)\n"
    "P        the twin: hold a flat hand still on its glass (for e) / P again: its\n"
    "         gestures in turn again\n"
    "W        keep every vision setting for this profile (its overrides file): W\n"
    "         again within 3 s (it asks first; it replaces the saved ones, if any)\n"
    "k        touch calibration: touch each target; n skips one; x cancels; S saves\n"
    "g        gestures panel: datasets, training and evaluation\n"
    "u        TUIO (or another switchable output) on / off, kept for the profile\n"
    "U        its target: type host:port, Enter keeps it (Esc: unchanged)\n"
    'o        a recording (Studies\' "record trials" writes them): type its path, Enter shows\n'
    "         its frames instead of the live camera (which is let go): space plays /\n"
    "         pauses, left / right step a frame, home / end jump, Esc: the live camera\n"
    "Overlay: hand outline green, contacts red with their ids, calibration target yellow.\n"
    "The view: Sixel or Kitty graphics where the terminal has them, else half-block\n"
    "(its title says which, and the grey levels shown black and white: the frame's\n"
    'levels are spread over the display\'s). To choose: [console] image = "halfblock",\n'
    '"sixel", "kitty" or "auto" (ask the terminal: the default) in the profile\'s\n'
    "overrides file (its path: Devices, F1), then open the console again; or open it\n"
    "again with haptable console --image halfblock (or sixel, kitty, auto) for once."
)
# in the order of importance: the footer shows as many as fit (whole: at 80 columns
# up to k), the line under the view the rest (``KEYS_LINE``), ? lists them all
BINDINGS = [
    *REPLAY_BINDINGS,  # a recording's keys: only while one shows (``recording_view``)
    # the calibration wizard's keys, first while it runs (x: or the exposure assistant);
    # at other times their hidden bindings below take the keys (a refusal says why)
    Binding("n", "skip_target(True)", "skip target"),
    Binding("x", "cancel(True)", "cancel"),
    Binding("S", "save_calibration(True)", "save calibration"),  # while a result waits
    Binding("plus", "tune_chosen(1)", "change", key_display="- +"),
    Binding("right_square_bracket", "choose(1)", "setting", key_display="[ ]"),
    Binding("v", "view", "view"),
    Binding("k", "calibrate", "calibrate"),
    Binding("g", "gestures_panel", "gestures"),
    Binding("u", "toggle_output", "TUIO"),
    Binding("b", "background", "background"),
    Binding("W", "save_tuning", "keep settings"),
    Binding("U", "edit_target", "TUIO target"),
    Binding("e", "exposure", "exposure"),
    Binding("o", "open_recording", "recording"),
    Binding("P", "hold_hand", "hold hand", show=False),
    Binding("R", "reset_tuning", "profile's settings", show=False),
    Binding("T", "tune('body_threshold', 1)", "body", key_display="t T"),
    Binding("C", "tune('contact_threshold', 1)", "contact", key_display="c C"),
    Binding("H", "tune('highpass_sigma_px', 1)", "high-pass", key_display="h H"),
    Binding("left_square_bracket", "choose(-1)", "previous setting", show=False),
    Binding("minus", "tune_chosen(-1)", "setting -", show=False),
    Binding("t", "tune('body_threshold', -1)", "body -", show=False),
    Binding("c", "tune('contact_threshold', -1)", "contact -", show=False),
    Binding("h", "tune('highpass_sigma_px', -1)", "high-pass -", show=False),
    Binding("n", "skip_target", "skip target", show=False),
    Binding("S", "save_calibration", "save cal.", show=False),
    Binding("x", "cancel", "cancel", show=False),
]


#: the actions that need the camera: refused while a demo holds it (the footer dims them)
NEEDS_CAMERA = frozenset(
    {
        "tune",
        "tune_chosen",
        "choose",
        "view",
        "reset_tuning",
        "save_tuning",
        "calibrate",
        "skip_target",
        "save_calibration",
        "background",
        "toggle_output",
        "edit_target",
        "exposure",
        "hold_hand",
    }
)


def camera_held(holder: str) -> str:
    """Why a key that needs the camera is refused while ``holder`` (a demo) has it."""
    return f"{holder} holds the camera (stop it on Scenes, F6)"


class CameraRefusals(RefusedKeys):
    """The Camera screen's refused keys (``console.tui.refused_keys``): those that need
    the camera while a demo holds it (``service.borrower``); its status line (``say``)
    says why, the footer dims them."""

    service: Any
    _refused_for: str | None = None  # the holder the status line names

    def _borrowed(self, key: str) -> bool:
        """Whether a demo holds the camera (the line then says ``key`` is refused, why)."""
        holder = self.service.borrower
        if holder is None:
            return False
        self._refused_for = holder
        self.say(f"{key} refused: {camera_held(holder)}", "warning")  # type: ignore[attr-defined]
        return True

    def _refusal_still_true(self) -> None:
        """The refusal on the status line is cleared when the camera is back."""
        if self._refused_for is not None and self.service.borrower != self._refused_for:
            self._refused_for = None
            self.say("")  # type: ignore[attr-defined]

    def check_action(self, action: str, parameters: tuple) -> bool | None:
        """While the target field has the focus every key of this screen types into it:
        the footer promises none of them (nor n, x while nothing takes them); a key
        refused now shows dimmed (a demo has the camera)."""
        found = self.query("#camera-target")  # type: ignore[attr-defined]
        busy = self._keys_state()
        typing = found and found.first().has_focus
        shown = self.replay_allows(action) and not typing  # type: ignore[attr-defined]
        return shown and key_shown(action, parameters, *busy) and self.key_dimmed(action)

    def _keys_state(self) -> tuple[bool, bool, bool]:
        """(calibrating, assisting, a calibration waits for S): the footer's keys."""
        s: Any = self
        return (s.calibration is not None, s._assisting is not None, s.unsaved)

    def key_refusal(self, action: str) -> str:
        holder = self.service.borrower
        return camera_held(holder) if holder is not None and action in NEEDS_CAMERA else ""

    def refusal_state(self) -> Any:
        return self.service.borrower

    def say_refused(self, key: str, why: str) -> None:
        self._borrowed(key)  # type: ignore[attr-defined]  # the one wording, the line kept


def key_shown(
    action: str, shown: tuple, calibrating: bool, assisting: bool, unsaved: bool = False
) -> bool:
    """Whether ``action``'s binding is on: its footer entry (``shown``: ``(True,)``) for
    ``n`` while the calibration runs, for ``x`` while it or the exposure assistant runs,
    for ``S`` while a finished calibration waits to be saved; every other binding always."""
    if not shown:
        return True
    if action == "skip_target":
        return calibrating
    if action == "cancel":
        return calibrating or assisting
    if action == "save_calibration":
        return unsaved
    return True


#: cameras whose hand ``P`` holds still (``P`` again: its gestures in turn)
_HELD: set[int] = set()


def hold_hand(svc: Any) -> tuple[str, str]:
    """``P``: the twin holds a flat hand still at the glass's centre (for ``e``), or
    goes back to what its hand did before; (the status line, its severity)."""
    cam = svc.camera
    if not isinstance(cam, SimulatedCamera):
        return "P: only the twin holds a hand on the glass: put your own flat hand on it", "warning"
    if id(cam) in _HELD:
        _HELD.discard(id(cam))
        cam.set_script(None)
        return (
            "P: the twin's hand goes back to its gestures in turn (P holds it again)",
            "information",
        )
    _HELD.add(id(cam))
    w, h = cam.mapping.table_mm
    cam.place("open_hand", (w / 2, h / 2))
    return (
        f"P: a flat hand held still on the twin's glass at {w / 2:.0f},{h / 2:.0f} mm: "
        "e measures it; P again: its gestures in turn",
        "information",
    )
