"""``haptable frf measure --sensor accelerometer``: the vibration map from a roving sensor
on the sound card's inputs (``plugins.vibrotactile.roving_run``), no laser needed."""

from __future__ import annotations

import argparse
import sys

from console.plugin_api import UserError, finite_float, positive_int

LEVEL = finite_float(0.1, 100.0, unit="V", note="the chirp's peak at the patches, e.g. 20")


def add_roving_options(m: argparse.ArgumentParser) -> None:
    m.add_argument(
        "--sensor",
        choices=("accelerometer",),
        default=None,
        help="measure with the sensor on the sound card's inputs ([audio_inputs]) instead of "
        "the vibrometer: the console says where to glue it, point by point (the twin moves "
        "its own); needs --out; run again to resume after a stop",
    )
    m.add_argument("--fast", action="store_true", help="twin: fast-forward, not real time")
    m.add_argument(
        "--level-v",
        type=LEVEL,
        default=90.0,
        help="chirp peak at the patches below --knee-hz (with 6 repeats, 90: the twin's "
        "20-100 Hz p95 error 0.7 dB, 20: 1.1 dB; the sensor's noise wins where the plate "
        "barely accelerates)",
    )
    m.add_argument(
        "--knee-hz",
        type=finite_float(0.0, 1e4, unit="Hz", note="0 for a flat chirp, e.g. 300"),
        default=300.0,
        help="above it the chirp's amplitude falls as knee/f, keeping the sensor within its "
        "input range where the plate's acceleration grows (0: flat)",
    )
    m.add_argument(
        "--repeats",
        type=positive_int(100),
        default=6,
        help="chirps per excitation (at 20 V, 6: 20-100 Hz p95 error 1.1 dB, 3: 2.2 dB on the twin; "
        "each repeat adds 5 x 2.25 s of audio per point)",
    )
    m.add_argument(
        "--points",
        default=None,
        help="only these grid points, e.g. 1,12,84 (default: every point)",
    )
    m.add_argument(
        "--sensor-mass-g",
        type=finite_float(0.01, 500.0, unit="g", note="the sensor's mass, e.g. 7"),
        default=None,
        help="take the sensor's mass out of the map (structural modification, "
        "plugins/vibrotactile/mass_correction.py); the loaded map is kept in MAP.npz.parts/",
    )
    m.add_argument(
        "--dummy-mass-g",
        type=finite_float(0.01, 500.0, unit="g", note="the clip-on dummy's mass, e.g. 14"),
        default=None,
        help="cancel the sensor's mass exactly: each point is measured again with a dummy "
        "of this mass clipped on the sensor (the console asks for it), and 1/H = (1+r)/H_s "
        "- r/H_s+d, r = sensor/dummy mass (plugins/vibrotactile/mass_cancel.py); needs "
        "--sensor-mass-g; doubles the audio time; a dummy 2x the sensor costs less noise",
    )
    m.add_argument(
        "--delay-samples",
        type=finite_float(0.0, 1e6, unit="samples"),
        default=0.0,
        help="the converters' round trip when no loopback input is named",
    )


def _points(spec: str | None, n: int) -> list[int]:
    if not spec:
        return list(range(n))
    try:
        got = [int(p) for p in spec.split(",") if p.strip()]
    except ValueError:
        raise UserError(f"--points {spec!r}: give point numbers, e.g. 1,12,84") from None
    bad = [p for p in got if not 1 <= p <= n]
    if bad or not got:
        raise UserError(f"--points {spec!r}: give point numbers 1..{n}, e.g. 1,12,84")
    return [p - 1 for p in got]


def measure_roving(args, ctx) -> int:
    # lazy: numpy, the outputs client and the run load only when measuring
    import numpy as np

    from console.plugin_api import find_input, input_specs
    from console.plugin_api.runtime import move_sensor, open_outputs
    from plugins.vibrotactile.roving import RovingSettings
    from plugins.vibrotactile.roving_run import RovingRun

    if not args.out:
        raise UserError("--sensor: give --out MAP.npz (its journal is kept beside it)")
    g = ctx.profile.section("grid")
    rows, cols, pitch = int(g["rows"]), int(g["columns"]), float(g["pitch_mm"])
    ox, oy = g["origin_mm"]
    k = np.arange(rows * cols)
    pts = np.column_stack([ox + (k % cols) * pitch, oy + (k // cols) * pitch])
    idx = _points(args.points, len(pts))
    twin = ctx.profile.get("audio.driver") == "twin"
    spec = find_input(input_specs(ctx.profile), args.sensor)
    sensor = (
        spec.to_json()
        if spec
        else {"kind": args.sensor, "name": "accel", "note": "the twin's default input"}
    )
    if spec is None and not twin:
        raise UserError(
            f"{ctx.profile.path}: no {args.sensor} among [audio_inputs]; add "
            f"[audio_inputs.accel] channel = 1, kind = '{args.sensor}', sensitivity = 10.2"
        )
    if twin:
        sensor["mass_g"] = float(ctx.profile.get("twin_inputs.sensor_mass_g") or 7.0)
    settings = RovingSettings(level_v=args.level_v, knee_hz=args.knee_hz, repeats=args.repeats)
    dummy_g = args.dummy_mass_g
    if dummy_g is not None:
        # lazy: the cancellation only for a run with a dummy
        from plugins.vibrotactile.mass_cancel import check_masses

        check_masses(args.sensor_mass_g, dummy_g)
        real_g = sensor.get("mass_g")  # the twin's sensor; on a table the one stated
        sensor["mass_g"] = float(args.sensor_mass_g)
    # the map's measurement holds the table: the console's plays would be measured too
    with (
        ctx.holding_table(),
        open_outputs(ctx.profile, ctx.pm, fast=True if args.fast else None) as out,
    ):
        run = RovingRun(
            out,
            args.out,
            pts[idx],
            settings,
            sensor=sensor,
            delay_default=args.delay_samples,
            dummy_mass_g=dummy_g,
        )

        def place(point: int, x_mm: float, y_mm: float) -> None:
            n = idx[point - 1] + 1
            if twin:
                move_sensor(out, x_mm, y_mm)  # the operator's move, simulated
                return
            print(f"glue the sensor on grid point {n} ({x_mm:.0f}, {y_mm:.0f}) mm, then Enter")
            sys.stdin.readline()

        def report(done: int, total: int, text: str) -> None:
            print(f"[{done}/{total}] {text}", flush=True)

        def dummy(point: int, x_mm: float, y_mm: float, on: bool) -> None:
            if twin:  # the twin's sensor gets the dummy's mass (its own: the profile's)
                move_sensor(out, x_mm, y_mm, (real_g or 0.0) + (dummy_g if on else 0.0))
                return
            what = f"clip the {dummy_g:g} g dummy on the sensor" if on else "remove the dummy"
            print(f"point {idx[point - 1] + 1}: {what}, then Enter")
            sys.stdin.readline()

        got = run.run(place, report, dummy if dummy_g is not None else None)
    print(
        f"wrote {got['map']}: {len(idx)} points x 5 excitations, {got['bins']} bins; "
        f"coherence >= 0.9 over {got['coherence_ge_0.9']:.0%} of them "
        f"({got['elapsed_s']:.0f} s)"
    )
    if dummy_g is not None:
        print(f"sensor mass {args.sensor_mass_g:g} g cancelled with the {dummy_g:g} g dummy")
    elif args.sensor_mass_g:
        # lazy: the modal fit (sdypy-EMA) only when a correction is asked for
        from plugins.vibrotactile.mass_correction import correct_file

        fix = correct_file(args.out, args.sensor_mass_g)
        print(
            f"sensor mass {args.sensor_mass_g:g} g taken out: {fix['modes']} modes, "
            f"{fix['modes_uncorrected']} not identifiable from these points (left as measured)"
        )
    return 0


def add_latency_parser(sub) -> None:
    lat = sub.add_parser(
        "latency",
        help="the converters' round trip on the loopback input (as jack_iodelay): a chirp "
        "through the gate, cross-correlated with what came back, next to PortAudio's claim",
    )
    lat.add_argument("--level-v", type=LEVEL, default=2.0, help="chirp peak at the patches")
    lat.add_argument("--fast", action="store_true", help="twin: fast-forward, not real time")
    lat.add_argument("--json", action="store_true")
    lat.add_argument(
        "--save",
        action="store_true",
        help="store the measured output latency in the profile's overrides file "
        "([audio] measured_output_latency_ms; `bench flow-latency` adds it)",
    )


#: chirps at most for a steady round trip (two in a row within a sample)
LATENCY_TRIES = 5


def measure_latency(args, ctx) -> int:
    """Play a short chirp on the piezo output and find it on the loopback input."""
    # lazy: numpy, the outputs client and the estimator load only when measuring
    import json

    import numpy as np

    from console.plugin_api import OutputPlan, Segment, find_input, input_specs
    from console.plugin_api.runtime import capture, open_outputs
    from plugins.vibrotactile.roving import RovingSettings, chirp_v, delay_samples

    twin = ctx.profile.get("audio.driver") == "twin"
    if find_input(input_specs(ctx.profile), "loopback") is None and not twin:
        raise UserError(
            f"{ctx.profile.path}: no loopback among [audio_inputs]; cable an output to an "
            "input and add [audio_inputs.loopback] channel = 2, kind = 'loopback', "
            "sensitivity = 1.0"
        )
    s = RovingSettings(level_v=args.level_v, f_start_hz=100.0, f_stop_hz=2000.0, sweep_s=0.3)
    s = RovingSettings(**{**s.to_json(), "band_hz": (100.0, 2000.0), "tail_s": 0.2})
    with open_outputs(ctx.profile, ctx.pm, fast=True if args.fast else None) as out:
        fs = int(out.limits.sample_rate_hz)
        x = np.concatenate([chirp_v(s, fs), np.zeros(int(s.tail_s * fs))])
        seg = Segment(x, np.zeros_like(x), frozenset({"PA"}), False, "latency chirp")
        lags: list[float] = []  # until two in a row agree (a stream just started, or an
        while len(lags) < LATENCY_TRIES:  # xrun, can add whole periods for a while)
            cap = capture(out, OutputPlan(fs, (seg,), "loopback latency", 0.0))
            lags.append(delay_samples(x, cap.physical("loopback")))
            if len(lags) >= 2 and abs(lags[-1] - lags[-2]) <= 1.0:
                break
        audio = out.status().get("audio", {})
    # lazy: loaded when this runs, not when the module is imported
    from plugins.vibrotactile.cli.latency_report import latency_report

    got = latency_report(lags[-1], fs, audio)
    got["chirps"] = len(lags)
    got["steady"] = bool(len(lags) >= 2 and abs(lags[-1] - lags[-2]) <= 1.0)
    if args.save:
        # lazy: loaded when this runs, not when the module is imported
        from console.plugin_api import save_overrides

        key = "audio.measured_output_latency_ms"
        got["saved"] = str(
            save_overrides(ctx.profile, {key: got["measured_output_latency_ms"]}, ctx.pm)
        )
    if args.json:
        print(json.dumps(got))
    else:
        shown = ", ".join(f"{v:.1f}" for v in lags)
        print(
            f"loopback round trip {got['round_trip_samples']:g} samples "
            f"({got['round_trip_ms']:g} ms); the driver claims "
            f"{got['portaudio_output_latency_ms']} ms of output latency; use "
            f"--delay-samples {lags[-1]:.0f} for a roving run without a loopback"
            + ("" if got["steady"] else f" (not steady over {len(lags)} chirps: {shown})")
        )
        print(
            f"output latency {got['measured_output_latency_ms']:g} ms (the round trip less "
            f"{got['input_share_ms']:g} ms: {got['input_share_from']})"
            + (f"; saved in {got['saved']}" if args.save else "")
        )
    return 0
