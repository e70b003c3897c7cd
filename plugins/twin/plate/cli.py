"""``haptable plate ...``: inspect the plate twin from the command line."""

from __future__ import annotations

import argparse
import json

from console.plugin_api import UserError, finite_float, positive_int

EDGE_CHOICES = ("ssss", "cccc", "ffff", "profile")


def configure(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="plate_command", metavar="{modes}")
    sub.required = True
    p = sub.add_parser("modes", help="natural frequencies of the glass plate")
    p.add_argument(
        "--edges",
        choices=EDGE_CHOICES,
        default="profile",
        help="edge conditions: simply supported, clamped, free, or the profile's seal springs",
    )
    p.add_argument(
        "--aspect",
        type=finite_float(0.05, 20),
        default=None,
        help="long/short side ratio (short side = long side / aspect); default: the profile's",
    )
    p.add_argument(
        "--count", type=positive_int(1000), default=10, help="number of elastic modes (default 10)"
    )
    p.add_argument("--json", action="store_true", help="print JSON")


def plate_modes(profile, edges: str, aspect: float | None, count: int) -> list[dict]:
    """Elastic modes, ascending: [{"frequency_hz", "lambda"}...] for the profile's glass."""

    # lazy: this module loads at every haptable start; model, ritz only when used
    from .model import params_from_profile
    from .ritz import solve_modes

    if count < 1:
        raise UserError(f"--count {count}: must be at least 1")
    if aspect is not None and not (0.05 <= aspect <= 20):
        raise UserError(f"--aspect {aspect:g}: use a long/short ratio between 0.05 and 20")
    params = params_from_profile(
        profile, edges=None if edges == "profile" else edges, aspect=aspect
    )
    n = params.basis_order
    modes = solve_modes(params.plate, params.edges, n)
    el = slice(modes.n_rigid, modes.n_rigid + count)
    return [
        {"frequency_hz": float(f), "lambda": float(lam)}
        for f, lam in zip(modes.freq_hz[el], modes.lam[el], strict=True)
    ]


def run(args: argparse.Namespace, ctx) -> int:
    if args.plate_command != "modes":  # pragma: no cover - argparse enforces the choice
        return 2
    modes = plate_modes(ctx.profile, args.edges, args.aspect, args.count)
    if args.json:
        print(json.dumps({"modes": modes}))
    else:
        print(f"{'#':>3} {'frequency_hz':>13} {'lambda':>10}")
        for i, m in enumerate(modes, 1):
            print(f"{i:>3} {m['frequency_hz']:>13.3f} {m['lambda']:>10.4f}")
    return 0
