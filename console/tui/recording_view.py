"""A recorded run on the Camera screen (issue 31): ``o`` types a recording's path, then the
view shows its frames instead of the live camera (the live camera is let go: viewing opens
no driver, and a demo holding the camera is not touched), with the recorded contacts (red,
with their ids), each hand as a circle of its recorded size around its centre (green: the
outline itself is not recorded) and the gesture on the side panel. ``space`` plays at the
recorded pace (a new frame shown at most every ``PLAY_PERIOD_S``) or pauses, ``left`` /
``right`` step a frame, ``home`` / ``end`` jump to the first / last, ``escape`` goes back
to the live camera. The file is read through the capability ``ReadsRecordings`` (the
recording plugin's frame-sink factory), in a worker; the view redraws when the frame
shown changes, never on a timer of its own while paused."""

from __future__ import annotations

import math
import time
from types import SimpleNamespace
from typing import Any

import numpy as np
from textual.widgets import Input

from console.core.errors import UserError
from console.core.recording_contracts import ReadsRecordings
from console.core.words import AT_CONSOLE, counted, worded
from console.tui.camera_live import hand_line
from console.tui.checked_field import refused, taken
from console.tui.field_open import opens_field, show_field
from console.tui.path_field import recording_field
from console.tui.recording_keys import REPLAY_KEYS_LINE
from console.tui.text import escape
from console.tui.util import from_thread, short_path
from console.tui.workers import work

#: a playing recording shows a new frame at most this often (as the live view draws)
PLAY_PERIOD_S = 0.2
#: the actions that only act on a recording, and those that only act on the live camera
REPLAY_ACTIONS = {"replay_play", "replay_step", "replay_jump", "replay_live"}
LIVE_ONLY = {
    "tune",
    "tune_chosen",
    "choose",
    "view",
    "calibrate",
    "toggle_output",
    "background",
    "save_tuning",
    "edit_target",
    "exposure",
    "hold_hand",
    "skip_target",
    "save_calibration",
}
NO_READER = "no plugin reads recordings: the recording plugin is not loaded"


def recording_reader(pm: Any) -> Any:
    """The registered frame-sink factory offering ``ReadsRecordings`` (``UserError``: none)."""
    for reg in pm.of("frame_sink").values():
        if isinstance(reg.factory, ReadsRecordings):
            return reg.factory
    raise UserError(NO_READER)


def open_run(pm: Any, path: str) -> Any:
    """The recording at ``path`` (blocking: a worker's), a ``UserError`` line otherwise."""
    if not path.strip():
        raise UserError("no path typed: type a recording's path (an .h5 file), Enter opens it")
    return reader_for(pm, path.strip()).open_recording(path.strip())


def reader_for(pm: Any, path: str, profile: Any = None) -> Any:
    """The first registered ``recording_reader`` that reads ``path`` (a study's trial
    file ...), else the recorder's own reader (whose refusal names the file)."""
    for name in pm.of("recording_reader"):
        reader = pm.built("recording_reader", name, profile)
        if reader.reads(path):
            return reader
    return recording_reader(pm)


#: which recordings have camera frames to show here (a study trial run without the
#: camera records its plans only: those show on Scope)
FRAMES_HINT = (
    "e.g. a demo's (with [recording] enabled = true in the profile) or a study trial "
    "that used the camera: <study folder>/P01/recording/trial_0000.h5"
)


def no_frames_fix(run: Any) -> str:
    """What to do with a recording without frames: its plans show on Scope (a study
    trial that did not see the camera), else another path."""
    try:
        n = sum(1 for p in run.plans() if p.get("kind") == "plan")
    except Exception:  # unreadable plans: nothing to offer but another file
        n = 0
    finally:
        run.close()
    if n:
        return f"its {n} plan{'s' * (n != 1)} show on Scope (F9, o); type another path"
    return "type another path"


def circle(center_px, radius_px: float, n: int = 48) -> np.ndarray:
    """(n, 2) points on a circle: a recorded hand drawn as its centre and size."""
    a = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
    cx, cy = center_px
    return np.stack([cx + radius_px * np.cos(a), cy + radius_px * np.sin(a)], axis=1)


def recorded_work(dec: dict) -> dict:
    """A frame's recorded decisions as the overlay helpers take a live frame's ``work``."""
    contacts = [
        SimpleNamespace(id=int(c[0]), pos_px=tuple(c[1]), pos_mm=c[2]) for c in dec["contacts"]
    ]
    hands = [
        SimpleNamespace(
            contour_px=circle(h["center_px"], float(h["radius_px"])),
            center_mm=h.get("center_mm"),
            finger_count=int(h.get("finger_count", 0)),
            contacts=h.get("contacts"),  # the ids of its contacts (None: not recorded)
        )
        for h in dec.get("hands") or ()
    ]
    return {"contacts": contacts, "hands": hands}


def gesture_words(dec: dict) -> str:
    """The recorded gesture (or the named one) as the live panel says it."""
    g, named = dec.get("gesture"), dec.get("named")
    if g:
        return f"gesture: {escape(g[0])} ({float(g[2]):.2f})"
    if named:
        return f"gesture: {escape(named[0])} ({float(named[1]):.2f})"
    return "gesture: -"


class RecordingMixin:
    """The Camera pane's recording view (mixed into ``CameraPane``)."""

    replay: Any = None  # the open recording (``RecordedRun``) while one shows
    replay_k = 0  # the frame shown (index)
    replay_playing = False
    _replay_t0 = 0.0  # monotonic time of the recording's t = 0 while playing
    _replay_timer: Any = None
    _replay_shown: tuple | None = None  # (k, view size, mode) drawn
    _replay_typed: str | None = None  # a refused path: the field shows it again
    _replay_refused: str | None = None  # ... and why it was refused
    _replay_frame: Any = None  # (k, image, decisions) read for the frame to show

    def on_mount(self) -> None:
        # labelled: what to type; the example on the status line (whole, it wraps there)
        box = recording_field("camera-recording", hint="")
        self.query_one("#camera-side").mount(box, before="#camera-scroll")

    # ------------------------------------------------------------------ keys
    def replay_allows(self, action: str) -> bool:
        """Whether ``action``'s key acts now: none while the path field types; the
        recording's keys only while one shows, the live camera's only while none does."""
        found = self.query("#camera-recording")
        if found and found.first().has_focus:
            return False
        if action in REPLAY_ACTIONS:
            return self.replay is not None
        return not (self.replay is not None and action in LIVE_ONLY)

    @opens_field
    def action_open_recording(self) -> None:
        box = self.query_one("#camera-recording", Input)
        box.value = self._replay_typed or ""
        show_field(box)
        if self._replay_typed and self._replay_refused:  # what was wrong, while it is fixed
            what = self._replay_refused.split(";")[0].split(": type")[0]
            self.say(f"{what}: edit the path, Enter opens it", "warning")
            return
        self.say(f"o: type a recording's path, {FRAMES_HINT}")

    def on_input_submitted(self, event: Input.Submitted) -> None:
        if event.input.id != "camera-recording":
            return
        event.stop()  # open, as typed, until the file opens (``checked_field``)
        self.say(f"o: opening {escape(event.value.strip())} ...")
        self._open_replay(event.value)

    def on_key(self, event) -> None:
        box = self.query_one("#camera-recording", Input)
        if event.key == "escape" and box.has_focus:
            event.stop()
            box.display = False
            self.say("")  # its example goes with it
            self.focus()

    @work(thread=True, exclusive=True, group="camera-replay-open")
    def _open_replay(self, path: str) -> None:
        try:
            run = open_run(self.app.ctx.pm, path)
            k0 = (run, 0, run.frame(0), run.decisions(0)) if run.n_frames else None
        except UserError as exc:
            self._replay_typed, self._replay_refused = path, f"o: {worded(exc, AT_CONSOLE)}"
            from_thread(self.app, self._replay_refused_said, self._replay_refused)
            return
        if k0 is None:
            line = f"o: recording {short_path(run.path)} has no frames: {no_frames_fix(run)}"
            self._replay_typed, self._replay_refused = path, line
            from_thread(self.app, self._replay_refused_said, line)
            return
        from_thread(self.app, self._replay_opened, run, k0)

    def _replay_refused_said(self, line: str) -> None:
        """A refused path: said, its field kept open as typed to correct it."""
        refused(self.query_one("#camera-recording", Input), self)
        self.say(line, "warning")

    def _replay_opened(self, run: Any, first: tuple) -> None:
        if self.replay is not None:
            self.replay.close()
        self._replay_typed = self._replay_refused = None
        taken(self.query_one("#camera-recording", Input), self)
        self.replay, self.replay_k, self.replay_playing = run, 0, False
        self._replay_frame = first[1:]
        self._watch(False)  # the live camera is let go while the recording shows
        self._keys_line(REPLAY_KEYS_LINE)
        self.refresh_bindings()
        name = getattr(run.path, "name", run.path)
        self.say(
            f"{escape(str(name))}: {counted(run.n_frames, 'frame')}; space plays, Esc: live camera"
        )
        self.replay_draw()

    def action_replay_play(self) -> None:
        if self.replay is None:
            return
        self.replay_playing = not self.replay_playing
        if self.replay_playing:
            if self.replay_k >= self.replay.n_frames - 1:
                self.replay_k = 0  # at the end: from the start again
            self._replay_t0 = time.monotonic() - self._t(self.replay_k)
            self._replay_timer = self.set_interval(PLAY_PERIOD_S, self._replay_tick)
            self._replay_load(self.replay_k)
        else:
            self._replay_stop_timer()
            self.replay_draw()

    def _replay_stop_timer(self) -> None:
        if self._replay_timer is not None:
            self._replay_timer.stop()
            self._replay_timer = None

    def _t(self, k: int) -> float:
        t = self.replay.t_capture_s
        return float(t[k] - t[0])

    def _replay_tick(self) -> None:
        """While playing: the frame of the recorded time now; paused at the last one
        (and when the screen is hidden: a hidden screen costs nothing)."""
        run = self.replay
        if run is None or not self.visible_now:
            self.replay_playing = False
            self._replay_stop_timer()
            return
        t = run.t_capture_s
        now = time.monotonic() - self._replay_t0 + float(t[0])
        k = min(int(np.searchsorted(t, now, side="right")) - 1, run.n_frames - 1)
        if k >= run.n_frames - 1:
            self.replay_playing = False
            self._replay_stop_timer()
        self._replay_load(max(k, 0))

    def action_replay_step(self, step: int) -> None:
        if self.replay is not None:
            self._pause()
            self._replay_load(min(max(self.replay_k + step, 0), self.replay.n_frames - 1))

    def action_replay_jump(self, k: int) -> None:
        if self.replay is not None:
            self._pause()
            self._replay_load(k % self.replay.n_frames)

    def _pause(self) -> None:
        self.replay_playing = False
        self._replay_stop_timer()

    def action_replay_live(self) -> None:
        """Back to the live camera: the recording is closed, the camera watched again."""
        run = self.replay
        if run is None:
            return
        self._pause()
        self.replay, self._replay_frame, self._replay_shown = None, None, None
        run.close()
        self._drawn = self._image_frame = self._info_stable = None
        self._said.pop("camera-settings", None)
        self._keys_line(None)
        self.refresh_bindings()
        if self.visible_now:
            self._watch(True)
        self.say("the live camera again (o opens a recording)")

    def _keys_line(self, text: str | None) -> None:
        """The line under the view: the recording's keys, or (``None``) the live ones."""
        # lazy: loaded when this runs, not when the module is imported
        from console.tui.camera_keys import KEYS_LINE  # the live camera's, as composed

        self.query_one("#camera-keys").update(KEYS_LINE if text is None else text)

    @work(thread=True, exclusive=True, group="camera-replay-read")
    def _replay_load(self, k: int) -> None:
        run = self.replay
        if run is None:
            return
        try:
            got = (k, run.frame(k), run.decisions(k))
        except (UserError, OSError, ValueError) as exc:
            from_thread(self.app, self.say, f"frame {k + 1}: {exc}", "warning")
            return
        from_thread(self.app, self._replay_got, run, got)

    def _replay_got(self, run: Any, got: tuple) -> None:
        if run is not self.replay:  # closed or another one opened meanwhile
            return
        self.replay_k = got[0]
        self._replay_frame = got
        self.replay_draw()

    # ------------------------------------------------------------------ drawing
    def replay_draw(self) -> bool:
        """Draw the recording's frame when one shows (True then: the live view is not
        drawn); only when the frame, the size or the play state changed."""
        run, got = self.replay, self._replay_frame
        if run is None:
            return False
        if got is None:
            return True
        k, image, dec = got
        shows = (k, self.view_area(), self.replay_playing, self.image_mode)
        if shows == self._replay_shown:
            return True
        self._replay_shown = shows
        work = recorded_work(dec)
        self._drawn = None  # each frame exactly as recorded (no noise hysteresis)
        if self.image_mode in ("sixel", "kitty"):
            self._image_frame, self._image_at = None, -1e9
            self._draw_graphics(shows, image, work)
        else:
            self._draw_halfblock(shows, image, work)
        state = "playing" if self.replay_playing else "paused"
        self._title(f"recording frame {k + 1}/{run.n_frames}, {self._t(k):.2f} s, {state}")
        self._replay_info(run, k, dec, work)
        return True

    def _replay_info(self, run: Any, k: int, dec: dict, work: dict) -> None:
        lines = [
            f"[b]recording[/b] {escape(short_path(run.path))}",
            f"frame {k + 1}/{run.n_frames}, {self._t(k):.2f} s (seq {int(run.seq[k])})",
            f"hands {len(work['hands'])}  contacts {len(work['contacts'])}",
            gesture_words(dec),
        ]
        lines.extend(hand_line(h) for h in work["hands"][:1])
        plan = dec.get("plan")
        if plan:
            lines.append(f"plan: {escape(str(plan.get('name', '?')))}")
        self._say("camera-info", "\n".join(lines))
        self._say("camera-measures", "")  # the live camera's, not the recording's
        self._say(
            "camera-settings",
            "\n".join(
                [
                    "space: play / pause",
                    "← →: a frame  home end: jump",
                    "o: another file  Esc: live camera",
                    "hands: circle of their size",
                ]
            ),
        )
