"""The GL side: draw a scene state (table mm) through the calibration with moderngl.

One program draws coloured triangles in millimetres; the homography is applied in the
vertex shader as a projective clip-space transform, so keystone corrections stay exact
(and texture interpolation perspective-correct). Text is one textured quad per string.
"""

from __future__ import annotations

import hashlib
import json
import logging
from typing import Any

import numpy as np

from console.plugin_api import UserError
from plugins.projector.draw import Layer, build_layer, primitives
from plugins.projector.geometry import Calibration
from plugins.projector.text import text_bitmap

log = logging.getLogger("haptable.projector")


#: What one state may ask the renderer for (the real scenes stay far below: ~170 shapes,
#: a few thousand text pixels): beyond it the state is not drawn (an error line shows).
MAX_PRIMITIVES = 10_000
MAX_TEXT_PIXELS = 16_000_000


def check_budget(prims: list[dict], px_per_mm: float) -> None:
    """``ValueError`` when ``prims`` would take too long to tessellate or too much memory
    for their text bitmaps (a state is untrusted input from the link)."""
    if len(prims) > MAX_PRIMITIVES:
        raise ValueError(f"{len(prims)} shapes (at most {MAX_PRIMITIVES})")
    area = 0.0
    for p in prims:
        if p["p"] == "text":
            px = min(max(float(p.get("size_mm", 12.0)) * px_per_mm * 1.25, 6.0), 256.0)
            area += len(str(p.get("text", ""))) * px * px * 0.7  # glyphs ~0.7 px wide per px
    if area > MAX_TEXT_PIXELS:
        raise ValueError(f"text of ~{area / 1e6:.0f} Mpx (at most {MAX_TEXT_PIXELS / 1e6:.0f})")


def error_primitives(message: str) -> list[dict]:
    """What the projector shows instead of a state it cannot draw."""
    return [
        {"p": "text", "xy": [20.0, 30.0], "text": message[:160], "size_mm": 12.0, "color": "red"}
    ]


_HOMOG = """
uniform mat3 H;        // table mm -> pixels (y down)
uniform vec2 size_px;
vec4 to_clip(vec2 mm) {
    vec3 p = H * vec3(mm, 1.0);
    return vec4(2.0 * p.x / size_px.x - p.z, p.z - 2.0 * p.y / size_px.y, 0.0, p.z);
}
"""

VS_FILL = (
    "#version 330\n"
    + _HOMOG
    + """
in vec2 in_mm;
in vec4 in_rgba;
out vec4 v_rgba;
void main() { gl_Position = to_clip(in_mm); v_rgba = in_rgba; }
"""
)
FS_FILL = """#version 330
in vec4 v_rgba; out vec4 f_color;
void main() { f_color = v_rgba; }
"""
VS_TEXT = (
    "#version 330\n"
    + _HOMOG
    + """
in vec2 in_mm;
in vec2 in_uv;
in vec4 in_rgba;
out vec2 v_uv;
out vec4 v_rgba;
void main() { gl_Position = to_clip(in_mm); v_uv = in_uv; v_rgba = in_rgba; }
"""
)
FS_TEXT = """#version 330
uniform sampler2D tex;
in vec2 v_uv; in vec4 v_rgba; out vec4 f_color;
void main() { f_color = vec4(v_rgba.rgb, v_rgba.a * texture(tex, v_uv).r); }
"""


def state_key(state: dict | None) -> str:
    """Hash of a state's JSON (the tessellation cache key)."""
    return hashlib.sha1(
        json.dumps(state, sort_keys=True, separators=(",", ":")).encode()
    ).hexdigest()


class Renderer:
    """Draws scene states into the bound framebuffer of ``ctx`` (a window or an FBO)."""

    def __init__(self, ctx: Any, size_px: tuple[int, int], calibration: Calibration) -> None:
        import moderngl

        self.ctx = ctx
        self.size_px = (int(size_px[0]), int(size_px[1]))
        self.fill = ctx.program(vertex_shader=VS_FILL, fragment_shader=FS_FILL)
        self.textp = ctx.program(vertex_shader=VS_TEXT, fragment_shader=FS_TEXT)
        self._blend = moderngl.BLEND
        self._key: str | None = None
        self._vao = None
        self._vbo = None
        self._n = 0
        self._text_vao = None
        self._text_vbo = None
        self._atlas = None
        self.layer: Layer | None = None
        self.set_calibration(calibration)

    def set_calibration(self, cal: Calibration) -> None:
        self.cal = cal
        h = cal.h_for(self.size_px)
        for p in (self.fill, self.textp):
            p["H"].write(h.T.astype("f4").tobytes())
            p["size_px"].value = self.size_px
        self._px_per_mm = 1.0 / cal.mm_per_px() * self.size_px[0] / cal.frame_px[0]

    def set_state(self, state: dict | None) -> bool:
        """Tessellate ``state`` unless it is the one already drawn; True if it changed."""
        key = state_key(state)
        if key == self._key:
            return False
        self._key = key
        try:
            prims = primitives(state)
            check_budget(prims, self._px_per_mm)
            self.layer = build_layer(prims)
        except Exception as e:  # noqa: BLE001 - a bad state must not take the projector down
            kind = (state or {}).get("kind", "?") if isinstance(state, dict) else "?"
            log.warning("projector: cannot draw scene kind %r: %s: %s", kind, type(e).__name__, e)
            self.layer = build_layer(
                error_primitives(f"cannot draw scene {kind!r}: {type(e).__name__}: {e}")
            )
        self._upload(self.layer)
        return True

    def _release_geometry(self) -> None:
        for obj in (self._vao, self._vbo, self._text_vao, self._text_vbo, self._atlas):
            if obj is not None:
                obj.release()
        self._vao = self._vbo = self._text_vao = self._text_vbo = self._atlas = None

    def _upload(self, layer: Layer) -> None:
        self._release_geometry()
        self._n = len(layer.xy_mm)
        if self._n:
            data = np.hstack([layer.xy_mm, layer.rgba]).astype("f4")
            self._vbo = self.ctx.buffer(data.tobytes())
            self._vao = self.ctx.vertex_array(self.fill, [(self._vbo, "2f 4f", "in_mm", "in_rgba")])
        if layer.texts:
            self._upload_texts(layer)

    def _upload_texts(self, layer: Layer) -> None:
        """All strings of the layer in one atlas texture and one vertex buffer."""
        bmps = [
            text_bitmap(t.text, int(round(t.size_mm * self._px_per_mm * 1.25))) for t in layer.texts
        ]
        atlas, boxes = pack_atlas(bmps)
        ah, aw = atlas.shape
        self._atlas = self.ctx.texture((aw, ah), 1, atlas.tobytes(), alignment=1)
        quads = []
        for t, bmp, (bx, by) in zip(layer.texts, bmps, boxes, strict=True):
            bh, bw = bmp.shape
            h = t.size_mm
            w = h * bw / bh
            x = t.xy_mm[0] - {"l": 0.0, "c": w / 2, "r": w}.get(t.anchor, 0.0)
            y = t.xy_mm[1] - h / 2
            u0, v0, u1, v1 = bx / aw, by / ah, (bx + bw) / aw, (by + bh) / ah
            corners = [
                (x, y, u0, v0),
                (x + w, y, u1, v0),
                (x + w, y + h, u1, v1),
                (x, y + h, u0, v1),
            ]
            for i in (0, 1, 2, 0, 2, 3):
                quads.append((*corners[i], *t.rgba))
        data = np.array(quads, "f4")
        self._text_vbo = self.ctx.buffer(data.tobytes())
        self._text_vao = self.ctx.vertex_array(
            self.textp, [(self._text_vbo, "2f 2f 4f", "in_mm", "in_uv", "in_rgba")]
        )

    def draw(self) -> None:
        """Clear to black and draw the current state into the bound framebuffer."""
        ctx = self.ctx
        ctx.viewport = (0, 0, *self.size_px)
        ctx.clear(0.0, 0.0, 0.0, 1.0)
        ctx.enable(self._blend)
        ctx.blend_func = ctx.SRC_ALPHA, ctx.ONE_MINUS_SRC_ALPHA
        if self._vao is not None:
            self._vao.render()
        if self._text_vao is not None:
            self._atlas.use(0)
            self._text_vao.render()

    def release(self) -> None:
        self._release_geometry()


def pack_atlas(bmps: list[np.ndarray], width: int = 2048, pad: int = 2) -> tuple[np.ndarray, list]:
    """Shelf-pack bitmaps into one (H, W) uint8 atlas; returns it and each (x, y) corner."""
    width = max(width, max(b.shape[1] for b in bmps) + 2 * pad)
    boxes, x, y, shelf = [], pad, pad, 0
    for b in bmps:
        h, w = b.shape
        if x + w + pad > width:
            x, y, shelf = pad, y + shelf + pad, 0
        boxes.append((x, y))
        x += w + pad
        shelf = max(shelf, h)
    atlas = np.zeros((y + shelf + pad, width), np.uint8)
    for b, (bx, by) in zip(bmps, boxes, strict=True):
        atlas[by : by + b.shape[0], bx : bx + b.shape[1]] = b
    return atlas, boxes


# --------------------------------------------------------------------------- headless
def egl_context():
    """A standalone OpenGL 3.3 context through EGL (Mesa llvmpipe works without a GPU)."""
    import moderngl

    return moderngl.create_standalone_context(require=330, backend="egl")


def egl_available() -> tuple[bool, str]:
    """Whether a headless EGL context can be made here, and why not."""
    try:
        ctx = egl_context()
    except Exception as e:  # noqa: BLE001 - any failure means "not here"
        return (
            False,
            f"no EGL OpenGL 3.3 context ({type(e).__name__}: {e}); install Mesa EGL (libegl1 libegl-mesa0 libgl1-mesa-dri)",
        )
    ctx.release()
    return True, ""


def egl_fence_wait():
    """``wait()`` that blocks until the GL commands issued so far are done, through
    glFenceSync/glClientWaitSync called via ctypes, which releases the GIL while it waits
    (moderngl's ``finish`` holds it, stalling the link thread for a whole frame).
    None if EGL does not give the entry points."""
    import ctypes

    try:
        egl = ctypes.CDLL("libEGL.so.1")
        egl.eglGetProcAddress.restype = ctypes.c_void_p
        egl.eglGetProcAddress.argtypes = [ctypes.c_char_p]
        addr = [
            egl.eglGetProcAddress(n) for n in (b"glFenceSync", b"glClientWaitSync", b"glDeleteSync")
        ]
    except (OSError, AttributeError):
        return None
    if not all(addr):
        return None
    fence = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.c_uint, ctypes.c_uint)(addr[0])
    client_wait = ctypes.CFUNCTYPE(ctypes.c_uint, ctypes.c_void_p, ctypes.c_uint, ctypes.c_uint64)(
        addr[1]
    )
    delete = ctypes.CFUNCTYPE(None, ctypes.c_void_p)(addr[2])
    gl_sync_gpu_commands_complete, gl_sync_flush_commands_bit = 0x9117, 0x1
    ok = (0x911A, 0x911C)  # ALREADY_SIGNALED, CONDITION_SATISFIED

    def wait(timeout_s: float = 5.0) -> bool:
        sync = fence(gl_sync_gpu_commands_complete, 0)
        if not sync:
            return False
        try:
            return client_wait(sync, gl_sync_flush_commands_bit, int(timeout_s * 1e9)) in ok
        finally:
            delete(sync)

    return wait


class Offscreen:
    """A renderer drawing into an offscreen framebuffer of ``size_px``."""

    def __init__(self, size_px: tuple[int, int], calibration: Calibration, ctx: Any = None) -> None:
        self.ctx = ctx or egl_context()
        self.size_px = (int(size_px[0]), int(size_px[1]))
        self.fbo = self.ctx.simple_framebuffer(self.size_px, components=4)
        self.renderer = Renderer(self.ctx, self.size_px, calibration)
        self._fence = None

    def render(self, state: dict | None) -> None:
        self.fbo.use()
        self.renderer.set_state(state)
        self.renderer.draw()

    def finish(self) -> None:
        """Wait until the frame is rendered (without holding the GIL when possible)."""
        if self._fence is None:
            self._fence = egl_fence_wait() or False
        if not (self._fence and self._fence()):
            self.ctx.finish()

    def read_rgb(self) -> np.ndarray:
        """(H, W, 3) uint8, top row first (as projected)."""
        raw = self.fbo.read(components=3, alignment=1)
        img = np.frombuffer(raw, np.uint8).reshape(self.size_px[1], self.size_px[0], 3)
        return img[::-1].copy()

    def release(self) -> None:
        self.renderer.release()
        self.fbo.release()


def write_png(path: str, rgb: np.ndarray) -> None:
    """Write an RGB image as PNG (OpenCV wants BGR)."""
    import cv2

    if not cv2.imwrite(str(path), np.ascontiguousarray(rgb[:, :, ::-1])):
        raise UserError(
            f"{path}: cannot write the screenshot; check the folder exists and is writable"
        )
