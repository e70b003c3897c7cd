"""A participant's plan: the protocol's trials in the order this participant meets them.

Seeded and deterministic: ``make_plan(protocol, participant_id)`` gives the same plan every
time. Orders marked ``same_for_all`` (and ``listed`` blocks) depend on the protocol's seed
only, so every participant meets them alike; ``random`` orders are seeded by the
participant (``participant_seed``); ``latin_square`` blocks take the participant's row of a
balanced Latin square (``balanced_latin_square``; row = participant number - 1 modulo
the rows, the number being the id's trailing digits unless given).
"""

from __future__ import annotations

import hashlib
import itertools
import math
import re
from typing import Any

import numpy as np

from console.plugin_api import UserError

from .protocol import Phase, Protocol
from .records import MAX_SEED


def balanced_latin_square(n: int) -> list[list[int]]:
    """Williams' balanced Latin square of ``n`` conditions: every condition once per row
    and column, and each ordered pair of neighbours exactly once over the rows (``n``
    rows for even ``n``; ``2n`` for odd ``n``, the rows and their mirror images)."""
    if n < 1:
        raise ValueError("n must be at least 1")
    first = [0]
    lo, hi = 1, n - 1
    for j in range(1, n):
        if j % 2:
            first.append(lo)
            lo += 1
        else:
            first.append(hi)
            hi -= 1
    rows = [[(c + r) % n for c in first] for r in range(n)]
    if n % 2:
        rows += [row[::-1] for row in rows]
    return rows


def participant_number(participant_id: str, row_hint: str = "or give --row") -> int:
    """The number in a participant id (``P07`` -> 7): its trailing digits. ``row_hint``:
    how else the user can pick the row ("" where they cannot)."""
    m = re.search(r"(\d+)$", participant_id)
    if not m or int(m.group(1)) < 1:
        raise UserError(
            f"participant {participant_id!r}: no number at its end to pick the counterbalancing "
            f"row; name participants P01, P02 ...{' ' + row_hint if row_hint else ''}"
        )
    return int(m.group(1))


def square_rows(protocol: Protocol) -> int:
    """The rows a participant's ``row`` picks from: the least common multiple of the
    rows of each ``latin_square`` phase's square (0: the protocol has none)."""
    sizes = [
        len(balanced_latin_square(len(p.factors[p.block_by])))
        for p in protocol.phases
        if p.block_order == "latin_square"
    ]
    return math.lcm(*sizes) if sizes else 0


def check_seed_row(protocol: Protocol, seed: int | None, row: int | None) -> None:
    """A seed and row given by the user (``--seed``, ``--row``) in range: one line if not."""
    if seed is not None and not (isinstance(seed, int) and 0 <= seed <= MAX_SEED):
        raise UserError(f"--seed {seed}: give a whole number from 0 to {MAX_SEED}")
    if row is None:
        return
    rows = square_rows(protocol)
    if not rows:
        raise UserError(
            f"--row {row}: {protocol.name} has no latin_square block order, so no "
            "counterbalancing row to pick; leave --row out"
        )
    if not (isinstance(row, int) and 0 <= row < rows):
        raise UserError(
            f"--row {row}: {protocol.name}'s Latin square has {rows} rows; give 0 to {rows - 1}"
        )


def participant_seed(protocol: Protocol, participant_id: str) -> int:
    """The seed of a participant's random orders (the protocol's seed and the id)."""
    h = hashlib.sha256(f"{protocol.seed}:{protocol.name}:{participant_id}".encode())
    return int.from_bytes(h.digest()[:8], "big") >> 1


def _rng(*keys: Any) -> np.random.Generator:
    h = hashlib.sha256(":".join(map(str, keys)).encode()).digest()
    return np.random.default_rng(int.from_bytes(h[:8], "big"))


def _blocks(protocol: Protocol, k: int, phase: Phase, seed: int, row: int) -> list[Any]:
    if not phase.block_by:
        return [None]
    levels = list(phase.factors[phase.block_by])
    if phase.block_order == "listed":
        return levels
    if phase.block_order == "random":
        return [levels[i] for i in _rng(seed, k, "blocks").permutation(len(levels))]
    square = balanced_latin_square(len(levels))
    return [levels[i] for i in square[row % len(square)]]


def _stimulus(protocol: Protocol, cell: dict[str, Any]) -> dict[str, Any]:
    if protocol.stimulus == "flow":
        pair = protocol.pairs[cell["pair"]]
        a, b = (
            (pair["left"], pair["right"])
            if cell["direction"] == "left_to_right"
            else (pair["right"], pair["left"])
        )
        return {"effect": "flow", "from_point": a, "to_point": b, **pair}
    if protocol.stimulus == "hand_flow":
        reg = protocol.regions[cell["region"]]
        return {
            "effect": "hand_flow",
            "center_mm": list(reg["center_mm"]),
            "direction": cell["direction"],
            "hand": reg["hand"],
        }
    return {
        "task": "knob",
        "condition": cell["condition"],
        "sectors": int(cell["sectors"]),
        "distance_deg": float(cell["distance_deg"]),
    }


def make_plan(
    protocol: Protocol,
    participant_id: str,
    *,
    seed: int | None = None,
    row: int | None = None,
    row_hint: str = "or give --row",
) -> dict[str, Any]:
    """The participant's plan (the ``plan.json`` contract): ``experiment``,
    ``protocol_sha256``, ``seed``, ``latin_square_row``, ``factors`` (each phase's factor
    levels in the protocol's order), ``trials`` (ordered) and ``questionnaires`` (each
    after a trial index)."""
    check_seed_row(protocol, seed, row)
    seed = participant_seed(protocol, participant_id) if seed is None else int(seed)
    needs_row = any(p.block_order == "latin_square" for p in protocol.phases)
    if row is None:
        row = participant_number(participant_id, row_hint) - 1 if needs_row else 0
    trials: list[dict[str, Any]] = []
    questionnaires: list[dict[str, Any]] = []
    for k, phase in enumerate(protocol.phases):
        names = list(phase.factors)
        for block in _blocks(protocol, k, phase, seed, row):
            cells = [
                dict(zip(names, combo, strict=True))
                for combo in itertools.product(*phase.factors.values())
                if block is None or dict(zip(names, combo, strict=True))[phase.block_by] == block
            ]
            cells = [c for c in cells for _ in range(phase.repetitions)]
            if phase.order == "same_for_all":
                rng = _rng(protocol.seed, protocol.name, k, block)
            else:
                rng = _rng(seed, k, block)
            for j in rng.permutation(len(cells)):
                c = cells[int(j)]
                stim = _stimulus(protocol, c)
                trials.append(
                    {
                        "index": len(trials),
                        "phase": phase.name,
                        "block": block,
                        "pair": c.get("pair"),
                        "region": c.get("region"),
                        "direction": c.get("direction"),
                        "condition": c.get("condition"),
                        "hand": stim.get("hand"),
                        "stimulus": stim,
                        "replays_allowed": phase.replays,
                    }
                )
            if phase.questionnaire_after_block and protocol.questionnaire is not None:
                questionnaires.append(
                    {
                        "after_trial": len(trials) - 1,
                        "condition": block,
                        "scale": protocol.questionnaire["scale"],
                        "items": [
                            {"category": cat["name"], "item": i + 1, "text": text}
                            for cat in protocol.questionnaire["categories"]
                            for i, text in enumerate(cat["items"])
                        ],
                    }
                )
    return {
        "experiment": protocol.name,
        "title": protocol.title,
        "stimulus": protocol.stimulus,
        "responses": list(protocol.responses),
        "protocol_file": protocol.path,
        "protocol_sha256": protocol.sha256,
        "participant": participant_id,
        "seed": seed,
        "latin_square_row": row if needs_row else None,
        "factors": {ph.name: {f: list(v) for f, v in ph.factors.items()} for ph in protocol.phases},
        "trials": trials,
        "questionnaires": questionnaires,
    }


def expected_response(trial: dict[str, Any]) -> str | None:
    """The right answer of a trial (its direction), None when nothing is answered."""
    return trial.get("direction")
