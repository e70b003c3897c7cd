"""``haptable projector``: run the projector, take a screenshot, or adjust its calibration."""

from __future__ import annotations

import contextlib
import json
import sys
from pathlib import Path
from typing import Any

from console.plugin_api import Parser, UserError, load_plugins, load_profile
from console.plugin_api.runtime import default_socket_path, socket_path_for
from plugins.projector import layout
from plugins.projector.cli_options import configure
from plugins.projector.geometry import glass_corners_mm, load_calibration, save_calibration
from plugins.projector.launch import projector_command
from plugins.projector.scenes import BUILTIN_SCENES
from plugins.projector.settings import DEFAULTS, calibration_path_for

__all__ = ["configure", "main", "run"]


def _opt(args: Any, ctx: Any, attr: str, key: str) -> Any:
    """An option: the command line first, then the profile, then the default."""
    v = getattr(args, attr, None)
    if v is not None:
        return v
    return layout.get(_profile(ctx), f"projector.{key}", DEFAULTS[key])


def _profile(ctx: Any) -> Any:
    return getattr(ctx, "profile", None) if ctx is not None else None


def scene_factories(ctx: Any) -> dict[str, Any]:
    """Scenes registered by all plugins (through the plugin manager)."""
    pm = getattr(ctx, "pm", None)
    if pm is not None:
        return {name: reg.factory for name, reg in pm.of("scene").items()}

    return {name: cls for name, (cls, _) in BUILTIN_SCENES.items()}


def build_state(ctx: Any, name: str, events: list[dict]) -> dict:
    scenes = scene_factories(ctx)
    if name not in scenes:
        raise UserError(f"--scene {name!r}: no such scene; available: {', '.join(sorted(scenes))}")
    scene = scenes[name](_profile(ctx))
    for ev in events:
        scene.update(ev)
    state = scene.state()
    json.dumps(state)
    return state


def _frame_px(args: Any, ctx: Any) -> tuple[int, int]:
    return (int(_opt(None, ctx, "", "width_px")), int(_opt(None, ctx, "", "height_px")))


def _calibration_path(args: Any, ctx: Any) -> Path | None:
    if args.calibration:
        return Path(args.calibration)
    return calibration_path_for(_profile(ctx))


def _snapshot_dir(args: Any, ctx: Any) -> Path | None:
    """``--snapshot-dir``, else ``[projector] snapshot_dir`` (relative to the profile)."""
    if args.snapshot_dir:
        return Path(args.snapshot_dir).expanduser().resolve()
    prof = _profile(ctx)
    p = prof.get("projector.snapshot_dir", "") if prof is not None else ""
    return prof.resolve(p) if p else None


def calibrate(args: Any, ctx: Any) -> int:
    path = _calibration_path(args, ctx)
    table = layout.table_mm(_profile(ctx))
    frame = _frame_px(args, ctx)
    if args.reset_calibration:
        if path is not None and path.exists():
            path.unlink()
        print(
            f"calibration reset to the default (glass corners on the {frame[0]}x{frame[1]} frame corners)"
        )
        return 0
    cal = load_calibration(path, frame, table)
    if args.set_corner or args.add_point:
        if path is None:
            raise UserError(
                "projector calibration: no file to store it in; give --calibration PATH or a --profile"
            )
        if args.set_corner:
            n, u, v = args.set_corner
            if int(n) != n or not 1 <= n <= 4:
                raise UserError(
                    f"--set-corner {n:g}: corners are 1 (0,0), 2 (W,0), 3 (W,H), 4 (0,H)"
                )
            mm = tuple(glass_corners_mm(table)[int(n) - 1])
            cal = cal.with_point(mm, (u, v))
        else:
            x, y, u, v = args.add_point
            cal = cal.with_point((x, y), (u, v))
        save_calibration(cal, path)
        print(f"saved {path}")
    print(
        json.dumps(
            {
                "path": str(path) if path else None,
                **cal.to_json(),
                "residuals_px": cal.residuals_px().round(3).tolist(),
            },
            indent=2,
        )
    )
    return 0


def screenshot(args: Any, ctx: Any) -> int:
    # lazy: this module loads at every haptable start; renderer only when used
    from plugins.projector.renderer import Offscreen, egl_available, write_png

    state = build_state(ctx, args.scene or "alignment", args.event)
    size = args.size or _frame_px(args, ctx)
    cal = load_calibration(
        _calibration_path(args, ctx), _frame_px(args, ctx), layout.table_mm(_profile(ctx))
    )
    ok, why = egl_available()
    if not ok:
        raise UserError(f"projector --screenshot: {why}")
    off = Offscreen(size, cal)
    off.render(state)
    write_png(args.screenshot, off.read_rgb())
    off.release()
    print(f"wrote {args.screenshot} ({size[0]}x{size[1]}, scene {args.scene or 'alignment'})")
    return 0


def show(args: Any, ctx: Any) -> int:
    """Be a console: start or adopt the projector, show a scene, wait, then stop it."""
    import time

    # lazy: the runtime part loads on first use, not at every haptable start
    from console.plugin_api.runtime import ProjectorService

    prof = _profile(ctx)
    extra: list[str] = []
    if args.size:
        extra += ["--size", f"{args.size[0]}x{args.size[1]}"]
    if args.screen is not None:
        extra += ["--screen", str(args.screen)]
    if args.calibration:
        extra += ["--calibration", str(Path(args.calibration).resolve())]
    sock = Path(args.socket).resolve() if args.socket else socket_path_for(prof)
    svc = ProjectorService(
        socket_path=sock,
        command=projector_command(
            sock, profile_path=getattr(prof, "path", None), headless=args.headless, extra=extra
        ),
        scenes=scene_factories(ctx),
        profile=prof,
        heartbeat_s=float(_opt(args, ctx, "heartbeat_s", "heartbeat_s")),
        peer_timeout_s=float(_opt(args, ctx, "peer_timeout_s", "peer_timeout_s")),
        log_path=sock.parent / "projector.log",
    )
    try:
        svc.start()
        if not svc.link.wait_connected(30):
            st = svc.status()
            why = st.get("last_error") or st.get("last_reason") or "no answer"
            raise UserError(f"projector: did not come up ({why}); see {st.get('log')}")
        svc.start_scene(args.show, args.event)
        if not svc.wait_drawn(20):
            raise UserError(
                "projector: connected but did not draw the scene within 20 s; see its log"
            )
        st = svc.status()
        how = "adopted" if st.get("adopted") else "started"
        print(f"showing {args.show} on projector pid {st['pid']} ({how})", flush=True)
        if args.snapshot:
            if not svc.snapshot(args.snapshot, 20):
                raise UserError(f"projector: no snapshot written to {args.snapshot}")
            print(f"wrote {args.snapshot}", flush=True)
        deadline = None if args.seconds is None else time.monotonic() + args.seconds
        with contextlib.suppress(KeyboardInterrupt):
            while deadline is None or time.monotonic() < deadline:
                time.sleep(0.1)
        svc.stop_scene()
        svc.wait_drawn(5)
    finally:
        svc.close(stop_projector=not args.keep)
    return 0


def run(args: Any, ctx: Any) -> int:
    if args.list_scenes:
        regs = ctx.pm.of("scene")
        for name in sorted(regs):
            scene = regs[name].factory(_profile(ctx))
            needs = getattr(scene, "needs", {}) or {}
            short = ", ".join(
                f"{k} ({len(v)})" if isinstance(v, list) else k for k, v in needs.items() if v
            )
            print(f"{name:18s} {regs[name].description}  [needs: {short or 'nothing'}]")
        return 0
    if args.show_calibration or args.set_corner or args.add_point or args.reset_calibration:
        return calibrate(args, ctx)
    if args.screenshot:
        return screenshot(args, ctx)
    if args.show:
        return show(args, ctx)
    # lazy: this module loads at every haptable start; app only when used
    from plugins.projector.app import ProjectorOptions
    from plugins.projector.app import run as run_projector

    prof = _profile(ctx) if args.socket is None or args.scene else None
    sock = (
        Path(args.socket)
        if args.socket
        else (socket_path_for(prof) if prof is not None else default_socket_path())
    )
    frame = _frame_px(args, ctx)
    opts = ProjectorOptions(
        socket_path=sock,
        size_px=args.size or frame,
        headless=args.headless,
        screen=int(_opt(args, ctx, "screen", "screen")),
        fps=float(_opt(args, ctx, "fps", "fps")),
        calibration_path=_calibration_path(args, ctx),
        frame_px=frame,
        table_mm=layout.table_mm(prof),
        heartbeat_s=float(_opt(args, ctx, "heartbeat_s", "heartbeat_s")),
        peer_timeout_s=float(_opt(args, ctx, "peer_timeout_s", "peer_timeout_s")),
        initial_state=build_state(ctx, args.scene, args.event) if args.scene else None,
        exit_without_console_s=args.exit_without_console_s,
        snapshot_dir=_snapshot_dir(args, ctx),
    )
    return run_projector(opts)


class StandaloneContext:
    """``python -m plugins.projector``: the profile and plugins load only when used, so a
    supervised projector given every option on its command line starts fast and alone."""

    def __init__(self, profile_arg: str | None, use_profile: bool) -> None:
        self._arg, self._use = profile_arg, use_profile
        self._profile: Any = None
        self._pm: Any = None

    @property
    def pm(self) -> Any:
        if self._pm is None:
            self._pm = load_plugins()
        return self._pm

    @property
    def profile(self) -> Any:
        if not self._use:
            return None
        if self._profile is None:
            self._profile = load_profile(self._arg, self.pm)
        return self._profile


def main(argv: list[str] | None = None) -> int:
    parser = Parser(prog="python -m plugins.projector", description="HapTable projector process")
    parser.add_argument(
        "--profile",
        "-p",
        default=None,
        help="profile name or path (default: none, built-in defaults)",
    )
    configure(parser)
    try:
        args = parser.parse_args(argv)
    except UserError as e:
        print(f"haptable projector: error: {e}", file=sys.stderr)
        return 2
    import logging

    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s")
    ctx = StandaloneContext(args.profile, use_profile=args.profile is not None)
    if args.profile is None:
        ctx._pm = _builtin_only()
    try:
        return run(args, ctx)
    except UserError as e:
        print(f"haptable projector: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:
        return 0


class _builtin_only:
    """Scenes of this plugin only (no profile, no other plugins)."""

    @staticmethod
    def of(kind: str) -> dict:
        from types import SimpleNamespace

        if kind != "scene":
            return {}
        return {
            n: SimpleNamespace(factory=cls, description=d) for n, (cls, d) in BUILTIN_SCENES.items()
        }
