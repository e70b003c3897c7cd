"""Small file helpers: tell a tables file from a vibration map."""

from __future__ import annotations

import os
from pathlib import Path

from console.plugin_api import UserError, npz_keys


def is_tables_file(path: str | os.PathLike) -> bool:
    """True for a lookup-tables file, False for a vibration map (its archive checked,
    no array read); anything else is a one-line ``UserError``."""
    p = Path(path)
    if not p.exists():
        raise UserError(
            f"{p}: no such file; build tables with `haptable tables build MAP --out {p}`"
        )
    keys = npz_keys(
        p,
        what="tables or vibration-map file",
        fix="pass a map (`haptable frf measure|import`) or tables (`haptable tables build`)",
    )
    return "max_diff_um_per_v" in keys
