"""The projector process: a full-screen pyglet window (or an EGL offscreen buffer) drawing
the newest scene state from the link at the display rate."""

from __future__ import annotations

import logging
import signal
import threading
import time
from dataclasses import dataclass
from pathlib import Path

from console.errors import UserError
from plugins.projector.geometry import Calibration, load_calibration
from plugins.projector.renderer import Offscreen, Renderer
from plugins.projector.server import LinkServer

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

    config = pyglet.gl.Config(
        major_version=3, minor_version=3, forward_compatible=True, double_buffer=True
    )
    try:
        window = pyglet.window.Window(
            fullscreen=True,
            screen=screens[screen],
            vsync=True,
            config=config,
            caption="HapTable projector",
        )
    except Exception as e:  # noqa: BLE001
        raise UserError(
            f"projector: no OpenGL 3.3 window on screen {screen} ({e}); update the GL driver"
        ) from None
    window.set_mouse_visible(False)
    return window, moderngl.create_context()


def read_screen(renderer: Renderer):
    """The window's back buffer as (H, W, 3) uint8, top row first (the frame just drawn)."""
    import numpy as np

    w, h = renderer.size_px
    raw = renderer.ctx.screen.read(viewport=(0, 0, w, h), components=3, alignment=1)
    return np.frombuffer(raw, np.uint8).reshape(h, w, 3)[::-1].copy()


def save_frame(path: str, rgb) -> None:
    from plugins.projector.renderer import write_png

    try:
        write_png(path, rgb)
    except UserError as e:
        log.warning("projector: snapshot: %s", e)


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
    server = LinkServer(
        opts.socket_path,
        heartbeat_s=opts.heartbeat_s,
        peer_timeout_s=opts.peer_timeout_s,
        initial=opts.initial_state,
        info={"size_px": list(size), "headless": opts.headless},
    )
    server.start()
    log.info(
        "projector: serving %s, %dx%d %s",
        opts.socket_path,
        *size,
        "headless" if opts.headless else "window",
    )
    period = 1.0 / opts.fps
    next_t = time.monotonic()
    alone_since = time.monotonic()
    try:
        while not stop.is_set() and not server.quit_requested.is_set():
            now = time.monotonic()
            if (cal := watcher.poll(now)) is not None:
                renderer.set_calibration(cal)
                renderer._key = None  # text sizes depend on the scale: re-tessellate
            version, _, _, state = server.snapshot()
            if window is not None:
                window.dispatch_events()
                if window.has_exit:
                    break
                renderer.ctx.screen.use()
                renderer.set_state(state)
                renderer.draw()
                shots = server.take_snapshot_requests()
                for path in shots:  # the back buffer, before the swap
                    save_frame(path, read_screen(renderer))
                window.flip()  # blocks to the display rate (vsync)
            else:
                off.render(state)
                off.finish()
                shots = server.take_snapshot_requests()
                for path in shots:
                    save_frame(path, off.read_rgb())
            server.frame_done(version, time.monotonic())
            for path in shots:
                server.snapshot_done(path)
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
