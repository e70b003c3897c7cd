"""The Camera screen's keys while it shows a recording (``console.tui.recording_view``),
apart so that the screen's key list (``console.tui.camera_keys``) can name them."""

from __future__ import annotations

from textual.binding import Binding

#: the view's keys while a recording shows
REPLAY_BINDINGS = [
    Binding("space", "replay_play", "play"),
    Binding("right", "replay_step(1)", "step", key_display="← →"),
    Binding("left", "replay_step(-1)", "step back", show=False),
    Binding("home", "replay_jump(0)", "jump", key_display="home end"),
    Binding("end", "replay_jump(-1)", "last", show=False),
    Binding("escape", "replay_live", "live camera", key_display="Esc"),
]
#: the line under the view while a recording shows (the live keys' line otherwise)
REPLAY_KEYS_LINE = "space play  ← → step  home end  Esc live"
