"""``haptable signals import FILE`` and ``haptable signals export NAME``: AHAP and Meta's
``.haptic`` files into and out of the signal library (``console.signals.haptic_files``
has the mapping)."""

from __future__ import annotations

import math
import re
from pathlib import Path

from console.core.errors import UserError
from console.safety import Limits

FORMATS = {".ahap": "ahap", ".haptic": "haptic"}
_LEVEL = re.compile(r"^\s*(-?\d+(?:\.\d+)?)\s*(V|dB)\s*$")


def configure(sub) -> None:
    """The two subcommands, on ``haptable signals``' subparsers."""
    imp = sub.add_parser("import", help="import an AHAP or .haptic file into the library")
    imp.add_argument("file")
    imp.add_argument("--name", help="library name (default: from the file name)")
    imp.add_argument("--level", help="peak for intensity 1: e.g. 40 V or 30 dB (re 1 V peak)")
    imp.add_argument("--format", choices=("ahap", "haptic"), help="default: from the suffix")
    imp.add_argument("--replace", action="store_true", help="replace a signal of that name")
    exp = sub.add_parser("export", help="write a signal as an AHAP or .haptic file")
    exp.add_argument("signal", help="a library name or an expression")
    exp.add_argument("--format", choices=("ahap", "haptic"), required=True)
    exp.add_argument("-o", "--out", required=True, help="the file to write")
    exp.add_argument("--level", help="the peak intensity 1 stands for (default: as import)")


def scale_for(profile, level: str | None, *, capped: bool = True):
    """The ``Scale`` of ``console.signals.haptic_files`` for this profile and ``--level``."""
    # lazy: the haptic file modules load only for these two commands
    from console.signals.haptic_files import MIN_BAND_HZ, Scale

    limits = Limits.from_profile(profile)
    lo_v, hi_v = limits.piezo_range()
    safe_v = min(-lo_v, hi_v)
    peak_v = safe_v
    if level is not None:
        m = _LEVEL.match(level)
        if not m:
            raise UserError(f"--level {level!r}: give a peak in V or dB re 1 V, e.g. 40 V or 30 dB")
        value = float(m.group(1))
        peak_v = value if m.group(2) == "V" else 10 ** (value / 20)
        if not (math.isfinite(peak_v) and peak_v > 0):
            raise UserError(f"--level {level!r}: give a peak above 0 V")
        if capped and peak_v > safe_v + 1e-9:
            raise UserError(
                f"--level {level!r} = {peak_v:.4g} V is above the {safe_v:g} V a sine may reach "
                f"on the patches ([limits] piezo_min_v..piezo_max_v, the card's full scale x "
                f"gain); give at most {safe_v:g} V"
            )
    band = profile.get("vibrotactile.play_band_hz", [0.0, 625.0])
    lo_hz, hi_hz = max(float(band[0]), MIN_BAND_HZ), float(band[-1])
    if hi_hz <= lo_hz * 1.01:
        raise UserError(
            f"[vibrotactile] play_band_hz = {list(band)}: the carrier needs a band above "
            f"{MIN_BAND_HZ:g} Hz; give e.g. [0.0, 625.0]"
        )
    return Scale(peak_v, lo_hz, hi_hz, limits.ramp_samples / limits.sample_rate_hz,
                 limits.sample_rate_hz, float(profile.get("limits.max_plan_s")))  # fmt: skip


def _format(path: Path, given: str | None) -> str:
    """The format of ``path``: ``given`` (``--format``), else from its suffix; a folder
    is said to be one (its empty suffix told nothing), with what to give instead."""
    if path.is_dir():
        raise UserError(
            f"{path} is a folder, not a file: give the .ahap or .haptic file to import "
            f"(e.g. {path / 'pattern.ahap'})"
        )
    if given:
        return given
    fmt = FORMATS.get(path.suffix.lower())
    if fmt is None:
        raise UserError(
            f"{path}: cannot tell the format from the suffix {path.suffix!r}; name the file "
            ".ahap or .haptic, or give --format ahap|haptic"
        )
    return fmt


def run_import(args, ctx, lib_path: Path) -> int:
    """Read the file, write its breakpoints to ``signals/NAME.json`` beside the library,
    then save ``NAME`` = an expression naming them (``@NAME``). If the save is refused,
    the data file is put back as it was (or removed): the library never points at data
    it did not save with."""
    # lazy: the haptic file modules load only for these two commands
    from console.config.signal_library import add_signal, check_name, read_library
    from console.signals import ahap, breakpoint_data, meta_haptic
    from console.signals.haptic_files import safe_name, to_data

    path = Path(args.file).expanduser()
    fmt = _format(path, args.format)
    scale = scale_for(ctx.profile, args.level)
    name = check_name(args.name or safe_name(path))
    if name in read_library(lib_path).raw and not args.replace:
        raise UserError(f"signal {name!r} is already in {lib_path}; choose another name "
                        "(--name) or replace it (--replace)")  # fmt: skip
    pattern = (ahap if fmt == "ahap" else meta_haptic).read(path)
    expr, curves, summary = to_data(pattern, scale, name)
    limits = Limits.from_profile(ctx.profile)
    desc = f"imported from {path.name}"[:200]
    data_file = breakpoint_data.data_path(lib_path, name)
    old = data_file.read_bytes() if data_file.is_file() else None
    breakpoint_data.write(lib_path, name, curves, path.name)
    try:
        add_signal(lib_path, name, expr, desc, replace=args.replace, limits=limits)
    except BaseException:
        if old is None:
            data_file.unlink(missing_ok=True)
        else:
            data_file.write_bytes(old)
        raise
    print(f"imported {summary}")
    print(f"breakpoints in {data_file}")
    print(f"saved {name} in {lib_path}")
    return 0


def run_export(args, ctx, name: str, node) -> int:
    # lazy: the haptic file modules load only for these two commands
    from console.files.atomic import write_text_atomic
    from console.signals import ahap, meta_haptic
    from console.signals.design import render
    from console.signals.haptic_files import export_signal

    scale = scale_for(ctx.profile, args.level, capped=False)
    x = render(node, scale.fs, max_s=scale.max_s, what=name)
    e = export_signal(x, scale, name)
    desc = f"{name} from HapTable: intensity 1 = {scale.peak_v:g} V peak, carrier " \
        f"{scale.lo_hz:g}-{scale.hi_hz:g} Hz"  # fmt: skip
    text = (ahap if args.format == "ahap" else meta_haptic).write(e, desc)
    out = Path(args.out).expanduser()
    if not out.parent.is_dir():
        raise UserError(f"-o {args.out}: no folder {out.parent}; give a path in an existing folder")
    try:
        write_text_atomic(out, text, mode=0o644)
    except OSError as exc:
        raise UserError(f"{args.out}: cannot write it ({exc.strerror or exc}); give -o a "
                        "path in a folder you can write") from None  # fmt: skip
    notes = f"; {'; '.join(e.notes)}" if e.notes else ""
    print(
        f"wrote {args.out} ({args.format}): {e.duration_s:.3f} s, {e.amp.size} intensity and "
        f"{e.sharp.size} sharpness breakpoints, intensity 1 = {scale.peak_v:g} V{notes}"
    )
    return 0
