"""A plan's summary (``haptable flow`` / ``point``) as lines a person reads: one value a
line, labels aligned, units taken from the key's suffix (``frequency_hz`` -> ``frequency
... Hz``), lists of parts as indented blocks. ``--json`` prints the summary itself."""

from __future__ import annotations

from typing import Any

#: key suffix -> unit shown after the value (longest suffixes first)
UNITS = (
    ("_um_per_v", "um/V"),
    ("_pct", "%"),
    ("_jnd", "JND"),
    ("_db", "dB"),
    ("_hz", "Hz"),
    ("_mm", "mm"),
    ("_ms", "ms"),
    ("_s", "s"),
    ("_v", "V"),
)
#: words of a key written out in its label
WORDS = {"sl": "sensation level", "um": "displacement", "per": "", "v": ""}


def label_and_unit(key: str) -> tuple[str, str]:
    """``"max_sl_db"`` -> ``("max sensation level", "dB")``; ``"um_per_v"`` ->
    ``("displacement", "um/V")``."""
    for suffix, unit in UNITS:
        if key == suffix[1:]:
            return _label(key), unit
        if key.endswith(suffix):
            return _label(key[: -len(suffix)]), unit
    return _label(key), ""


def _label(stem: str) -> str:
    words = [WORDS.get(w, w) for w in stem.split("_")]
    return " ".join(w for w in words if w) or stem


def value_text(value: Any, unit: str = "") -> str:
    """A value as text: numbers to 4 significant digits, lists joined, a grid of booleans
    as rows of ``#`` (on) and ``.`` (off)."""
    if isinstance(value, bool):
        text = "yes" if value else "no"
    elif isinstance(value, int):
        text = str(value)
    elif isinstance(value, float):
        text = f"{value:.4g}"
    elif value is None:
        return "-"
    elif isinstance(value, list | tuple):
        if not value:
            return "none"
        if all(isinstance(r, list | tuple) and all(isinstance(c, bool) for c in r) for r in value):
            return " / ".join("".join("#" if c else "." for c in row) for row in value)
        sep = " " if all(isinstance(v, str) and len(v) <= 4 for v in value) else ", "
        text = sep.join(value_text(v) for v in value)
    else:
        text = str(value)
    return f"{text} {unit}" if unit else text


def _is_block_list(value: Any) -> bool:
    return (
        isinstance(value, list | tuple) and bool(value) and all(isinstance(v, dict) for v in value)
    )


def summary_lines(summary: dict, indent: int = 0) -> list[str]:
    """The summary as aligned ``label  value unit`` lines; a list of dicts (segments,
    parts) as one indented block per item, titled by its ``label`` or its number."""
    rows: dict[str, list[str]] = {}  # label -> texts (``felt_db``, ``felt_jnd``: one row)
    for key, value in summary.items():
        if _is_block_list(value) or isinstance(value, dict):
            continue
        label, unit = label_and_unit(key)
        many = isinstance(value, list | tuple) and len(value) > 1
        if many and all(isinstance(v, str) and len(v) > 4 for v in value):  # notes
            rows.setdefault(label, []).append("\n".join(value))
        else:
            rows.setdefault(label, []).append(value_text(value, unit))
    pad = max((len(label) for label in rows), default=0)
    lines = []
    for label, texts in rows.items():
        text = " = ".join(texts).replace("\n", "\n" + " " * (indent + pad + 2))
        lines += (" " * indent + f"{label:<{pad}}  {text}").splitlines()
    for key, value in summary.items():
        if isinstance(value, dict):
            lines.append(" " * indent + label_and_unit(key)[0])
            lines += summary_lines(value, indent + 2)
        elif _is_block_list(value):
            singular = label_and_unit(key)[0].removesuffix("s")
            for i, item in enumerate(value, 1):
                title = f"{singular} {i}" + (f": {item['label']}" if item.get("label") else "")
                lines.append(" " * indent + title)
                rest = {k: v for k, v in item.items() if k != "label"}
                lines += summary_lines(rest, indent + 2)
    return lines
