"""What the vibrotactile commands share: option types from ``[vibrotactile]`` keys,
progress on stderr, the profile's settings, the map argument (``measured``), points and
tables from the command line."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from console.plugin_api import Limits, UserError, from_field, load_map
from plugins.vibrotactile.settings import field, setup_from_profile
from plugins.vibrotactile.thresholds import Perception


def key_type(name: str, unit: str = ""):
    """The option type of one overriding ``[vibrotactile] name``: the key's range."""
    return from_field(field("vibrotactile", name), unit=unit)


def progress_printer(min_s: float = 1.0):
    """A progress callback for the CLI: prints to stderr once the work passed ``min_s``."""
    t0 = time.perf_counter()
    state = {"shown": False}

    def cb(frac: float, msg: str) -> None:
        if time.perf_counter() - t0 < min_s and frac < 1.0:
            return
        if frac >= 1.0 and not state["shown"]:
            return
        state["shown"] = True
        bar = "#" * int(frac * 30)
        end = "\n" if frac >= 1.0 else ""
        print(f"\r{msg} [{bar:<30}] {frac * 100:3.0f}%", end=end, file=sys.stderr, flush=True)

    return cb


def vt_section(ctx) -> dict:
    """The profile's ``[vibrotactile]`` section."""
    return ctx.profile.section("vibrotactile")


def settings_of(ctx):
    """Stimulus settings from the profile (the registered effects read the same)."""
    return setup_from_profile(ctx.profile).settings


def piezo_limits(ctx) -> dict:
    """The piezo range the safety gate allows (profile limits and amplifier/card reach)."""
    lo, hi = Limits.from_profile(ctx.profile).piezo_range()
    return {
        "piezo_min_v": lo,
        "piezo_max_v": hi,
        "max_plan_s": float(ctx.profile.get("limits.max_plan_s")),
    }


def perception_of(ctx):
    return Perception.from_section(ctx.profile.section("perception"))


def cache_dir_of(args, ctx) -> Path | None:
    # lazy: this module loads at every haptable start; cache only when used
    from plugins.vibrotactile.cache import default_cache_dir

    raw = getattr(args, "cache_dir", None) or vt_section(ctx)["cache_dir"]
    if raw == "none":
        return None
    return Path(raw).expanduser() if raw else default_cache_dir()


#: the map argument naming the profile's measured map (HapTable's one cache)
MEASURED = "measured"
MAP_HELP = (
    "a vibration map (.npz), or 'measured': the profile's measured map, the file the "
    "console's Vibration screen and the flow demo use (measured first when there is none)"
)


def map_source(source: str, ctx) -> str:
    """``source``, or for ``measured`` (when no file has that name) the profile's measured
    map in HapTable's cache (``console.runtime.measured_map``), measured with the profile's
    vibrometer first when the cache has none."""
    if source != MEASURED or Path(source).exists():
        return source
    # lazy: the runtime part loads on first use, not at every haptable start
    from console.plugin_api.runtime import measured_map_file

    return str(measured_map_file(ctx.profile, ctx.pm, progress_printer()))


def sample_rate(ctx) -> float:
    return float(ctx.profile.get("audio.sample_rate_hz"))


def parse_point(text: str, vmap):
    """``51`` (point id: the map's node number) -> map index; ``x,y`` (mm) -> (x, y), finite."""
    t = text.strip()
    hint = "give a point id of the map (its node number) or x,y in mm (e.g. 300,200)"
    if "," in t:
        try:
            x, y = (float(v) for v in t.split(","))
        except ValueError:
            raise UserError(f"point {text!r}: {hint}") from None
        if not (np.isfinite(x) and np.isfinite(y)):
            raise UserError(f"point {text!r}: x and y must be finite numbers in mm; {hint}")
        return (x, y)
    try:
        num = int(t)
    except ValueError:
        raise UserError(f"point {text!r}: {hint}") from None
    return vmap.point_index(num)


def tables_for(path: str, ctx, args, band_hz: float | None = None):
    """Tables from a tables file, or built (and cached) from a vibration map."""
    # lazy: this module loads at every haptable start; lazy, tables, vibration_io only when used
    from plugins.vibrotactile.lazy import tables_cached
    from plugins.vibrotactile.tables import load_tables
    from plugins.vibrotactile.vibration_io import is_tables_file

    path = map_source(path, ctx)
    if is_tables_file(path):
        t = load_tables(path, sample_rate_hz=sample_rate(ctx))
        want = getattr(args, "rule", None)
        if want is not None and want != t.rule:
            raise UserError(
                f"{path}: tables built with the {t.rule} rule, not {want}; rebuild them with "
                f"`haptable tables build MAP --out FILE --rule {want}` or give the map"
            )
        return t
    vm = load_map(
        path,
        require_all=not getattr(args, "allow_missing", False),
    )
    c, per = table_rule_of(ctx, args)
    return tables_cached(
        vm,
        band_hz or vt_section(ctx)["band_hz"],
        cache_dir_of(args, ctx),
        progress_printer(),
        min_contrast_db=c,
        perceptual=per,
    )


def table_rule_of(ctx, args):
    """(min_contrast_db, PerceptualRule or None) from ``--rule``/``--min-contrast-db`` and
    the profile's ``[vibrotactile] table_rule`` and ``min_contrast_db``."""
    # lazy: this module loads at every haptable start; perceptual only when used
    from plugins.vibrotactile.perceptual_rule import rule_from_profile

    c = getattr(args, "min_contrast_db", None)
    rule = getattr(args, "rule", None)
    if rule is None:  # as the effects' Setup.rule_of: a contrast floor is the paper's rule
        floor = c is not None or float(vt_section(ctx).get("min_contrast_db", 0.0)) > 0
        rule = "paper" if floor else str(vt_section(ctx).get("table_rule", "perceptual"))
    if rule == "paper":
        c = float(vt_section(ctx).get("min_contrast_db", 0.0)) if c is None else float(c)
        return c, None
    if c:
        raise UserError(
            f"--min-contrast-db {c:g} applies to --rule paper only; the perceptual rule "
            "weighs contrast itself"
        )
    return 0.0, rule_from_profile(ctx.profile, sample_rate(ctx))


def add_rule_option(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--rule",
        choices=("perceptual", "paper"),
        default=None,
        help="table rule. perceptual: the entry the finger tells apart best (felt "
        "active-minus-passive difference in JND above the [perception] threshold, at the "
        "drive the amplifier can deliver, inside [vibrotactile] play_band_hz); paper: "
        "largest displacement difference (Fig. 8). Default: profile [vibrotactile] "
        "table_rule (perceptual); a tables file keeps the rule it was built with",
    )
