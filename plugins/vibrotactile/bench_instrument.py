"""``haptable bench instrument``: the roving-sensor map against the twin's true FRFs.

The twin's roving accelerometer (``plugins.twin.inputs``) measures the grid as an
operator would (``plugins.vibrotactile.roving_run``, the moves simulated), with the
sensor's mass on the plate model and without it, and with its mass cancelled by a second
pass with a clip-on dummy (``mass_cancel``, ``DUMMY_X`` x the sensor's mass). Each map is compared with the twin's
true displacement FRFs (the plate without any sensor) on the same bins: the magnitude
error per band where the coherence is >= 0.9 (the goal: <= 1 dB over 20-625 Hz), the
share of bins that coherent, and the lookup tables built from each map against those
built from the true map (same actuator, and same frequency within the resonance's
half-power width 2 zeta f, for the 84 x 83 ordered pairs; the goal >= 95 %).

Timing: the twin plays fast-forward; ``audio_s`` is what the same run plays on a real
table in real time, and ``operator_s`` adds an assumed ``MOVE_S`` per point for gluing
the sensor. The twin's blocks are ``BLOCK`` samples (fewer gate calls; the signal is the
same).
"""

from __future__ import annotations

import dataclasses
import math
import os
import tempfile
import time

import numpy as np

from console.plugin_api import EXCITATIONS, UserError, load_map, machine_info, make_map

BANDS_HZ = ((20.0, 100.0), (100.0, 200.0), (200.0, 400.0), (400.0, 625.0))
GOOD = 0.9
MOVE_S = 20.0  # the operator moves and glues the sensor (an assumption, said so)
DUMMY_X = 2.0  # the clip-on dummy's mass in sensor masses (``mass_cancel``: less noise than 1)
#: 90 V below 300 Hz (the gate allows -100..250 V), falling as 1/f above: the largest
#: acceleration on the grid stays ~65 % of the twin's input range (196 m/s^2)
SETTINGS = {"level_v": 90.0, "knee_hz": 300.0, "repeats": 6}  # as `frf measure`
BLOCK = 1024


def band_errors(
    freqs_hz: np.ndarray,
    frf: np.ndarray,
    coh: np.ndarray,
    true: np.ndarray,
    bands: tuple[tuple[float, float], ...] = BANDS_HZ,
    good: float = GOOD,
    repeats: int | None = None,
) -> list[dict]:
    """Per band: |20 log10(|H1| / |H_true|)| where coherence >= ``good``: median, p95,
    max, the share within 1 dB, the share of bins that coherent, and (``repeats`` given)
    the share inside twice the random error the coherence predicts (``random_error_db``:
    ~95 % when the coherence tells the truth)."""
    # lazy: the roving module's error bound only with repeats
    from plugins.vibrotactile.roving import random_error_db

    with np.errstate(divide="ignore", invalid="ignore"):
        err = np.abs(20 * np.log10(np.abs(frf) / np.abs(true)))
    bound = 2 * random_error_db(coh, repeats) if repeats else None
    out = []
    for lo, hi in bands:
        inside = np.broadcast_to((freqs_hz >= lo) & (freqs_hz < hi), frf.shape)
        ok = inside & (coh >= good) & np.isfinite(err)
        e = err[ok]
        row = {
            "band_hz": [lo, hi],
            "coherent_share": round(float(ok.sum() / max(1, inside.sum())), 4),
            "median_db": round(float(np.median(e)), 3) if e.size else None,
            "p95_db": round(float(np.percentile(e, 95)), 3) if e.size else None,
            "max_db": round(float(e.max()), 3) if e.size else None,
            "within_1db": round(float(np.mean(e <= 1.0)), 4) if e.size else None,
        }
        if bound is not None and e.size:
            row["within_2sigma_of_coherence"] = round(float(np.mean(e <= bound[ok])), 4)
        out.append(row)
    return out


def table_agreement(m_meas, m_true, zeta: float = 0.01, band_hz: float = 625.0) -> dict:
    """The lookup tables from two maps on the same bins: the share of ordered pairs with
    the same actuator, and with the same actuator and a frequency within 2 zeta f."""
    # lazy: the tables module (interpolation, perceptual rule) only for the bench
    from plugins.vibrotactile.tables import build_tables

    a, b = build_tables(m_meas, band_hz), build_tables(m_true, band_hz)
    off = ~np.eye(a.actuator.shape[0], dtype=bool)
    same_act = (a.actuator == b.actuator) & off
    near = np.abs(a.freq_hz - b.freq_hz) <= np.maximum(2 * zeta * b.freq_hz, 1e-9)
    return {
        "pairs": int(off.sum()),
        "same_actuator": round(float(same_act.sum() / off.sum()), 4),
        "same_actuator_and_bin": round(
            float((same_act & (a.freq_hz == b.freq_hz)).sum() / off.sum()), 4
        ),
        "same_actuator_and_freq_within_2zeta_f": round(
            float((same_act & near).sum() / off.sum()), 4
        ),
    }


def corrected_run(m, mass_g: float, coh, true, m_true, zeta: float) -> dict:
    """The mass-loaded map corrected (``mass_correction``), compared as the others."""
    # lazy: the modal fit (sdypy-EMA) only for the bench's corrected run
    from plugins.vibrotactile.mass_correction import correct_map

    t0 = time.perf_counter()
    fixed, corr = correct_map(m, mass_g)
    return {
        "bands": band_errors(fixed.freq_hz, fixed.frf_um_per_v, coh, true),
        "tables": table_agreement(fixed, m_true, zeta),
        "correction_s": round(time.perf_counter() - t0, 1),
        "correction": {k: v for k, v in corr.summary().items() if k != "unloaded_hz"},
    }


def run_instrument_bench(ctx, quick: bool) -> dict:
    # lazy: the outputs, the plate twin and the run load only for the bench
    from console.plugin_api.runtime import move_sensor, open_outputs
    from plugins.vibrotactile.roving import RovingSettings
    from plugins.vibrotactile.roving_run import RovingRun

    prof = ctx.profile
    audio = {**prof.section("audio"), "block_size": BLOCK, "driver": "twin"}
    prof = dataclasses.replace(prof, data={**prof.data, "audio": audio})
    g = prof.section("grid")
    k = np.arange(int(g["rows"]) * int(g["columns"]))
    ox, oy = g["origin_mm"]
    pitch, cols = float(g["pitch_mm"]), int(g["columns"])
    pts = np.column_stack([ox + (k % cols) * pitch, oy + (k // cols) * pitch])
    if quick:
        pts = pts[::7]
    settings = RovingSettings(**SETTINGS)
    # the plate twin's vibrometer knows the true FRFs (``PlateResponse``)
    plate = ctx.pm.build("vibrometer", prof.get("vibrometer.driver") or "twin", prof)
    if not callable(getattr(plate, "true_frf_um_per_v", None)):
        raise UserError("bench instrument: the profile's vibrometer is not the plate twin's")
    zeta = float(prof.get("plate.damping_ratio") or 0.01)
    mass_g = float(prof.get("twin_inputs.sensor_mass_g") or 7.0)
    out: dict = {
        "points": int(len(pts)),
        "settings": settings.to_json(),
        "sensor_mass_g": mass_g,
        "goal": "<= 1 dB where coherence >= 0.9 over 20-625 Hz; tables agree >= 95 %",
    }
    runs = {}
    with tempfile.TemporaryDirectory() as tmp, open_outputs(prof, ctx.pm, fast=True) as outputs:
        dummy_g = DUMMY_X * mass_g
        cases = (("mass_on", mass_g, None), ("mass_off", 0.0, None))
        cases += (("mass_on_dummy_cancelled", mass_g, dummy_g),)
        for label, m_g, d_g in cases:
            run = RovingRun(
                outputs,
                os.path.join(tmp, f"{label}.npz"),
                pts,
                settings,
                sensor={"kind": "accelerometer", "mass_g": m_g},
                dummy_mass_g=d_g,
            )

            def place(point: int, xm: float, ym: float, m_g: float = m_g) -> None:
                move_sensor(outputs, xm, ym, m_g)

            def dummy(point: int, xm: float, ym: float, on: bool, m_g=m_g, d_g=d_g) -> None:
                move_sensor(outputs, xm, ym, m_g + (d_g if on else 0.0))

            t0 = time.perf_counter()
            got = run.run(place, dummy=dummy)
            wall = time.perf_counter() - t0
            m = load_map(got["map"], require_all=False)
            coh = np.load(run.parts / "coherence.npz")["coherence"]
            true = plate.true_frf_um_per_v(pts[:, 0], pts[:, 1], m.freq_hz, EXCITATIONS)
            m_true = make_map(true, m.freq_hz, m.points, m.points_mm, EXCITATIONS, None)
            audio_s = (
                len(pts)
                * len(EXCITATIONS)
                * settings.repeats
                * (settings.sweep_s + settings.tail_s)
            )
            runs[label] = {
                "bands": band_errors(
                    m.freq_hz, m.frf_um_per_v, coh, true, repeats=settings.repeats
                ),
                "coherent_share_20_625": round(float(np.mean(coh >= GOOD)), 4),
                "tables": table_agreement(m, m_true, zeta),
                "twin_wall_s": round(wall, 1),
                "twin_wall_s_per_point": round(wall / len(pts), 2),
                "audio_s": round(audio_s, 1),
                "operator_s": round(audio_s + MOVE_S * len(pts), 1),
                "bins": int(m.freq_hz.size),
            }
            if d_g:  # two passes per point, and the dummy clipped on and off
                runs[label]["dummy_mass_g"] = d_g
                runs[label]["audio_s"] = round(2 * audio_s, 1)
                runs[label]["operator_s"] = round(2 * (audio_s + MOVE_S * len(pts)), 1)
            if m_g > 0 and not d_g:  # the same map with the sensor's mass fitted out
                runs["mass_on_corrected"] = corrected_run(m, m_g, coh, true, m_true, zeta)
    out["runs"] = runs
    out["full_map_84_points_twin_s_estimate"] = round(
        runs["mass_on"]["twin_wall_s_per_point"] * 84, 1
    )
    out["full_map_84_points_real_table_min"] = round(
        math.ceil(
            84
            * (len(EXCITATIONS) * settings.repeats * (settings.sweep_s + settings.tail_s) + MOVE_S)
        )
        / 60,
        1,
    )
    out["machine"] = machine_info()
    out["quick"] = quick
    out["load_average_1min"] = os.getloadavg()[0]
    return out
