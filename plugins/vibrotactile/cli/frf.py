"""``haptable frf``: import and export UFF 58, measure the profile's map, summarise one."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from console.plugin_api import UserError, finite_float, grid_points_mm, load_map, save_map
from plugins.vibrotactile.cli.common import (
    MAP_HELP,
    key_type,
    map_source,
    progress_printer,
    vt_section,
)

#: an amplifier gain (generator volts -> piezo volts; PI E413.D2: 50)
GAIN = finite_float(1e-6, 1e6, note="the amplifier's gain, e.g. 50")


def configure_frf(p: argparse.ArgumentParser) -> None:
    sub = p.add_subparsers(dest="frf_cmd", metavar="ACTION", required=True)
    i = sub.add_parser(
        "import",
        help="UFF 58/58b -> vibration map: EXC=FILE per excitation, or one FILE for all",
    )
    i.add_argument(
        "files",
        nargs="+",
        metavar="EXC=FILE|FILE",
        help="PA=pa.uff PB=pb.uff ... PALL=all.uff, or one file holding every excitation "
        "(told apart by reference node: --ref-node)",
    )
    i.add_argument("--out", required=True, help="vibration map (.npz) to write")
    i.add_argument(
        "--ref-node",
        nargs="+",
        metavar="EXC=NODE",
        default=None,
        help="one file for all: the reference node of each excitation (default PA=1 PB=2 "
        "PC=3 PD=4 PALL=5)",
    )
    i.add_argument(
        "--gain",
        type=GAIN,
        default=None,
        help="amplifier gain: the UFF reference is generator volts (default: the gain a "
        "HapTable export stored, else profile amplifiers.piezo_gain)",
    )
    i.add_argument(
        "--mask-below-hz",
        type=key_type("mask_below_hz", "Hz"),
        default=None,
        help="mask bins below (default: a HapTable export's mask, else profile)",
    )
    i.add_argument(
        "--reference",
        choices=("voltage", "force"),
        default="voltage",
        help="what the FRF is per: generator voltage (default) or a measured force (m/N: "
        "needs --sensitivity-n-per-v)",
    )
    i.add_argument(
        "--sensitivity-n-per-v",
        type=finite_float(1e-9, 1e9, unit="N/V"),
        default=None,
        help="with --reference force: newtons of that force per generator volt",
    )
    i.add_argument(
        "--allow-missing", action="store_true", help="accept fewer than five excitations"
    )
    e = sub.add_parser(
        "export", help="vibration map -> UFF 58, one file per excitation (or --one-file)"
    )
    e.add_argument("map", help=MAP_HELP)
    e.add_argument("--out", required=True, help="folder for PA.uff ... PALL.uff")
    e.add_argument("--binary", action="store_true", help="write binary 58b")
    e.add_argument(
        "--one-file",
        action="store_true",
        help="write DIR/all.uff holding every excitation (ref_node PA=1 .. PALL=5)",
    )
    e.add_argument(
        "--gain",
        type=GAIN,
        default=1.0,
        help="amplifier gain: write per generator volt = map x gain (1: per piezo volt); "
        "stored in the files, so import reads it back",
    )
    m = sub.add_parser(
        "measure",
        help="measure the profile's vibration map with its vibrometer (twin: simulated) into "
        "HapTable's cache, where the console and the demos read it ('measured' as a MAP)",
    )
    m.add_argument("--out", default=None, help="also write the map (.npz) here")
    # lazy: only the options' words (plugins.vibrotactile.cli.frf_roving holds the run)
    from plugins.vibrotactile.cli.frf_roving import add_latency_parser, add_roving_options

    add_roving_options(m)
    add_latency_parser(sub)
    s = sub.add_parser("info", help="summarise a vibration map")
    s.add_argument("map", help=MAP_HELP)
    s.add_argument("--json", action="store_true")


def run_frf(args, ctx) -> int:
    if args.frf_cmd == "import":
        # lazy: this module loads at every haptable start; uff_import only when used
        from plugins.vibrotactile.uff_import import import_uff

        plain = [f for f in args.files if "=" not in f]
        if plain and (len(args.files) > 1):
            raise UserError(
                f"{plain[0]!r}: give EXC=FILE per excitation (PA=pa.uff ...) or one FILE for "
                "all excitations (with --ref-node), not both"
            )
        if plain:
            files = plain[0]
        else:
            if args.ref_node:
                raise UserError("--ref-node: only for one FILE holding every excitation")
            files = {}
            for item in args.files:
                exc, path = item.split("=", 1)
                files[exc.strip().upper()] = path
        ref_nodes = None
        if args.ref_node:
            ref_nodes = {}
            for item in args.ref_node:
                exc, _, num = item.partition("=")
                try:
                    ref_nodes[exc.strip().upper()] = int(num)
                except ValueError:
                    raise UserError(f"--ref-node {item!r}: write EXC=NODE, e.g. PA=1") from None
        g = ctx.profile.section("grid")
        grid = grid_points_mm(g["rows"], g["columns"], g["pitch_mm"], tuple(g["origin_mm"]))
        m = import_uff(
            files,
            gain=args.gain,
            mask_below_hz=args.mask_below_hz,
            grid_mm=grid,
            require_all=not args.allow_missing,
            ref_nodes=ref_nodes,
            reference=args.reference,
            sensitivity_n_per_v=args.sensitivity_n_per_v,
            default_gain=ctx.profile.get("amplifiers.piezo_gain"),
            default_mask_below_hz=vt_section(ctx)["mask_below_hz"],
        )
        gain = m.provenance["gain"]
        save_map(args.out, m)
        print(
            f"wrote {args.out}: {len(m.excitations)} excitations x {m.points.size} points x "
            f"{m.freq_hz.size} bins ({m.freq_hz[0]:g}-{m.freq_hz[-1]:g} Hz), gain {gain:g}"
            + (f"; note: {m.provenance['note']}" if m.provenance.get("note") else "")
        )
        return 0
    if args.frf_cmd == "latency":
        # lazy: the loopback measurement loads only when asked for
        from plugins.vibrotactile.cli.frf_roving import measure_latency

        return measure_latency(args, ctx)
    if args.frf_cmd == "measure" and args.sensor:
        # lazy: the roving measurement loads only when asked for
        from plugins.vibrotactile.cli.frf_roving import measure_roving

        return measure_roving(args, ctx)
    if args.frf_cmd == "measure":
        return measure_map(args, ctx)

    if args.frf_cmd == "export":
        # lazy: this module loads at every haptable start; uff_export only when used
        from plugins.vibrotactile.uff_export import export_uff

        m = load_map(map_source(args.map, ctx), require_all=False)
        for path in export_uff(
            m, args.out, binary=args.binary, gain=args.gain, one_file=args.one_file
        ):
            print(f"wrote {path}")
        return 0
    m = load_map(map_source(args.map, ctx), require_all=False)
    info = {
        "excitations": list(m.excitations),
        "points": int(m.points.size),
        "bins": int(m.freq_hz.size),
        "freq_hz": [float(m.freq_hz[0]), float(m.freq_hz[-1])],
        "masked_bins": int(m.masked.sum()),
        "peak_um_per_v": float(np.abs(m.frf_um_per_v).max()),
        "provenance": m.provenance,
    }
    if args.json:
        print(json.dumps(info, indent=2))
    else:
        # lazy: this module loads at every haptable start; summary_text only when used
        from plugins.vibrotactile.summary_text import summary_lines

        print("\n".join(summary_lines(info)))
    return 0


def measure_map(args, ctx) -> int:
    """Measure the grid with the vibrometer the profile names into HapTable's cache (the
    file the console and the demos read: ``console.runtime.measured_map``), and copy it
    to ``--out`` when given."""
    # lazy: the runtime part loads on first use, not at every haptable start
    from console.plugin_api.runtime import measured_map_file

    cached = measured_map_file(ctx.profile, ctx.pm, progress_printer(), remeasure=True)
    m = load_map(cached)
    wrote = [str(cached)]
    if args.out:
        out = Path(args.out)
        if out.suffix.lower() != ".npz":
            raise UserError(f"--out {out}: give a .npz path for the vibration map")
        out.parent.mkdir(parents=True, exist_ok=True)
        save_map(out, m)
        wrote.insert(0, str(out))
    name = ctx.profile.get("vibrometer.driver") or "the only vibrometer"
    print(
        f"wrote {' and '.join(wrote)}: {len(m.excitations)} excitations x {m.points.size} "
        f"points x {m.freq_hz.size} bins ({m.freq_hz[0]:g}-{m.freq_hz[-1]:g} Hz) from "
        f"vibrometer {name!r}"
    )
    return 0
