"""``haptable replay FILE``: a recording's frames through the same pipeline; one line:
every decision the same (exit 0) or the first difference (exit 1). A study's recorded
trials (a folder, or a ``haptable-study-trial`` file) are replayed by ``haptable study
replay`` (its stimuli re-rendered from the recorded parameters)."""

from __future__ import annotations

import argparse


def configure(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "file",
        help="a recording (haptable demo flow --record FILE), or a study's recorded trials "
        "(haptable study run ... --record: a trial file or the folder)",
    )
    p.add_argument(
        "--vision-only",
        action="store_true",
        help="only vision and gestures, as fast as possible (default: the recorded demo at "
        "its recorded pace, its plans compared too)",
    )


def _study_command(path: str, ctx) -> int | None:
    """A study's recording goes to the command that made it (``haptable study replay``,
    through its registration: the recorder knows no study code); ``None``: not one."""
    from pathlib import Path

    p = Path(path).expanduser()
    study = ctx.pm.commands.get("study")
    if study is None or not (p.is_dir() or _study_format(p)):
        return None
    parser = argparse.ArgumentParser(prog="haptable study")
    study.configure(parser)
    return study.run(parser.parse_args(["replay", str(p)]), ctx)


def _study_format(p) -> bool:
    """Whether ``p`` is an HDF5 file of a study's trial (``haptable-study-trial``)."""
    if not p.is_file():
        return False
    try:
        import h5py  # lazy: only when replaying

        with h5py.File(p, "r") as f:
            fmt = f.attrs.get("format", "")
    except OSError:
        return False
    return (fmt.decode() if isinstance(fmt, bytes) else str(fmt)) == "haptable-study-trial"


def run(args, ctx) -> int:
    code = _study_command(args.file, ctx)
    if code is not None:
        return code
    if args.vision_only:
        from .replay import replay  # lazy: the vision stages load when replaying

        same, line = replay(args.file, ctx.profile, ctx.pm)
    else:
        from .replay_demo import replay_demo  # lazy: the demo loads when replaying

        same, line = replay_demo(args.file, ctx)
    print(line)
    return 0 if same else 1
