"""What HapTable writes into a UFF file beyond the FRFs and reads back on import: the
reference node of each excitation, the ``HapTable`` tag of the id lines (``gain=``,
``masked=``) and the masked bins as text."""

from __future__ import annotations

import numpy as np

from console.plugin_api import UserError

#: the import's default excitation of each reference node (one file for all excitations)
REF_NODES = {"PA": 1, "PB": 2, "PC": 3, "PD": 4, "PALL": 5}
#: the tag starting the id lines this project's export writes (id2: gain, id3: mask)
TAG = "HapTable"


def mask_text(masked: np.ndarray) -> str:
    """Masked bins as index ranges (``0-4,9-9``), ``none``, or ``zeros`` when too long."""
    idx = np.flatnonzero(masked)
    if idx.size == 0:
        return "none"
    runs, start = [], idx[0]
    for a, b in zip(idx[:-1], idx[1:], strict=True):
        if b != a + 1:
            runs.append(f"{start}-{a}")
            start = b
    runs.append(f"{start}-{idx[-1]}")
    text = ",".join(runs)
    return text if len(text) <= 60 else "zeros"


def mask_from_text(text: str, frf: np.ndarray, where: str) -> np.ndarray:
    """The stored mask back (``zeros``: the bins where every FRF is 0)."""
    n = frf.shape[-1]
    if text == "none":
        return np.zeros(n, bool)
    if text == "zeros":
        return np.all(frf == 0, axis=(0, 1))
    mask = np.zeros(n, bool)
    try:
        for part in text.split(","):
            a, b = (int(v) for v in part.split("-"))
            if not 0 <= a <= b < n:
                raise ValueError
            mask[a : b + 1] = True
    except ValueError:
        raise UserError(f"{where}: stored mask {text[:40]!r} is damaged; re-export it") from None
    return mask
