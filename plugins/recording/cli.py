"""``haptable replay FILE``: a recording's frames through the same pipeline; one line:
every decision the same (exit 0) or the first difference (exit 1)."""

from __future__ import annotations

import argparse


def configure(p: argparse.ArgumentParser) -> None:
    p.add_argument("file", help="a recording (haptable demo flow --record FILE)")
    p.add_argument(
        "--vision-only",
        action="store_true",
        help="only vision and gestures, as fast as possible (default: the recorded demo at "
        "its recorded pace, its plans compared too)",
    )


def run(args, ctx) -> int:
    if args.vision_only:
        from .replay import replay  # lazy: the vision stages load when replaying

        same, line = replay(args.file, ctx.profile, ctx.pm)
    else:
        from .replay_demo import replay_demo  # lazy: the demo loads when replaying

        same, line = replay_demo(args.file, ctx)
    print(line)
    return 0 if same else 1
