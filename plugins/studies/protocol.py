"""Study protocols as data: ``studies/<name>.toml`` read and checked with one-line errors.

A protocol has ``[study]`` (name, title, stimulus ``flow`` | ``hand_flow`` | ``knob``,
responses, seed, and the projected ``scene`` whose touched buttons answer), the stimulus places (``[[pairs]]`` for ``flow``: ``name``, ``left`` and
``right`` grid point ids; ``[[regions]]`` for ``hand_flow``: ``name``, ``center_mm``,
``hand``), ``[[phases]]`` and, for the knob, ``[questionnaire]``. A phase crosses its
``factors`` (a table of lists), repeats them ``repetitions`` times and orders them:

- ``order``: ``random`` (seeded per participant) or ``same_for_all`` (seeded by the
  protocol's seed only: the same order for every participant);
- ``block_by`` (a factor): trials grouped by its levels, the blocks in ``block_order``
  ``listed`` | ``random`` | ``latin_square`` (a balanced Latin square over participants);
- ``replays``: replays allowed per trial, an integer or ``"unlimited"``;
- ``questionnaire_after_block``: the questionnaire after each block.

A pair, region or questionnaire category is named once (a second would silently redefine
it); a factor's levels are names or numbers. The file is read bounded (``textfiles``: a
regular file of at most 1 MB, UTF-8, nesting TOML can parse). Every mistake is a
``UserError`` naming the file, the key, the value and the fix.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from console.plugin_api import Field, UserError, check, parse_toml_text

from . import sensation, textfiles

STIMULI = ("flow", "hand_flow", "knob")
ORDERS = ("random", "same_for_all")
BLOCK_ORDERS = ("listed", "random", "latin_square")
#: the factor each stimulus needs in every phase, besides its own place factor
FACTORS = {
    "flow": ("pair", "direction"),
    "hand_flow": ("region", "direction"),
    "knob": ("condition", "sectors", "distance_deg"),
}
EXP1_DIRECTIONS = ("left_to_right", "right_to_left")
HAND_DIRECTIONS = ("up", "down", "left", "right")
MAX_TRIALS = 100_000

STUDY_FIELDS = {
    "name": Field("str", help="the protocol's short name"),
    "title": Field("str", "", help="what the experimenter reads"),
    "stimulus": Field("str", choices=STIMULI, help="how a trial is played"),
    "responses": Field("strs", [], help="the answers a participant may give"),
    "seed": Field("int", 0, min=0, help="seeds the orders shared by every participant"),
    "scene": Field("str", "", help="the projected scene whose touched buttons answer"),
    "level": Field("str", "", help='stimulus level: "20 dB SL" or "1.5 V" (sensation.py)'),
}
PHASE_FIELDS = {
    "name": Field("str", help="the phase's name (familiarisation, main ...)"),
    "repetitions": Field("int", min=1, max=1000, help="repetitions of each factor cell"),
    "order": Field("str", "random", choices=ORDERS, help="trial order inside a block"),
    "block_by": Field("str", "", help="a factor whose levels are blocks"),
    "block_order": Field("str", "listed", choices=BLOCK_ORDERS, help="order of the blocks"),
    "questionnaire_after_block": Field("bool", False, help="the questionnaire after a block"),
}


@dataclass(frozen=True)
class Phase:
    name: str
    factors: dict[str, tuple[Any, ...]]
    repetitions: int
    order: str
    block_by: str
    block_order: str
    replays: int | None  # None: unlimited
    questionnaire_after_block: bool

    @property
    def n_trials(self) -> int:
        n = self.repetitions
        for levels in self.factors.values():
            n *= len(levels)
        return n


@dataclass(frozen=True)
class Protocol:
    name: str
    title: str
    stimulus: str
    responses: tuple[str, ...]
    seed: int
    phases: tuple[Phase, ...]
    pairs: dict[str, dict[str, int]] = field(default_factory=dict)
    regions: dict[str, dict[str, Any]] = field(default_factory=dict)
    questionnaire: dict[str, Any] | None = None
    scene: str = ""
    level: str = ""  # "" (the effect's own), "<n> dB SL" or "<v> V": sensation.parse_level
    path: str = ""
    sha256: str = ""

    @property
    def n_trials(self) -> int:
        return sum(p.n_trials for p in self.phases)


def studies_dir() -> Path:
    """The repository's ``studies/`` folder (beside ``profiles/``)."""
    return Path(__file__).resolve().parents[2] / "studies"


def available() -> list[str]:
    """The protocol names in ``studies/``."""
    d = studies_dir()
    return sorted(p.stem for p in d.glob("*.toml")) if d.is_dir() else []


def find(name_or_path: str | Path) -> Path:
    """A protocol's file: a path, or a name in ``studies/``."""
    p = Path(name_or_path).expanduser()
    if p.exists() or p.is_symlink():
        return p  # what it is (a FIFO, a folder ...) is checked when it is read
    if p.suffix == ".toml":
        raise UserError(f"{p}: no such protocol file; give a TOML file or one of {available()}")
    q = studies_dir() / f"{name_or_path}.toml"
    if not q.is_file():
        raise UserError(
            f"study {str(name_or_path)!r}: no protocol of that name; use one of "
            f"{', '.join(available()) or '(none)'} or a path to a .toml file"
        )
    return q


def load(name_or_path: str | Path) -> Protocol:
    """Read and check a protocol (a name in ``studies/`` or a file path)."""
    path = find(name_or_path)
    fix = f"give a protocol .toml file or one of {', '.join(available()) or '(none)'}"
    raw_bytes = textfiles.read_bytes(
        path, what="study protocol", fix=fix, limit=textfiles.MAX_PROTOCOL_BYTES
    )
    text = textfiles.decode(raw_bytes, str(path), "save the protocol as UTF-8 text")
    raw = parse_toml_text(text, where=str(path), what="study protocol")
    return parse(raw, str(path), sha256=hashlib.sha256(raw_bytes).hexdigest())


def _bad(where: str, key: str, value: Any, fix: str) -> UserError:
    return UserError(f"{where}: {key} = {value!r}: {fix}")


def _fields(where: str, table: Any, fields: dict[str, Field], prefix: str) -> dict[str, Any]:
    if not isinstance(table, dict):
        raise _bad(where, prefix.rstrip("."), table, "must be a table")
    out = {}
    for key, f in fields.items():
        if key not in table:
            if f.required:
                raise UserError(f"{where}: {prefix}{key} is missing; add it ({f.help})")
            out[key] = f.default
            continue
        ok, v = check(f, table[key])
        if not ok:
            raise _bad(where, prefix + key, table[key], f"must be {f.allowed()} ({f.help})")
        out[key] = v
    return out


def _unknown(where: str, table: dict, known: set[str], prefix: str) -> None:
    for key in table:
        if key not in known:
            raise UserError(
                f"{where}: {prefix}{key} is not a protocol key; use one of {', '.join(sorted(known))}"
            )


def parse(raw: dict[str, Any], where: str = "<protocol>", *, sha256: str = "") -> Protocol:
    """A checked ``Protocol`` from a parsed TOML document."""
    if "procedure" in raw:
        raise UserError(
            f"{where}: an adaptive protocol ([procedure]) has no ANOVA analysis; its thresholds "
            "are in each participant's adaptive_result.json and thresholds.json"
        )
    _unknown(where, raw, {"study", "pairs", "regions", "phases", "questionnaire"}, "")
    if "study" not in raw:
        raise UserError(f"{where}: [study] is missing; add it with name and stimulus")
    study = _fields(where, raw["study"], STUDY_FIELDS, "study.")
    _unknown(where, raw["study"], set(STUDY_FIELDS), "study.")
    stim = study["stimulus"]
    sensation.parse_level(study["level"], where, stim)  # a bad level is one line here
    pairs = _pairs(where, raw.get("pairs", [])) if stim == "flow" else {}
    regions = _regions(where, raw.get("regions", [])) if stim == "hand_flow" else {}
    responses = tuple(study["responses"])
    want = {"flow": EXP1_DIRECTIONS, "hand_flow": HAND_DIRECTIONS, "knob": ()}[stim]
    if stim != "knob" and sorted(responses) != sorted(want):
        raise _bad(
            where, "study.responses", list(responses), f"a {stim} study answers {list(want)}"
        )
    phases_raw = raw.get("phases")
    if not isinstance(phases_raw, list) or not phases_raw:
        raise UserError(f"{where}: [[phases]] is missing; add at least one phase")
    names: set[str] = set()
    phases = []
    for i, ph in enumerate(phases_raw):
        phase = _phase(where, i, ph, stim, pairs, regions, want)
        if phase.name in names:
            raise _bad(where, f"phases[{i}].name", phase.name, "phase names must differ")
        names.add(phase.name)
        phases.append(phase)
    q = raw.get("questionnaire")
    questionnaire = _questionnaire(where, q) if q is not None else None
    if any(p.questionnaire_after_block for p in phases) and questionnaire is None:
        raise UserError(
            f"{where}: a phase asks for the questionnaire but [questionnaire] is missing; add it"
        )
    proto = Protocol(
        name=study["name"],
        title=study["title"] or study["name"],
        stimulus=stim,
        responses=responses,
        seed=study["seed"],
        phases=tuple(phases),
        pairs=pairs,
        regions=regions,
        questionnaire=questionnaire,
        scene=study["scene"],
        level=study["level"],
        path=where,
        sha256=sha256,
    )
    if proto.n_trials > MAX_TRIALS:
        raise UserError(
            f"{where}: {proto.n_trials} trials; at most {MAX_TRIALS}: fewer repetitions"
        )
    return proto


def _pairs(where: str, items: Any) -> dict[str, dict[str, int]]:
    if not isinstance(items, list) or not items:
        raise UserError(f"{where}: [[pairs]] is missing; a flow study names its point pairs")
    f = {
        "name": Field("str", help="the pair's name"),
        "left": Field("int", min=0, help="grid point id under the left index finger"),
        "right": Field("int", min=0, help="grid point id under the right index finger"),
    }
    out: dict[str, dict[str, int]] = {}
    for i, it in enumerate(items):
        v = _fields(where, it, f, f"pairs[{i}].")
        _unknown(where, it, set(f), f"pairs[{i}].")
        if v["left"] == v["right"]:
            raise _bad(where, f"pairs[{i}].right", v["right"], "a pair needs two different points")
        _unique(where, "pairs", i, v["name"], out)
        out[v["name"]] = {"left": v["left"], "right": v["right"]}
    return out


def _unique(where: str, table: str, i: int, name: str, seen: dict[str, Any]) -> None:
    """A name given twice in ``[[table]]`` (the later would silently redefine it)."""
    if name in seen:
        first = list(seen).index(name)
        raise _bad(
            where,
            f"{table}[{i}].name",
            name,
            f"{table}[{first}] has that name already; give each its own name",
        )


def _regions(where: str, items: Any) -> dict[str, dict[str, Any]]:
    if not isinstance(items, list) or not items:
        raise UserError(f"{where}: [[regions]] is missing; a hand_flow study names its regions")
    f = {
        "name": Field("str", help="the region's name"),
        "center_mm": Field("floats", length=2, min=0, max=1e4, help="[x, y] in mm"),
        "hand": Field("str", choices=("left", "right"), help="the hand resting there"),
    }
    out: dict[str, dict[str, Any]] = {}
    for i, it in enumerate(items):
        v = _fields(where, it, f, f"regions[{i}].")
        _unknown(where, it, set(f), f"regions[{i}].")
        _unique(where, "regions", i, v["name"], out)
        out[v["name"]] = {"center_mm": v["center_mm"], "hand": v["hand"]}
    return out


def _phase(
    where: str, i: int, ph: Any, stim: str, pairs: dict, regions: dict, directions: tuple
) -> Phase:
    pre = f"phases[{i}]."
    v = _fields(where, ph, PHASE_FIELDS, pre)
    _unknown(where, ph, set(PHASE_FIELDS) | {"factors", "replays"}, pre)
    factors = ph.get("factors")
    if not isinstance(factors, dict) or not factors:
        raise UserError(f"{where}: {pre}factors is missing; add a table of factor lists")
    need = FACTORS[stim]
    if sorted(factors) != sorted(need):
        raise _bad(where, pre + "factors", sorted(factors), f"a {stim} phase crosses {list(need)}")
    levels: dict[str, tuple[Any, ...]] = {}
    for name in need:
        vals = factors[name]
        if not isinstance(vals, list) or not vals or len(set(map(str, vals))) != len(vals):
            raise _bad(where, f"{pre}factors.{name}", vals, "give a list of distinct levels")
        for x in vals:
            if isinstance(x, bool) or not isinstance(x, str | int | float):
                raise _bad(
                    where, f"{pre}factors.{name}", x, "a level is a name or a number, not a list"
                )
        known = {
            "pair": pairs,
            "region": regions,
            "direction": directions,
        }.get(name)
        for x in vals:
            if known is not None and x not in known:
                raise _bad(
                    where, f"{pre}factors.{name}", x, f"use one of {', '.join(map(str, known))}"
                )
            if name == "sectors" and not (isinstance(x, int) and x >= 2):
                raise _bad(where, f"{pre}factors.sectors", x, "give whole sector counts >= 2")
            if name == "distance_deg" and not (
                isinstance(x, int | float) and not isinstance(x, bool) and 0 < x <= 3600
            ):
                raise _bad(where, f"{pre}factors.distance_deg", x, "give degrees in (0, 3600]")
            if name == "condition" and not isinstance(x, str):
                raise _bad(where, f"{pre}factors.condition", x, "give condition names")
        levels[name] = tuple(vals)
    if "sectors" in levels and "distance_deg" in levels:
        for n in levels["sectors"]:
            for d in levels["distance_deg"]:
                steps = d / (360.0 / n)
                if abs(steps - round(steps)) > 1e-9:
                    raise _bad(
                        where,
                        f"{pre}factors.distance_deg",
                        d,
                        f"not a whole number of {n}-sector items; use a multiple of {360 / n:g}",
                    )
    if v["block_by"] and v["block_by"] not in levels:
        raise _bad(where, pre + "block_by", v["block_by"], f"use one of {list(levels)} or omit it")
    if v["block_order"] != "listed" and not v["block_by"]:
        raise _bad(where, pre + "block_order", v["block_order"], "needs block_by (the factor)")
    if v["questionnaire_after_block"] and not v["block_by"]:
        raise _bad(where, pre + "questionnaire_after_block", True, "needs block_by")
    rep = ph.get("replays", 0)
    if rep == "unlimited":
        replays = None
    elif isinstance(rep, int) and not isinstance(rep, bool) and 0 <= rep <= 100:
        replays = rep
    else:
        raise _bad(where, pre + "replays", rep, 'give an integer 0..100 or "unlimited"')
    return Phase(
        name=v["name"],
        factors=levels,
        repetitions=v["repetitions"],
        order=v["order"],
        block_by=v["block_by"],
        block_order=v["block_order"],
        replays=replays,
        questionnaire_after_block=v["questionnaire_after_block"],
    )


def _questionnaire(where: str, q: Any) -> dict[str, Any]:
    if not isinstance(q, dict):
        raise _bad(where, "questionnaire", q, "must be a table")
    _unknown(where, q, {"scale", "categories"}, "questionnaire.")
    scale = q.get("scale", 7)
    # one key per point on the Studies screen (``1``..``9``): a longer scale could not be
    # answered there
    if not (isinstance(scale, int) and not isinstance(scale, bool) and 2 <= scale <= 9):
        raise _bad(
            where,
            "questionnaire.scale",
            scale,
            "give the points of the scale, 2..9 (one key each: 1..9)",
        )
    cats = q.get("categories")
    if not isinstance(cats, list) or not cats:
        raise UserError(f"{where}: questionnaire.categories is missing; list the categories")
    out = []
    names: dict[str, Any] = {}
    for i, c in enumerate(cats):
        pre = f"questionnaire.categories[{i}]"
        if not isinstance(c, dict) or not isinstance(c.get("name"), str):
            raise _bad(where, pre, c, 'give { name = "...", items = ["...", ...] }')
        _unique(where, "questionnaire.categories", i, c["name"], names)
        names[c["name"]] = c
        items = c.get("items")
        if not isinstance(items, list) or not items or not all(isinstance(s, str) for s in items):
            raise _bad(where, pre + ".items", items, "give a list of item texts")
        out.append({"name": c["name"], "items": list(items)})
    return {"scale": scale, "categories": out}
