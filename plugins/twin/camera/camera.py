"""The streaming camera twin: a ``console.core.contracts.Camera`` driven by a script.

Scripts (``scripts``) say which hands are where at frame ``k``: the empty table, gestures
in turn, touches of given points (touch calibration), held hands.
``TwinCamera.set_target(pos_mm)`` switches to touching one projected target on demand,
like an operator reacting to the projector; ``set_targets([...])`` touches several at
once (one hand each), ``place(gesture, center_mm)`` holds a static hand. A hand that
keeps its shape is moved, not built again (``coherent``): a held hand's tremor moves its
last full render, a turning hand (the knob demo's) its shape's canvas.

Touches land with a realistic error: the contact pad sits a little behind where the
person aims (``bias_mm`` back along the finger) plus a random scatter (``error_mm``
standard deviation per axis). ``camera.truth`` holds the ground truth of the last frame
(contacts in px and mm, hand centre and angle, gesture label, touch target).
Setting ``lights_changed = True`` makes the room lights jump (gain and offset step).
"""

from __future__ import annotations

import collections
import threading
import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from console.plugin_api import Frame, GestureScript, TunableRange

from .coherent import CoherentFrames
from .geometry import TableMapping
from .gestures import GESTURES, plan_take, take_pose
from .hand import hand_pieces, make_subject, scaled_subject
from .render import Rig
from .sample import render_background, render_frame, render_sample
from .scripts import (
    HoldScript,
    IdleScript,
    Script,
    SequenceScript,
    Together,
    TouchScript,
    _Delayed,
    demo_script,
)

#: a reader away this long: the frames meanwhile are ``unread``, not dropped; a reader
#: late by up to CATCH_UP_FRAMES gets them all in order (a driver's queue), later drops
READER_AWAY_S, CATCH_UP_FRAMES = 0.5, 3
#: the sensor's controls, as a camera driver's (``AdjustableCamera``): multipliers on the
#: light before the 8-bit clip (1: the nominal frame); gain never below 1 (as a sensor's)
CONTROLS = {"exposure": TunableRange(0.05, 4.0, 0.05), "gain": TunableRange(1.0, 8.0, 0.25)}
#: where they are kept in the profile
CONTROL_KEYS = {"exposure": "twin_camera.exposure", "gain": "twin_camera.gain"}


class TwinCamera:
    """The IR camera twin: ``read()`` paced at ``fps`` (or as fast as asked when
    ``realtime=False``), ``status()`` with measured fps and dropped frames (those a
    reader missed while reading; frames that passed while nobody read are ``unread``)."""

    def __init__(
        self,
        rig: Rig | None = None,
        script: Script | None = None,
        *,
        fps: float = 60.0,
        realtime: bool = True,
        seed: int = 0,
        subject_seed: int = 0,
        noise: bool = True,
        touch_error_mm: float = 1.5,
        touch_bias_mm: float = 2.0,
        hand_scale: float = 1.0,
        hover_scale: float = 1.0,
        exposure: float = 1.0,
        gain: float = 1.0,
    ) -> None:
        self.rig = rig or Rig()
        self.exposure = CONTROLS["exposure"].clamp(exposure)
        self.gain = CONTROLS["gain"].clamp(gain)
        self.hand_scale, self.hover_scale = hand_scale, hover_scale
        self.fps = float(fps)
        self.realtime = realtime
        self.script: Script = script or IdleScript()
        self._own_script = self.script  # what set_script(None) goes back to
        self.noise = noise
        self.subject_seed = subject_seed
        self.touch_error_mm, self.touch_bias_mm = touch_error_mm, touch_bias_mm
        self._rng = np.random.default_rng(seed)
        self._seed = seed
        self._lock = threading.Lock()
        self._k = 0  # next frame index
        self._t0: float | None = None
        self._dropped = 0  # frames a reader missed while reading (it was late)
        self._unread = 0  # frames that passed while nobody read (not drops)
        self._last_read: float | None = None  # when read() was last called
        self._frames = 0
        self._times: collections.deque[float] = collections.deque(maxlen=61)
        self._closed = False
        self.truth: dict[str, Any] | None = None
        self.lights_changed = False  # a sudden ambient change (gain and offset step)
        self.rate_fps: float | None = None  # frames at most this often (``set_rate``)
        self._stride = 1  # every how many frames of the script's time one is rendered

    def _coherent(self) -> CoherentFrames:
        """The stream's renderer: a hand that keeps its shape is moved (``coherent``);
        made anew when the rig changes."""
        kept = self.__dict__.get("_frames_from")
        if kept is None or kept.rig is not self.rig:
            kept = self._frames_from = CoherentFrames(self.rig)
        return kept

    def __getstate__(self) -> dict[str, Any]:
        """Picklable (``apart``): the lock is made anew, the stream's clock restarts."""
        state = dict(self.__dict__)
        del state["_lock"]
        state.pop("_frames_from", None)  # its kept render: made again there
        state["_t0"] = None
        state["_last_read"] = None
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update({"exposure": 1.0, "gain": 1.0, **state})
        self._lock = threading.Lock()

    # ------------------------------------------------------------------ AdjustableCamera
    def controls(self) -> dict[str, TunableRange]:
        """Exposure and gain: multipliers on the light before the 8-bit clip."""
        return dict(CONTROLS)

    def control_values(self) -> dict[str, float]:
        return {"exposure": self.exposure, "gain": self.gain}

    def control_keys(self) -> dict[str, str]:
        return dict(CONTROL_KEYS)

    def set_control(self, name: str, value: float) -> None:
        """Exposure or gain from the next frame on (kept in its range)."""
        rng = CONTROLS.get(name)
        if rng is None:
            raise ValueError(f"{name!r} is no camera control: use one of {', '.join(CONTROLS)}")
        setattr(self, name, rng.clamp(value))

    @property
    def light(self) -> float:
        """The sensor's exposure x gain (1: the nominal frame)."""
        return self.exposure * self.gain

    def apart(self):
        """This camera (rig, script, state) streaming from its own process, as a camera
        device does (``process.ProcessCamera``): its rendering no longer competes with
        the reader's process for the GIL. This object stays the parent's copy for the
        mapping and offline renders; close the returned camera to end the process."""
        from .process import ProcessCamera  # lazy: the subprocess and shared-memory machinery

        return ProcessCamera(self)

    def set_rate(self, fps: float | None) -> None:
        """Deliver frames at most ``fps`` a second (``None``: every frame, the camera's
        fps; ``0``: none, ``read`` renders nothing until another rate is set): a viewer
        that shows a few frames a second needs no more rendered. The script's time still
        runs at the camera's fps (a gesture lasts as long; the frames' ``seq`` skip the
        ones not rendered, which count as neither dropped nor unread)."""
        if fps is not None and fps <= 0:
            with self._lock:
                self.rate_fps = 0.0
            return
        stride = 1 if fps is None else max(1, int(self.fps // float(fps)))
        with self._lock:
            self.rate_fps = None if stride == 1 else float(fps)
            self._stride = stride

    @property
    def paused(self) -> bool:
        """``set_rate(0)``: no frames wanted."""
        return self.rate_fps == 0.0

    # ------------------------------------------------------------------ scripting
    def set_script(self, script: Script | GestureScript | None) -> None:
        """Show ``script`` from the next frame on: a ``console.core.types.GestureScript``
        (how other plugins script the twin) or one of this module's scripts; ``None``:
        the script the camera was made with (the profile's) again."""
        if script is None:
            script = self._own_script
        elif isinstance(script, GestureScript):
            script = self.sequence(script)
        with self._lock:
            self.script = script

    def sequence(self, script: GestureScript) -> SequenceScript:
        """A ``GestureScript`` as a ``SequenceScript`` on this camera's table and fps."""
        return SequenceScript(
            [(s.gesture, s.subject, s.side, s.frames) for s in script.steps],
            table_mm=self.rig.mapping.table_mm,
            fps=self.fps,
            gap_frames=script.gap_frames,
            loop=script.loop,
            subject_seed=self.subject_seed,
            seed=script.seed,
        )

    @property
    def mapping(self) -> TableMapping:
        """The explicit table mm <-> camera px mapping of this camera."""
        return self.rig.mapping

    def render_sample(
        self,
        gesture: str,
        subject: str,
        rep: int,
        rng: np.random.Generator,
        *,
        n_frames: int | None = None,
        t0_s: float | None = None,
        side: str | None = None,
        subject_seed: int | None = None,
        subject_change: Callable[[Any], Any] | None = None,
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """One performance rendered offline (not on the stream): frames and truth
        (``sample.render_sample`` on this camera's rig and fps, the subject's hand scaled
        by ``hand_scale`` and its lifted parts' heights by ``hover_scale``, then changed
        by ``subject_change`` (a function of the ``hand.Subject``, a frozen dataclass:
        finger widths, lengths, hover ... for a randomised dataset))."""
        seed = self.subject_seed if subject_seed is None else subject_seed
        subj = scaled_subject(make_subject(subject, seed), self.hand_scale, self.hover_scale)
        if subject_change is not None:
            subj = subject_change(subj)
        return render_sample(
            gesture,
            subj,
            rep,
            rng,
            n_frames=n_frames,
            fps=self.fps,
            rig=self.rig,
            side=side,
            t0_s=t0_s,
            subject_seed=seed,
        )

    def render_background(self, t_s: float, rng: np.random.Generator) -> np.ndarray:
        """The empty table at session time ``t_s`` (offline, with this rig's drift)."""
        return render_background(self.rig, t_s, rng)

    def perform(
        self,
        gesture: str,
        subject: str = "s1",
        side: str | None = None,
        n_frames: int | None = None,
        gap_frames: int = 0,
    ) -> int:
        """Perform one gesture from the next frame on; returns its first frame index
        (after ``gap_frames`` of empty table). Used by ``gestures record``."""
        with self._lock:
            seq = SequenceScript(
                [],
                table_mm=self.rig.mapping.table_mm,
                fps=self.fps,
                gap_frames=gap_frames,
                loop=False,
                subject_seed=self.subject_seed,
                seed=int(self._rng.integers(2**31)),
            )
            seq.add(gesture, subject, side, n_frames, at=self._k)
            self.script = seq
            return self._k + gap_frames

    def set_target(
        self,
        pos_mm: tuple[float, float] | None,
        subject: str = "s1",
        side: str = "right",
        reaction_frames: int = 12,
    ) -> None:
        """Show a projected target: the operator's finger touches it after a reaction
        time and stays until the next target (``None``: hands off the table)."""
        pts = [] if pos_mm is None else [pos_mm]
        self.set_targets(pts, subject, [side] * len(pts), reaction_frames)

    def mm_to_px(self, pos_mm: tuple[float, float]) -> tuple[float, float] | None:
        """Where the table point ``pos_mm`` shows in this camera's image (pixels; the
        lens included), as ``console.core.contracts.TouchableCamera`` asks."""
        p = np.asarray(self.rig.mapping.mm_to_px(np.asarray([pos_mm], float)), float)
        x, y = p.reshape(-1, 2)[0]
        return (float(x), float(y))

    def set_targets(
        self,
        points_mm: list[tuple[float, float]],
        subject: str = "s1",
        sides: list[str] | None = None,
        reaction_frames: int = 12,
    ) -> None:
        """Touch several targets at once, one hand each (e.g. the two index fingers of
        the paper's flow experiment). Default sides: the left-most point gets the left
        hand when there are two. ``[]``: hands off the table."""
        pts = [tuple(map(float, p)) for p in points_mm]
        if sides is None:
            sides = ["right"] * len(pts)
            if len(pts) == 2:
                order = sorted(range(2), key=lambda i: pts[i][0])
                sides[order[0]] = "left"
        if len(sides) != len(pts):
            raise ValueError(f"{len(pts)} targets but {len(sides)} hand sides")
        with self._lock:
            if not pts:
                self.script = IdleScript()
                return
            scripts: list[Script] = [
                TouchScript(
                    [p],
                    table_mm=self.rig.mapping.table_mm,
                    subject=subject,
                    side=sd,
                    dwell_frames=10**9,
                    approach_frames=6,
                    gap_frames=0,
                    error_mm=self.touch_error_mm,
                    bias_mm=self.touch_bias_mm,
                    subject_seed=self.subject_seed,
                    seed=int(self._rng.integers(2**31)),
                    loop=False,
                )
                for p, sd in zip(pts, sides, strict=True)
            ]
            script = scripts[0] if len(scripts) == 1 else Together(scripts)
            self.script = _Delayed(script, self._k + reaction_frames)

    def place(
        self,
        gesture: str,
        center_mm: tuple[float, float],
        angle_deg: float = 90.0,
        subject: str = "s1",
        side: str = "right",
    ) -> None:
        """Hold a static gesture with the palm centre at ``center_mm`` (fingers pointing
        ``angle_deg`` in the table frame), e.g. a hand resting on a flow region."""
        if gesture not in GESTURES:
            raise ValueError(f"unknown gesture {gesture!r}; use one of {', '.join(GESTURES)}")
        subj = make_subject(subject, self.subject_seed)
        table = self.rig.mapping.table_mm
        rng = np.random.default_rng(int(self._rng.integers(2**31)))
        take = plan_take(
            gesture, subj, rng, table, side=side, wrist_mm=(0.0, 0.0), angle_deg=angle_deg
        )
        centre = hand_pieces(subj, take_pose(take, 0.0)).center_mm
        d = np.asarray(center_mm, dtype=float) - centre
        take = replace(take, wrist_mm=(float(d[0]), float(d[1])))
        with self._lock:
            self.script = HoldScript([take])

    # ------------------------------------------------------------------ Camera protocol
    def read(self, timeout_s: float = 0.1) -> Frame | None:
        if self._closed:
            return None
        if self.paused:  # nobody wants frames: the time passes unread
            time.sleep(max(timeout_s, 0.0))
            return None
        now = time.monotonic()
        away = self._last_read is not None and now - self._last_read > READER_AWAY_S
        self._last_read = now
        if self.realtime:
            if self._t0 is None:
                self._t0 = now - self._k / self.fps
            elif away:  # nobody read meanwhile (a stopped loop): unread, not dropped
                late = int((now - (self._t0 + self._k / self.fps)) * self.fps)
                if late > 0:
                    self._unread += late
                    self._k += late
                self._t0 = now - self._k / self.fps
            step = self._stride
            due = self._t0 + self._k / self.fps
            wait = due - now
            if wait > timeout_s:
                time.sleep(max(timeout_s, 0.0))
                return None
            if wait > 0:
                time.sleep(wait)
            elif -wait >= (CATCH_UP_FRAMES + 1) * step / self.fps:
                missed = int(-wait * self.fps / step) - CATCH_UP_FRAMES
                self._dropped += missed
                self._k += missed * step
                due = self._t0 + self._k / self.fps
            t_capture = due  # late by fewer: rendered now, the next right after
        else:
            t_capture = now
        with self._lock:
            k = self._k
            self._k += self._stride
            t_s = k / self.fps
            hands, label, extra = self.script.hands(k, t_s, self._rng)
            img, truth = self._coherent().render(
                hands,
                t_s,
                self._rng,
                label=label,
                noise=self.noise,
                step=self.lights_changed,
                light=self.light,
            )
        truth.update(extra)
        truth["seq"] = k
        truth["illumination_step"] = self.lights_changed
        self.truth = truth
        self._frames += 1
        self._times.append(time.monotonic())
        return Frame(image=img, seq=k, t_capture_s=t_capture, source="twin")

    def background(self) -> np.ndarray:
        """The empty table now (for a background capture without lifting the hands)."""
        t_s = self._k / self.fps
        return render_frame(
            [],
            self.rig,
            t_s,
            self._rng,
            noise=self.noise,
            step=self.lights_changed,
            light=self.light,
        )[0]

    def close(self) -> None:
        self._closed = True

    def measured_fps(self) -> float:
        """Frames delivered per second over the last (up to) 60 frames."""
        if len(self._times) < 2 or self._times[-1] <= self._times[0]:
            return 0.0
        return (len(self._times) - 1) / (self._times[-1] - self._times[0])

    def status(self) -> dict[str, Any]:
        return {
            "driver": "twin",
            "fps": round(self.measured_fps(), 2),
            "nominal_fps": self.fps,
            "rate_fps": self.rate_fps,
            "dropped": self._dropped,
            "unread": self._unread,
            "frames": self._frames,
            "realtime": self.realtime,
            "script": getattr(self.script, "name", type(self.script).__name__),
            "size_px": list(self.rig.mapping.image_px),
            "lens_distortion": self.rig.mapping.distorted,
            "closed": self._closed,
            **self.control_values(),
        }


__all__ = [
    "HoldScript",
    "IdleScript",
    "SequenceScript",
    "Together",
    "TouchScript",
    "TwinCamera",
    "demo_script",
]
