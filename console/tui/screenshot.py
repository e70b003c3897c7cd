"""Save an SVG of the console as it looks now (for the README and bug reports).

``python -m console.tui.screenshot docs/console.svg [--tab vibration] [--size 100x30]
[--map MAP.npz] [--profile NAME]``: opens the console headless on the profile, waits for
the outputs, optionally loads a vibration map and selects points 51 and 52 (the paper's
example pair), and writes ``App.save_screenshot``'s SVG.
"""

from __future__ import annotations

import argparse
import asyncio
from pathlib import Path

from console.core.options import seconds
from console.runtime.context import Context


async def _shoot(args) -> Path:
    # lazy: Textual and plugins load only when a screenshot is taken
    from console.config.plugins import load_plugins
    from console.tui.app import HapTableApp

    app = HapTableApp(Context(args.profile, load_plugins()), fast=True, initial=args.tab)
    w, h = (int(v) for v in args.size.lower().split("x"))
    async with app.run_test(size=(w, h)) as pilot:
        for _ in range(200):
            if app.session.outputs is not None:
                break
            await pilot.pause(0.05)
        if args.map and args.tab == "vibration":
            pane = app.pane("vibration")
            pane.run_command(f"load {args.map}")
            for _ in range(600):
                if pane.session is not None:
                    break
                await pilot.pause(0.05)
            pane.selected = [51, 52]
            pane.move_cursor(52)
            pane._redraw_grid()
            pane._show_selection()
        await pilot.pause(args.wait_s)
        await pilot.wait_for_scheduled_animations()
        out = Path(args.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        app.save_screenshot(filename=out.name, path=str(out.parent))
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m console.tui.screenshot", description=__doc__)
    p.add_argument("out", help="SVG file to write")
    p.add_argument("--tab", default="devices", help="devices, vibration, relays, ...")
    p.add_argument("--size", default="100x30", help="terminal size, columns x rows")
    p.add_argument("--map", help="vibration map to load on the vibration screen")
    p.add_argument("--profile", default=None)
    p.add_argument("--wait-s", type=seconds(600.0), default=1.0, help="settle time before the shot")
    args = p.parse_args(argv)
    print(asyncio.run(_shoot(args)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
