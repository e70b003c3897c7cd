"""Small file helpers: tell a tables file from a vibration map."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from console.errors import UserError


def is_tables_file(path: str | os.PathLike) -> bool:
    p = Path(path)
    if not p.exists():
        raise UserError(
            f"{p}: no such file; build tables with `haptable tables build MAP --out {p}`"
        )
    try:
        with np.load(p, allow_pickle=False) as z:
            return "max_diff_um_per_v" in z.files
    except (OSError, ValueError):
        raise UserError(f"{p}: not a tables or vibration-map file (.npz)") from None
