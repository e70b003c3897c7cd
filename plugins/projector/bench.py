"""``haptable bench projector``: frame time per scene at 1920 x 1080 headless, link latency."""

from __future__ import annotations

import tempfile
import time
from pathlib import Path
from typing import Any

from console.plugin_api import machine_info, summarize_s
from console.plugin_api.runtime import ProjectorService
from plugins.projector.draw import build_layer, primitives
from plugins.projector.geometry import default_calibration
from plugins.projector.launch import projector_command
from plugins.projector.layout import hand_outline_mm
from plugins.projector.renderer import Offscreen, egl_context
from plugins.projector.scenes import BUILTIN_SCENES

SIZE = (1920, 1080)


def scene_states(profile: Any) -> dict[str, list[dict]]:
    """Two states per scene (a frame that changes state alternates between them)."""
    out: dict[str, list[dict]] = {}
    events = {
        "touch_calibration": [{"type": "touch"}],
        "flow_two_point": [{"type": "pair", "name": "1"}],
        "flow_hand": [{"type": "region", "name": "R1"}],
        "knob": [{"type": "rotate", "delta_deg": 45.0}],
        "contacts": [
            {
                "type": "contacts",
                "contacts": [
                    {"id": i, "pos_mm": [100.0 + 50 * i, 150.0 + 10 * i]} for i in range(10)
                ],
                "hands": [
                    {
                        "contour_mm": hand_outline_mm((400.0, 250.0)),
                        "center_mm": [400.0, 250.0],
                        "label": "5 fingers",
                    }
                ],
            }
        ],
        "grid": [{"type": "audition", "point": 51, "passive": 52, "excitation": "PA"}],
        "alignment": [{"type": "select_corner", "corner": 2}],
    }
    for name, (cls, _) in BUILTIN_SCENES.items():
        if name == "black":
            continue
        scene = cls(profile)
        first = scene.state()
        for ev in events.get(name, []):
            scene.update(ev)
        out[name] = [first, scene.state()]
    return out


def frame_times(profile: Any, n_frames: int) -> dict:
    ctx = egl_context()
    off = Offscreen(SIZE, default_calibration(SIZE), ctx=ctx)
    results = {"renderer": ctx.info.get("GL_RENDERER", "?")}
    for name, (a, b) in scene_states(profile).items():
        off.render(a)
        off.finish()
        steady = []
        for _ in range(n_frames):
            t = time.perf_counter()
            off.render(a)  # same state: cached geometry
            off.finish()
            steady.append(time.perf_counter() - t)
        change = []
        tess = []
        for i in range(max(10, n_frames // 4)):
            s = b if i % 2 == 0 else a
            t = time.perf_counter()
            build_layer(primitives(s))
            tess.append(time.perf_counter() - t)
            t = time.perf_counter()
            off.render(s)  # new state: tessellate + upload + draw
            off.finish()
            change.append(time.perf_counter() - t)
        off.render(b)
        layer = off.renderer.layer
        results[name] = {
            "frame": summarize_s(steady),
            "frame_with_new_state": summarize_s(change),
            "tessellate": summarize_s(tess),
            "triangles": int(len(layer.xy_mm) // 3) if layer else 0,
            "texts": len(layer.texts) if layer else 0,
        }
    off.release()
    ctx.release()
    return results


def link_latency(n_messages: int) -> dict:
    with tempfile.TemporaryDirectory(prefix="hpt-bench-") as d:
        sock = Path(d) / "p.sock"
        svc = ProjectorService(
            socket_path=sock,
            command=projector_command(
                sock, headless=True, extra=["--size", f"{SIZE[0]}x{SIZE[1]}"]
            ),
            scenes={n: c for n, (c, _) in BUILTIN_SCENES.items()},
            log_path=Path(d) / "projector.log",
        )
        try:
            svc.start()
            if not svc.link.wait_connected(30):
                return {
                    "error": "the projector did not connect: "
                    + (Path(d) / "projector.log").read_text()[-500:]
                }
            svc.start_scene("knob")
            svc.wait_drawn(10)
            svc.link.latency_s.clear()
            svc.link.drawn_latency_s.clear()
            for _ in range(n_messages):
                svc.update({"type": "rotate", "delta_deg": 7.0})
                svc.wait_drawn(5)
                time.sleep(0.005)
            one_way = list(svc.link.latency_s)
            drawn = list(svc.link.drawn_latency_s)
            fps = svc.status()["fps"]
        finally:
            svc.close()
    return {
        "console_to_projector": summarize_s(one_way),
        "console_to_frame_drawn": summarize_s(drawn),
        "projector_fps": fps,
        "note": "one-way: send -> projector read (shared CLOCK_MONOTONIC); drawn: send -> first "
        "finished frame with that state, headless at 60 fps (so up to one frame of waiting)",
    }


def run_bench(ctx: Any, quick: bool) -> dict:
    profile = None
    try:
        profile = ctx.profile if ctx is not None else None
    except Exception:  # noqa: BLE001 - the bench measures with defaults when no profile loads
        profile = None
    import os

    load_before = os.getloadavg()[0]
    return {
        "load_avg_1min": load_before,  # other work on the machine skews llvmpipe timings
        "size_px": list(SIZE),
        "frame_time_headless": frame_times(profile, 30 if quick else 200),
        "link_latency": link_latency(50 if quick else 400),
        "machine": machine_info(),
    }
