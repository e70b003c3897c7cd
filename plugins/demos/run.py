"""Start and stop a demo: camera, vision, gestures, the demo's stages, watchdog, TUIO.

``start_demo("flow"|"knob", profile, plugins, outputs, **params) -> DemoRun`` is what the
console and ``haptable demo`` call; ``DemoRun.stop()`` ends it (outputs ramp down or
finish their plan; the camera is closed if the run opened it); ``DemoRun.snapshot()``
is the latency monitor and the demo's state as JSON values.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from console.plugin_api import (
    AdjustableCamera,
    BeginsRun,
    UserError,
    WatchesOutputs,
    summarize_s,
)
from console.plugin_api.runtime import (
    FrameLoop,
    LatencyMonitor,
    VisionStage,
    Watchdog,
    learn_background,
    measured_map_file,
    open_camera,
    open_classifier,
)

from .adapters import flow_renderers
from .flow import FlowDemo
from .knob import KnobDemo
from .planner import PlanProcess
from .script import script_twin

log = logging.getLogger("haptable.demos")

DEMOS = ("flow", "knob")


def open_frame_sinks(profile: Any, plugins: Any, *, force: dict[str, bool] | None = None):
    """Every registered frame sink the profile enables (``haptable_register_frame_sinks``).

    ``force`` maps sink names to True (open even if the profile leaves it off) or False
    (leave it closed even if enabled)."""
    force = force or {}
    regs = plugins.of("frame_sink")
    missing = sorted(n for n, on in force.items() if on and n not in regs)
    if missing:
        known = ", ".join(sorted(regs)) or "none"
        raise UserError(
            f"frame sink {missing[0]!r}: no plugin registers it (registered: {known}); "
            "install or unblock the plugin that provides it"
        )
    sinks = []
    for name, reg in sorted(regs.items()):
        if force.get(name) is False:
            continue
        sink = reg.factory(profile, force=bool(force.get(name)))
        if sink is not None:
            sinks.append(sink)
    return sinks


@dataclass
class DemoRun:
    """A running demo. ``stop()`` is safe to call twice."""

    name: str
    demo: Any
    loop: FrameLoop
    watchdog: Watchdog
    camera: Any
    owns_camera: bool
    outputs: Any
    sinks: list = field(default_factory=list)
    t_start_s: float = field(default_factory=time.monotonic)
    stopped: bool = False

    @property
    def monitor(self) -> LatencyMonitor:
        return self.loop.monitor

    def stop(self) -> None:
        if self.stopped:
            return
        self.stopped = True
        self.watchdog.stop()
        self.loop.stop()
        try:
            self.demo.stop()
        finally:
            for s in self.sinks:
                close = getattr(s, "close", None)
                if close:
                    try:
                        close()
                    except Exception:
                        log.exception("sink close failed")
            if self.owns_camera:
                self.camera.close()

    def snapshot(self) -> dict:
        """Latency monitor, watchdog, demo state and camera status (JSON values)."""
        try:
            cam = self.camera.status()
        except Exception as exc:
            cam = {"error": repr(exc)}
        out = {
            "demo": self.name,
            "running": not self.stopped and self.loop.running,
            "uptime_s": round(time.monotonic() - self.t_start_s, 3),
            "latency": self.monitor.snapshot(),
            "watchdog": {
                "limit_ms": self.watchdog.limit_s * 1e3,
                "tripped": self.watchdog.tripped,
                "reason": self.watchdog.reason,
            },
            "camera": cam,
            "realtime_loop": self.loop.realtime_granted,
            "last_error": self.loop.last_error,
        }
        out.update(demo_state(self.demo))
        return out

    def status_lines(self, snapshot: dict) -> list[str]:
        """``snapshot`` as the operator reads it (``plugins.demos.status``)."""
        from .status import status_lines  # lazy: it keeps Textual (its markup) lazy

        return status_lines(snapshot)

    def scene_state(self) -> dict | None:
        """The demo's projected scene (``flow_hand`` / ``knob``) as the JSON the projector
        draws, or ``None`` without a scene plugin."""
        scene = getattr(self.demo, "scene", None)
        return scene.state() if scene is not None else None

    @property
    def scene_name(self) -> str:
        """The scene to start on the projector for this demo."""
        return self.demo.link.name

    def __enter__(self) -> DemoRun:
        return self

    def __exit__(self, *exc) -> None:
        self.stop()


def demo_state(demo: Any) -> dict:
    if demo.name == "knob":
        s = demo.session
        lat = demo.crossing_to_output_s()
        kern = demo.crossing_in_kernel_s()
        return {
            "knob": {
                "condition": demo.condition,
                "item": int(s.knob.item),
                "angle_deg": float(s.tracker.angle_deg),
                "touching": bool(s.tracker.touching),
                "crossings": demo.crossings_total,
                # post -> the detent's first sample handed to the driver (the last 512)
                "crossing_to_output_ms": summarize_s(lat) if lat else None,
                # its post arrived at the outputs process -> that block handed (no socket)
                "crossing_in_kernel_ms": summarize_s(kern) if kern else None,
            }
        }
    evs = [{k: v for k, v in e.items() if k != "report"} for e in list(demo.events)[-10:]]
    late = list(demo.late_plan_s)
    return {
        "flow": {
            "direction": demo.current_direction(),
            "flows": demo.played_total,  # plays only (Scenes: "N played")
            "flows_late": demo.played_late,
            "last": evs,
            "preparing": demo.preparation(),
        },
        # the plays planned outside the frame loop, which no frame's decision scheduled
        # (Latency's end to end counts none of them): how many, their planning time
        "off_loop": {
            "n": demo.played_late,
            "what": "flow",
            "planning_ms": summarize_s(late) if late else None,
        },
    }


def _twin_apart(profile: Any, plugins: Any) -> bool:
    """The profile's camera is simulated (its registration says so) and renders in its
    own process (``[runtime] twin_camera_process``)."""
    return bool(profile.get("runtime.twin_camera_process")) and plugins.simulated("camera", profile)


def _open_camera(profile: Any, plugins: Any, demo: str) -> Any:
    """The profile's camera; the twin scripted for ``demo`` in its own process
    (``[runtime] twin_camera_process``: the twin's ``apart()``, its rendering out of
    this process's GIL)."""
    camera = open_camera(profile, plugins)
    apart = getattr(camera, "apart", None)
    if _twin_apart(profile, plugins) and callable(apart):
        script_twin(camera, demo, profile)  # from the child's first frame on
        return apart()
    return camera


def flow_map_path(profile: Any, plugins: Any = None) -> Path:
    """The flow's vibration map: ``[demos] flow_map``, else (on the twin) the profile's
    measured map in HapTable's one cache, the file the console's Vibration screen and
    ``haptable tables measured`` use (measured once)."""

    raw = profile.get("demos.flow_map") or ""
    if raw:
        p = Path(profile.resolve(raw)) if hasattr(profile, "resolve") else Path(raw)
        if not p.is_file():
            raise UserError(
                f"[demos] flow_map = {raw!r}: file not found ({p}); give a vibration map "
                "(haptable frf import ...) or leave it empty on the twin"
            )
        return p
    if profile.get("camera.driver") != "twin":
        raise UserError(
            "[demos] flow_map is empty: give the table's vibration map (haptable frf import ...)"
        )
    try:
        return measured_map_file(profile, plugins)
    except UserError as exc:
        raise UserError(
            f"[demos] flow_map is empty and the twin's map cannot be measured ({exc}); set "
            "[demos] flow_map to a vibration map (haptable frf import ...)"
        ) from None


def start_demo(
    name: str,
    profile: Any,
    plugins: Any,
    outputs: Any,
    *,
    camera: Any = None,
    script: bool = True,
    condition: str | None = None,
    sectors: int | None = None,
    direction: str | None = None,
    flow_plans: Any = None,
    prepare: bool = True,
    sinks: list | None = None,
    tuio: bool | None = None,
    watchdog_ms: float | None = None,
    progress: Any = None,
    projector: Any = None,
    classifier: Any = None,
    camera_apart: bool = False,
    vision: dict | None = None,
    camera_controls: dict | None = None,
    prepare_first: bool = False,
) -> DemoRun:
    """Start demo ``name`` on the profile's camera (or ``camera``) and ``outputs``.

    ``script``: on the twin camera, a scripted hand performs the demo. Registered frame
    sinks the profile enables are fed too; ``tuio`` forces the ``tuio`` sink on (True) or
    off (False) (default: ``[tuio] enabled``). ``watchdog_ms`` overrides ``[runtime]``.
    ``camera``/``classifier``: reuse the console's (its tuned thresholds and learned
    background; stop the console's own frame loop first); the run closes neither.
    ``camera_apart``: a scripted twin ``camera`` is replaced by the twin rendering in its
    own process when ``[runtime] twin_camera_process`` says so (the console lends its
    in-process twin; rendering it beside the loop and the audio costs them the GIL).
    ``projector``: the console's projector service (``update(event)``, after its
    ``start_scene("knob"|"flow_hand")``): the demo's scene events are forwarded to it.
    ``vision``: classifier parameters to override (the console's tuned thresholds);
    ``camera_controls``: the camera's exposure and gain as the console set them (given to
    a camera whose driver takes them, ``AdjustableCamera``; others ignore them).
    On the twin, the flow's map is the measured map in HapTable's one cache, shared with
    the console's Vibration screen (``console.runtime.measured_map``).
    The flow demo runs at once and prepares its plans behind itself (seconds per scene
    region, minutes for the atlas the first time, cached on disk after; its snapshot says
    how far); ``prepare_first``: prepare before the loop starts, reporting
    ``progress(done, total, what)`` (call this from a worker thread).
    """
    if name not in DEMOS:
        raise UserError(f"demo {name!r}: unknown; use one of {', '.join(DEMOS)}")
    dm = profile.section("demos")
    rt = profile.section("runtime")
    if camera_apart and script and camera is not None and _twin_apart(profile, plugins):
        camera = None  # the run opens the twin in its own process (and closes it)
    owns = camera is None
    if owns:
        camera = _open_camera(profile, plugins, name) if script else open_camera(profile, plugins)
    try:
        if script:
            script_twin(camera, name, profile)
        if isinstance(camera, AdjustableCamera):
            for key, value in (camera_controls or {}).items():  # the console's exposure, gain
                if key in camera.controls():
                    camera.set_control(key, value)
        clf = classifier
        if clf is None:
            clf = open_classifier(profile, plugins)
            learn_background(camera, clf)
        for key, value in (vision or {}).items():  # the console's tuned thresholds
            clf.set_tunable(key, value)
        gestures = clf.gesture_stage(
            still_mm=float(dm.get("still_mm", 12.0)), still_s=float(dm.get("still_ms", 300)) / 1e3
        )
        all_sinks = list(sinks or [])
        all_sinks += open_frame_sinks(
            profile, plugins, force=None if tuio is None else {"tuio": tuio}
        )
        for s in all_sinks:  # a recorder sees the plans and relay requests the demo makes
            if isinstance(s, WatchesOutputs):
                outputs = s.watch_outputs(outputs)
        if name == "knob":
            demo = KnobDemo(
                profile,
                plugins,
                outputs,
                condition=condition or dm.get("knob_condition", "HD+CF"),
                sectors=sectors or None,
                projector=projector,
            )
        else:
            pairs, planner = None, None
            plans = flow_plans
            if plans is None:
                if dm.get("plan_process", True):
                    planner = PlanProcess(profile)
                plans, pairs = flow_renderers(
                    plugins, profile, flow_map_path(profile, plugins), planner
                )
            demo = FlowDemo(
                profile,
                plugins,
                outputs,
                plans,
                direction=direction or dm.get("flow_direction", "right"),
                grid_mm=float(dm.get("flow_grid_mm", 10.0)),
                pair_plans=pairs,
                projector=projector,
                still_mm=float(dm.get("still_mm", 12.0)),
                still_s=float(dm.get("still_ms", 300)) / 1e3,
                prepare=prepare,
                planner=planner,
                precompute=bool(dm.get("flow_atlas", True)),
            )
        stages = [
            ("vision", VisionStage(clf)),
            ("classify", gestures),
            *demo.stage_fns(),
        ]
        mon = LatencyMonitor(
            [n for n, _ in stages],
            size=int(rt.get("latency_window_frames", 1200)),
            end_stage="scheduled",
        )
        for s in all_sinks:  # a recorder keeps what the run starts from
            if isinstance(s, BeginsRun):
                s.begin(demo=name, classifier=clf, scene=getattr(demo, "scene", None))
        loop = FrameLoop(
            camera,
            stages,
            monitor=mon,
            queue_size=int(rt.get("queue_frames", 2)),
            sinks=all_sinks,
            name=name,
            realtime=bool(rt.get("realtime_loop", True)),
        )
        limit_ms = watchdog_ms or float(rt.get("watchdog_ms", 250))
        wd = Watchdog(loop, outputs.estop, limit_ms / 1e3, realtime=loop.realtime)
        demo.start(progress, wait=prepare_first)
        loop.start()
        wd.start()
    except BaseException:
        if owns:
            camera.close()
        raise
    return DemoRun(name, demo, loop, wd, camera, owns, outputs, all_sinks)
