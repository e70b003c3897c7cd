"""The projector process: a full-screen pyglet window (or an EGL offscreen buffer) drawing
the newest scene state from the link at the display rate."""

from __future__ import annotations

import logging
import signal
import threading
import time
from dataclasses import dataclass
from pathlib import Path

from console.plugin_api import UserError
from plugins.projector.geometry import (
    Calibration,
    glass_corners_mm,
    load_calibration,
    save_calibration,
)
from plugins.projector.renderer import Offscreen, Renderer
from plugins.projector.server import LinkServer
from plugins.projector.snapshots import write_snapshot

log = logging.getLogger("haptable.projector")


@dataclass
class ProjectorOptions:
    socket_path: Path
    size_px: tuple[int, int]
    headless: bool = False
    screen: int = 0
    fps: float = 60.0
    calibration_path: Path | None = None
    frame_px: tuple[int, int] = (1280, 800)  # the frame the calibration is expressed in
    table_mm: tuple[float, float] = (743.46, 447.29)
    heartbeat_s: float = 0.25
    peer_timeout_s: float = 2.0
    initial_state: dict | None = None
    exit_without_console_s: float = 0.0  # 0: wait for a console forever
    snapshot_dir: Path | None = None  # where ``snapshot`` requests may write (None: default)


class CalibrationWatcher:
    """Reloads the calibration file when it changes (the operator adjusts corners live)."""

    def __init__(
        self, path: Path | None, frame_px: tuple[int, int], table_mm: tuple[float, float]
    ) -> None:
        self.path, self.frame_px, self.table_mm = path, frame_px, table_mm
        self._mtime: float | None = None
        self._checked = 0.0
        self.cal = self._load()

    def _stat(self) -> float | None:
        try:
            return self.path.stat().st_mtime if self.path else None
        except OSError:
            return None

    def _load(self) -> Calibration:
        self._mtime = self._stat()
        return load_calibration(self.path, self.frame_px, self.table_mm)

    def poll(self, now: float) -> Calibration | None:
        """A new calibration if the file changed since the last look (checked once a second)."""
        if now - self._checked < 1.0:
            return None
        self._checked = now
        if self._stat() == self._mtime:
            return None
        try:
            self.cal = self._load()
        except UserError as e:
            log.warning("projector: keeping the previous calibration: %s", e)
            return None
        return self.cal


class CornerAdjust:
    """The operator adjusts the glass corners from the projector's keyboard.

    ``C`` starts (the alignment view replaces the scene), ``1``..``4`` pick a corner,
    arrows move it one pixel (ten with Shift), ``Enter`` saves the calibration file,
    ``Esc`` leaves without saving.
    """

    NUDGE = {"LEFT": (-1, 0), "RIGHT": (1, 0), "UP": (0, -1), "DOWN": (0, 1)}

    def __init__(self, cal: Calibration, path: Path | None) -> None:
        self.cal = self.saved = cal
        self.path = path
        self.active = False
        self.corner = 1
        self.note = ""

    def corner_px(self) -> tuple[float, float]:
        u, v = self.cal.to_px([glass_corners_mm(self.cal.table_mm)[self.corner - 1]])[0]
        return float(u), float(v)

    def key(self, name: str, shift: bool = False) -> bool:
        """Handle a key (pyglet symbol name); True if the picture changes."""
        name = name.lstrip("_").upper()
        if not self.active:
            if name == "C":
                self.active, self.corner, self.saved, self.note = True, 1, self.cal, ""
                return True
            return False
        if name in ("1", "2", "3", "4"):
            self.corner = int(name)
        elif name in self.NUDGE:
            du, dv = self.NUDGE[name]
            step = 10.0 if shift else 1.0
            u, v = self.corner_px()
            mm = tuple(glass_corners_mm(self.cal.table_mm)[self.corner - 1])
            try:
                self.cal = self.cal.with_point(mm, (u + du * step, v + dv * step))
                self.note = ""
            except UserError:
                self.note = "that would fold the glass"
        elif name in ("RETURN", "ENTER"):
            if self.path is None:
                self.note = "no calibration file (start with --calibration or a profile)"
                return True
            try:
                save_calibration(self.cal, self.path)
            except UserError as e:
                self.note = str(e)
                return True
            self.saved, self.active = self.cal, False
        elif name == "ESCAPE":
            self.cal, self.active = self.saved, False
        else:
            return False
        return True

    def overlay(self) -> dict:
        u, v = self.corner_px()
        msg = f"corner {self.corner} at ({u:.0f}, {v:.0f}) px: arrows move, 1-4 pick, Enter saves, Esc cancels"
        return {
            "kind": "alignment",
            "table_mm": list(self.cal.table_mm),
            "selected": self.corner,
            "message": self.note or msg,
        }


def open_window(screen: int):
    """A full-screen pyglet window on ``screen`` with a moderngl context (vsync on)."""
    try:
        import pyglet

        display = pyglet.display.get_display()
        screens = display.get_screens()
    except Exception as e:  # noqa: BLE001 - no X/Wayland display, no GL
        raise UserError(
            f"projector: cannot open a window ({type(e).__name__}: {e}); "
            "run it on the machine's display or use --headless"
        ) from None
    if not 0 <= screen < len(screens):
        raise UserError(
            f"projector: --screen {screen}: this display has screens 0..{len(screens) - 1}"
        )
    import moderngl

    base = {
        "major_version": 3,
        "minor_version": 3,
        "forward_compatible": True,
        "double_buffer": True,
    }
    window, last = None, None
    for extra in ({"sample_buffers": 1, "samples": 4}, {}):  # 4x MSAA if the driver has it
        try:
            window = pyglet.window.Window(
                fullscreen=True,
                screen=screens[screen],
                vsync=True,
                config=pyglet.gl.Config(**base, **extra),
                caption="HapTable projector",
            )
            break
        except Exception as e:  # noqa: BLE001
            last = e
    if window is None:
        raise UserError(
            f"projector: no OpenGL 3.3 window on screen {screen} ({last}); update the GL driver"
        )
    window.set_mouse_visible(False)
    return window, moderngl.create_context()


def read_screen(renderer: Renderer):
    """The window's back buffer as (H, W, 3) uint8, top row first (the frame just drawn)."""
    import numpy as np

    w, h = renderer.size_px
    raw = renderer.ctx.screen.read(viewport=(0, 0, w, h), components=3, alignment=1)
    return np.frombuffer(raw, np.uint8).reshape(h, w, 3)[::-1].copy()


def save_frames(server: LinkServer, shots: list[tuple[str, Path]], rgb) -> None:
    """Write the frame for each snapshot request (paths checked by the server) and answer."""
    for request, path in shots:
        try:
            write_snapshot(path, rgb)
        except UserError as e:
            log.warning("projector: snapshot: %s", e)
            server.snapshot_failed(request, str(e))
        else:
            server.snapshot_done(request, path)


def run(opts: ProjectorOptions) -> int:
    """Serve the link and draw until SIGTERM/SIGINT or a ``quit`` message."""
    stop = threading.Event()
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, lambda *_: stop.set())
    watcher = CalibrationWatcher(opts.calibration_path, opts.frame_px, opts.table_mm)
    window = None
    if opts.headless:
        off = Offscreen(opts.size_px, watcher.cal)
        renderer: Renderer = off.renderer
        size = off.size_px
    else:
        window, ctx = open_window(opts.screen)
        size = tuple(window.get_framebuffer_size())
        renderer = Renderer(ctx, size, watcher.cal)
        adjust = CornerAdjust(watcher.cal, opts.calibration_path)

        def on_key_press(symbol, modifiers):
            import pyglet

            if adjust.key(
                pyglet.window.key.symbol_string(symbol),
                bool(modifiers & pyglet.window.key.MOD_SHIFT),
            ):
                renderer.set_calibration(adjust.cal)
                renderer._key = None
            return True  # Esc must not close the projector: the console owns it

        window.push_handlers(on_key_press=on_key_press)
    server = LinkServer(
        opts.socket_path,
        heartbeat_s=opts.heartbeat_s,
        peer_timeout_s=opts.peer_timeout_s,
        initial=opts.initial_state,
        info={"size_px": list(size), "headless": opts.headless},
        snapshot_dir=opts.snapshot_dir,
    )
    server.start()
    log.info(
        "projector: serving %s, %dx%d %s",
        opts.socket_path,
        *size,
        "headless" if opts.headless else "window",
    )
    period = 1.0 / opts.fps
    # headless, a frame whose state and calibration are unchanged is not drawn again:
    # nothing in a scene moves on its own (the drawing is a function of the two), the
    # buffer already holds it, and software GL costs a core at 60 fps
    drawn: int | None = None
    calibrated = False
    next_t = time.monotonic()
    alone_since = time.monotonic()
    try:
        while not stop.is_set() and not server.quit_requested.is_set():
            now = time.monotonic()
            if (cal := watcher.poll(now)) is not None:
                calibrated = True
                renderer.set_calibration(cal)
                renderer._key = None  # text sizes depend on the scale: re-tessellate
                if window is not None and not adjust.active:
                    adjust.cal = adjust.saved = cal
            version, _, _, state = server.snapshot()
            if window is not None and adjust.active:
                state = adjust.overlay()
            if window is not None:
                window.dispatch_events()
                if window.has_exit:
                    break
                renderer.ctx.screen.use()
                renderer.set_state(state)
                renderer.draw()
                shots = server.take_snapshot_requests()
                if shots:  # the back buffer, before the swap
                    save_frames(server, shots, read_screen(renderer))
                window.flip()  # blocks to the display rate (vsync)
            else:
                shots = server.take_snapshot_requests()
                if version != drawn or calibrated or shots:
                    off.render(state)
                    off.finish()
                    drawn, calibrated = version, False
                if shots:
                    save_frames(server, shots, off.read_rgb())
            server.frame_done(version, time.monotonic())
            if server.connected:
                alone_since = now
            elif (
                opts.exit_without_console_s > 0 and now - alone_since > opts.exit_without_console_s
            ):
                log.warning(
                    "projector: no console for %.0f s: exiting", opts.exit_without_console_s
                )
                break
            if window is None:
                next_t += period
                delay = next_t - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
                else:
                    next_t = time.monotonic()
    finally:
        server.close()
        renderer.release()
        if window is not None:
            window.close()
    return 0
