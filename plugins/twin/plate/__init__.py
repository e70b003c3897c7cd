"""Plate twin plugin: glass modes, piezo coupling, FRFs and a simulated vibrometer.

Profile sections declared here: [glass], [plate], [piezo], [vibrometer]. The geometry
comes from the core's [table], [grid] and [patches.*]. Registers the ``twin`` vibrometer
(``[vibrometer] driver``), the ``plate`` command and the ``plate`` and ``closed-loop``
benchmarks; ``closed_loop`` plays recorded outputs into the twin.

The ``twin`` vibrometer's ``measure(progress=)`` calls ``progress(done, total)`` after each
excitation's responses and each averaged sweep; an exception raised in ``progress`` (an
operator's cancel) stops the measurement and propagates.
"""

from __future__ import annotations

from console.plugin_api import DeviceStatus, Field, hookimpl

from . import cli
from . import defaults as dflt


@hookimpl
def haptable_profile_sections(register) -> None:
    register(
        "glass",
        {
            "youngs_modulus_gpa": Field(
                "float",
                dflt.GLASS_E_GPA,
                min=1.0,
                max=500.0,
                help="glass Young's modulus (soda-lime ~72 GPa, recalled)",
            ),
            "poisson_ratio": Field(
                "float", dflt.GLASS_NU, min=0.0, max=0.49, help="glass Poisson ratio (~0.22)"
            ),
            "density_kg_m3": Field(
                "float", dflt.GLASS_RHO, min=100.0, max=20000.0, help="glass density (~2500)"
            ),
        },
        help="Touch-screen glass material (FACTS: recalled defaults).",
    )
    register(
        "plate",
        {
            "damping_ratio": Field(
                "float",
                dflt.DAMPING_RATIO,
                min=1e-5,
                max=0.3,
                help="modal damping ratio, all modes (no sourced value; 0.5-3 % plausible)",
            ),
            "seal_translational_n_per_m2": Field(
                "float",
                dflt.SEAL_KT_N_PER_M2,
                min=0.0,
                help="rubber seal stiffness per metre of edge against deflection (N/m per m)",
            ),
            "seal_rotational_n_per_rad": Field(
                "float",
                dflt.SEAL_KR_N_PER_RAD,
                min=0.0,
                help="rubber seal stiffness per metre of edge against edge rotation (N m/rad per m)",
            ),
            "seal_edge_scale": Field(
                "floats",
                [1.0, 1.0, 1.0, 1.0],
                length=4,
                min=0.0,
                help="seal stiffness factor per edge x=0, x=width, y=0, y=height (0: no seal)",
            ),
            "band_max_hz": Field(
                "float",
                dflt.BAND_MAX_HZ,
                min=1.0,
                max=20000.0,
                help="top of the band the FRFs are used in (the sweep's top)",
            ),
            "mode_margin": Field(
                "float",
                dflt.MODE_MARGIN,
                min=1.0,
                max=20.0,
                help="keep modes up to mode_margin x band_max_hz",
            ),
            "static_residual": Field(
                "bool", True, help="add the static response of the modes left out"
            ),
            "basis_order": Field(
                "int",
                dflt.BASIS_ORDER,
                min=8,
                max=40,
                help="Legendre polynomials per direction in the Ritz basis",
            ),
        },
        help="Plate twin: seals, damping, modal truncation.",
    )
    register(
        "piezo",
        {
            "d31_pc_per_n": Field(
                "float",
                dflt.D31_PC_PER_N,
                min=-2000.0,
                max=2000.0,
                help="piezo charge constant d31 (DuraAct ~-180 pC/N, recalled)",
            ),
            "ceramic_thickness_mm": Field(
                "float",
                dflt.CERAMIC_THICKNESS_MM,
                min=0.01,
                max=5.0,
                help="active ceramic thickness (DuraAct ~0.2 mm)",
            ),
            "youngs_modulus_gpa": Field(
                "float",
                dflt.CERAMIC_E_GPA,
                min=1.0,
                max=500.0,
                help="ceramic Young's modulus (PZT ~62 GPa, recalled)",
            ),
        },
        help="Piezo patches: pin-force coupling constants.",
    )
    register(
        "vibrometer",
        {
            "driver": Field(
                "str",
                "twin",
                help="vibrometer plugin that measures the map (twin: the simulated LDV on "
                "the plate twin; a lab registers its real one)",
            ),
            "sweep_start_hz": Field("float", 0.0, min=0.0, help="linear sweep start"),
            "sweep_stop_hz": Field(
                "float", dflt.BAND_MAX_HZ, min=1.0, help="linear sweep stop (paper: 625 Hz)"
            ),
            "sweep_s": Field("float", dflt.SWEEP_DURATION_S, min=0.1, help="sweep duration"),
            "record_s": Field(
                "float",
                dflt.RECORD_S,
                min=0.1,
                help="analyser record per sweep (>= sweep_s; frequency step 1/record_s)",
            ),
            "sample_rate_hz": Field(
                "float", dflt.SAMPLE_RATE_HZ, min=100.0, help="analyser sample rate"
            ),
            "generator_vpp": Field(
                "float",
                dflt.SWEEP_GENERATOR_VPP,
                min=0.0,
                help="generator sweep amplitude, peak to peak (x piezo_gain at the patch)",
            ),
            "sweeps": Field("int", dflt.SWEEPS, min=1, max=100, help="sweeps averaged (H1)"),
            "noise_um_per_s_per_sqrt_hz": Field(
                "float",
                dflt.NOISE_UM_PER_S_PER_SQRT_HZ,
                min=0.0,
                help="LDV velocity noise density (assumed)",
            ),
            "mask_below_hz": Field(
                "float",
                dflt.MASK_BELOW_HZ,
                min=0.0,
                help="bins below this are masked (velocity -> displacement blows up at DC)",
            ),
            "seed": Field("int", 0, min=0, help="noise seed (reproducible measurements)"),
        },
        help="Simulated laser-vibrometer measurement of the plate twin.",
    )


@hookimpl
def haptable_register_vibrometers(register) -> None:
    def factory(profile):
        # lazy: vibrometer loads when called, not at every haptable start
        from .vibrometer import TwinVibrometer

        return TwinVibrometer(profile)

    def probe(profile) -> DeviceStatus:
        return DeviceStatus(
            "vibrometer",
            "twin",
            "simulated",
            "plate twin: simulated laser vibrometer (linear sweep, H1 over 3 sweeps)",
        )

    register(
        "twin",
        factory,
        description="simulated laser vibrometer on the plate twin",
        probe=probe,
    )


@hookimpl
def haptable_register_observers(register) -> None:
    def factory(profile):
        # lazy: observer loads when called, not at every haptable start
        from .observer import TwinObserver

        return TwinObserver(profile)

    register(
        "twin",
        factory,
        description="simulated participant: the plate twin's vibration under the finger or "
        "hand, threshold, JND, lapse (plate/observer.py)",
    )


@hookimpl
def haptable_register_commands(register) -> None:
    register("plate", cli.configure, cli.run, help="plate twin: natural modes")


@hookimpl
def haptable_register_benchmarks(register) -> None:
    def run(ctx, quick: bool) -> dict:
        # lazy: bench loads when called, not at every haptable start
        from .bench import run_bench

        return run_bench(getattr(ctx, "profile", None), quick)

    register("plate", run, help="modal solve vs basis size, FRF truncation, vibrometer time")

    def run_loop(ctx, quick: bool) -> dict:
        # lazy: loop_bench loads when called, not at every haptable start
        from .loop_bench import run_bench as run_loop_bench

        return run_loop_bench(ctx, quick)

    register(
        "closed-loop",
        run_loop,
        help="flows played through the gate into the plate twin: predicted vs achieved margins",
    )

    def run_localisation(ctx, quick: bool) -> dict:
        # lazy: localisation loads when called, not at every haptable start
        from .localisation import run_bench as run_localisation_bench

        return run_localisation_bench(ctx, quick)

    register(
        "localisation",
        run_localisation,
        help="paper tables vs independent patches vs time reversal, played into the plate "
        "twin: achieved contrast over grid pairs and under hands, drive volts, map error",
    )
