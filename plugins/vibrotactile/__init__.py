"""Localized vibrotactile feedback: vibration map I/O, interpolation, excitation lookup
tables, flow stimuli (between two points, under a hand) and the ``vibration`` benchmark.

Effects (``haptable_register_effects``): ``flow`` (between two points), ``hand_flow``
(under a hand) and ``point`` (a pulse); see ``plugins.vibrotactile.effects`` for the
request vocabulary. The ``flow`` effect also gives the lookup tables (``tables(vmap=,
progress=)``, built step by step with progress and cancel; ``query(active, passive,
vmap=)``), ``prepare``/``cached`` and UFF import (``import_map({"PA": path, ...})``):
``plugins.vibrotactile.registered``. Commands: ``haptable frf import|export|info``,
``haptable tables build|query``, ``haptable flow``, ``haptable point``. Profile sections:
``[vibrotactile]`` and ``[perception]`` (the human threshold curve, as data).
"""

from __future__ import annotations

from console.hookspecs import hookimpl
from console.schema import Field


def _sections() -> dict:
    from plugins.vibrotactile.perception import (
        DEFAULT_FREQ_HZ,
        DEFAULT_THRESHOLD_DB,
        DEFAULT_WEBER_FRACTION,
        DEFAULT_WEBER_FREQ_HZ,
        SOURCES,
    )

    return {
        "perception": (
            {
                "freq_hz": Field(
                    "floats",
                    list(DEFAULT_FREQ_HZ),
                    min=0.1,
                    max=20000,
                    min_length=2,
                    help="frequencies of the threshold curve (ascending)",
                ),
                "threshold_db_re_1um": Field(
                    "floats",
                    list(DEFAULT_THRESHOLD_DB),
                    min=-80,
                    max=80,
                    min_length=2,
                    help="palm detection threshold, dB re 1 um peak, per frequency",
                ),
                "fingertip_offset_db": Field(
                    "float", 6.0, min=-40, max=40, help="fingertip threshold above the palm's"
                ),
                "jnd_db": Field(
                    "float", 1.5, min=0.1, max=10, help="intensity just-noticeable difference"
                ),
                "weber_freq_hz": Field(
                    "floats",
                    list(DEFAULT_WEBER_FREQ_HZ),
                    min=0.1,
                    max=20000,
                    min_length=1,
                    help="frequencies of the Weber fraction curve (ascending)",
                ),
                "weber_fraction": Field(
                    "floats",
                    list(DEFAULT_WEBER_FRACTION),
                    min=0.01,
                    max=10,
                    min_length=1,
                    help="amplitude Weber fraction per frequency: one JND is 20 log10(1 + w) "
                    "dB (perceptual tables count felt differences in these JNDs)",
                ),
                "sources": Field("str", SOURCES, help="where the curve comes from"),
            },
            "human vibrotactile sensitivity: threshold vs frequency (palm), fingertip offset, JND",
        ),
        "vibrotactile": (
            {
                "band_hz": Field(
                    "float", 650.0, min=1, max=20000, help="usable band for tables and flows"
                ),
                "mask_below_hz": Field(
                    "float",
                    5.0,
                    min=0,
                    max=1000,
                    help="UFF import: bins below are masked (near-DC)",
                ),
                "interpolation": Field(
                    "str",
                    "spline",
                    choices=("spline", "keys", "bilinear"),
                    help="FRF interpolation off the grid",
                ),
                "part_s": Field("float", 1.5, min=0.05, max=30, help="duration of each flow part"),
                "pulse_s": Field("float", 0.5, min=0.05, max=30, help="duration of a point pulse"),
                "ramp_ms": Field(
                    "float", 100.0, min=5, max=5000, help="linear ramp at each end of a part"
                ),
                "gap_ms": Field(
                    "float",
                    0.0,
                    min=0,
                    max=5000,
                    help="extra silence between the parts (beyond the relay guard)",
                ),
                "min_contrast_db": Field(
                    "float",
                    0.0,
                    min=0,
                    max=60,
                    help="tables: a pair's entry must have at least this active/passive "
                    "contrast (ranked by difference among those); 0: the paper's rule "
                    "(largest absolute difference, Fig. 8)",
                ),
                "table_rule": Field(
                    "str",
                    "perceptual",
                    choices=("perceptual", "paper"),
                    help="lookup-table rule: perceptual (largest felt active-minus-passive "
                    "difference in JND at the flow's level) or paper (largest displacement "
                    "difference, Fig. 8)",
                ),
                "play_band_hz": Field(
                    "floats",
                    [0.0, 625.0],
                    min=0,
                    max=20000,
                    min_length=2,
                    help="band the amplifier and patches are known to play (perceptual "
                    "tables): the paper measured its map with a 0-625 Hz sweep through the "
                    "E413.D2 amplifier (section 4)",
                ),
                "ringdown_gap_k": Field(
                    "float",
                    0.0,
                    min=0,
                    max=20,
                    help="silence between flow parts >= k decay times 1/(2 pi zeta f) of "
                    "part 1's mode (k >= SL/8.7 puts its ring below threshold); 0: off",
                ),
                "ringdown_zeta": Field(
                    "float",
                    0.0,
                    min=0,
                    max=0.5,
                    help="modal damping for the ring-down gap; 0: from the map's "
                    "half-power bandwidth (1 % where it is not resolved)",
                ),
                "sensation_level_db": Field(
                    "float", 20.0, min=0, max=60, help="target level above the fingertip threshold"
                ),
                "method": Field(
                    "str",
                    "auto",
                    choices=("auto", "paper", "independent", "time_reversal"),
                    help="flow and point rendering: paper (one actuator or all four per "
                    "part, the tables), independent (an amplitude and phase per patch), "
                    "time_reversal; auto: independent when [audio] channels give each "
                    "patch its own channel, else paper",
                ),
                "map_error_rel": Field(
                    "float",
                    0.05,
                    min=1e-4,
                    max=1,
                    help="independent patches: the map's error (std / the bin's RMS |H|) "
                    "the per-patch solution must survive (regularises the cancellation)",
                ),
                "drive_max_v": Field(
                    "float",
                    95.0,
                    min=1,
                    max=1000,
                    help="largest sine amplitude at the piezo (also capped by [limits])",
                ),
                "hand_mm": Field(
                    "float", 120.0, min=20, max=400, help="side of the area under a hand"
                ),
                "hand_squares": Field(
                    "int", 3, min=2, max=9, help="squares per side under the hand"
                ),
                "hand_subgrid": Field(
                    "int", 15, min=1, max=60, help="subgrid points per square side"
                ),
                "cache_dir": Field(
                    "str",
                    "",
                    choices=("", "none"),
                    help="tables and flow plans on disk: empty = HapTable's one cache "
                    "(~/.cache/haptable, $HAPTABLE_CACHE_DIR), 'none' = computed every time",
                ),
            },
            "vibration map use: tables, interpolation, flow stimuli",
        ),
    }


def field(section: str, key: str) -> Field:
    """The declared field of ``[section] key`` (a command-line option overriding the key
    takes its range: ``console.options.from_field``)."""
    return _sections()[section][0][key]


@hookimpl
def haptable_profile_sections(register) -> None:
    for name, (fields, help_) in _sections().items():
        register(name, fields, help=help_)


def _effect(cls_name: str, module: str = "effects"):
    def factory(profile):
        import importlib

        return getattr(importlib.import_module(f"plugins.vibrotactile.{module}"), cls_name)(profile)

    factory.__doc__ = f"``plugins.vibrotactile.{module}.{cls_name}(profile)``"
    return factory


@hookimpl
def haptable_register_effects(register) -> None:
    # flow also offers: tables(vmap=, progress=) (stepwise, cancellable: raise in
    # progress), query(active, passive, vmap=), prepare(pairs, vmap=, progress=),
    # cached(...), import_map({"PA": "pa.uff", ...}) -> VibrationMap (UFF 58)
    register(
        "flow",
        _effect("RegisteredFlowEffect", "registered"),
        description="two-point flow (paper Fig. 9): render(from_point=, to_point=, vmap=|tables=)",
    )
    register(
        "hand_flow",
        _effect("HandFlowEffect"),
        description="flow under a hand: render(center_mm=, direction=, vmap=, hand_mm=)",
    )
    register(
        "point",
        _effect("PointEffect"),
        description="localized pulse at one point: render(point=, vmap=|tables=)",
    )


@hookimpl
def haptable_register_commands(register) -> None:
    from plugins.vibrotactile import cli

    register(
        "frf", cli.configure_frf, cli.run_frf, help="vibration map: import/export UFF 58, info"
    )
    register(
        "tables",
        cli.configure_tables,
        cli.run_tables,
        help="excitation lookup tables: build, query",
    )
    register(
        "flow",
        cli.configure_flow,
        cli.run_flow,
        help="vibrotactile flow between points or under a hand",
    )
    register("point", cli.configure_point, cli.run_point, help="localized pulse at one point")


@hookimpl
def haptable_register_benchmarks(register) -> None:
    def run(ctx, quick: bool, report_dir: str | None = None) -> dict:
        from plugins.vibrotactile.bench import run_bench

        return run_bench(ctx, quick, report_dir=report_dir)

    register(
        "vibration",
        run,
        help="interpolation error vs time, table build/query, flow-under-hand precompute",
    )
