"""Protocols as data: the paper's counts, orders, counterbalancing and one-line errors."""

from __future__ import annotations

import itertools
from collections import Counter

import pytest

from console.core.errors import UserError
from plugins.studies import protocol as P
from plugins.studies.plan import balanced_latin_square, make_plan


def _phase(plan, name):
    return [t for t in plan["trials"] if t["phase"] == name]


def test_exp1_is_10_familiarisation_then_40_with_one_replay():
    plan = make_plan(P.load("exp1"), "P01")
    fam, main = _phase(plan, "familiarisation"), _phase(plan, "main")
    assert [t["index"] for t in plan["trials"]] == list(range(50))
    assert len(fam) == 10 and plan["trials"][:10] == fam  # familiarisation first
    assert Counter(t["direction"] for t in fam) == {"left_to_right": 5, "right_to_left": 5}
    assert {t["pair"] for t in fam} == {"F"} and {t["replays_allowed"] for t in fam} == {None}
    assert len(main) == 40 and {t["replays_allowed"] for t in main} == {1}
    assert Counter((t["pair"], t["direction"]) for t in main) == {
        (p, d): 5 for p in "1234" for d in ("left_to_right", "right_to_left")
    }
    # the stimulus goes from the left finger's point to the right one's for left-to-right
    t = next(t for t in main if t["pair"] == "4" and t["direction"] == "left_to_right")
    assert (t["stimulus"]["from_point"], t["stimulus"]["to_point"]) == (33, 22)


def test_exp1_random_order_differs_between_participants_and_repeats_per_seed():
    proto = P.load("exp1")
    a, b = make_plan(proto, "P01"), make_plan(proto, "P02")
    key = [(t["pair"], t["direction"]) for t in a["trials"]]
    assert key != [(t["pair"], t["direction"]) for t in b["trials"]]
    assert make_plan(proto, "P01") == a  # seeded: the same plan again


def test_exp2_is_40_preliminary_then_160_by_region_same_order_for_everyone():
    proto = P.load("exp2")
    plans = [make_plan(proto, f"P{k:02d}") for k in (1, 2, 7)]
    for plan in plans:
        pre, main = _phase(plan, "preliminary"), _phase(plan, "main")
        assert len(pre) == 40 and {t["region"] for t in pre} == {"Rprelim"}
        assert Counter(t["direction"] for t in pre) == dict.fromkeys(
            ("up", "down", "left", "right"), 10
        )
        assert {t["replays_allowed"] for t in pre} == {None}
        assert len(main) == 160 and {t["replays_allowed"] for t in main} == {1}
        # region blocks R1..R4, each 4 directions x 10
        assert [r for r, _ in itertools.groupby(t["region"] for t in main)] == [
            "R1",
            "R2",
            "R3",
            "R4",
        ]
        for r in ("R1", "R2", "R3", "R4"):
            block = [t for t in main if t["region"] == r]
            assert Counter(t["direction"] for t in block) == dict.fromkeys(
                ("up", "down", "left", "right"), 10
            )
        # left hand in R1-R2, right in R3-R4
        assert {t["region"]: t["hand"] for t in main} == {
            "R1": "left",
            "R2": "left",
            "R3": "right",
            "R4": "right",
        }
    orders = [[(t["region"], t["direction"]) for t in _phase(p, "main")] for p in plans]
    assert orders[0] == orders[1] == orders[2]  # the same for every participant
    assert len({tuple(o[:10]) for o in orders}) == 1 and len(set(orders[0][:10])) > 1
    # ... while the preliminary block is random per participant
    pres = [[t["direction"] for t in _phase(p, "preliminary")] for p in plans]
    assert pres[0] != pres[1]


@pytest.mark.parametrize("n", [2, 3, 4, 5, 6])
def test_balanced_latin_square_is_latin_and_balanced(n):
    rows = balanced_latin_square(n)
    assert len(rows) == (n if n % 2 == 0 else 2 * n)
    for row in rows:
        assert sorted(row) == list(range(n))
    for c in range(n):  # each column holds each condition equally often
        assert Counter(r[c] for r in rows) == dict.fromkeys(range(n), len(rows) // n)
    # each ordered pair of neighbours equally often (once for even n, twice for odd)
    pairs = Counter((r[j], r[j + 1]) for r in rows for j in range(n - 1))
    assert set(pairs) == {(a, b) for a in range(n) for b in range(n) if a != b}
    assert len(set(pairs.values())) == 1


def test_knob_is_4x3x3x6_counterbalanced_with_questionnaire_after_each_condition():
    proto = P.load("knob")
    plans = [make_plan(proto, f"P{k:02d}") for k in range(1, 9)]
    for plan in plans:
        trials = plan["trials"]
        assert len(trials) == 216 == 4 * 3 * 3 * 6
        blocks = [c for c, _ in itertools.groupby(t["condition"] for t in trials)]
        assert sorted(blocks) == sorted(["V", "HD", "HD+CF", "HD+VF"]) and len(blocks) == 4
        for c in blocks:
            cell = Counter(
                (t["stimulus"]["sectors"], t["stimulus"]["distance_deg"])
                for t in trials
                if t["condition"] == c
            )
            assert cell == {(s, d): 6 for s in (8, 16, 32) for d in (135.0, 270.0, 450.0)}
        qs = plan["questionnaires"]
        assert [q["condition"] for q in qs] == blocks
        assert [q["after_trial"] for q in qs] == [53, 107, 161, 215]
        for q in qs:
            assert q["scale"] == 7 and len(q["items"]) == 14
            assert (
                Counter(i["category"] for i in q["items"])
                == {c: 2 for c in {i["category"] for i in q["items"]}}
                and len({i["category"] for i in q["items"]}) == 7
            )
    orders = [tuple(q["condition"] for q in p["questionnaires"]) for p in plans]
    assert orders[:4] == orders[4:]  # row = number - 1 modulo 4
    assert len(set(orders[:4])) == 4
    for pos in range(4):  # every condition once in every position over four participants
        assert len({o[pos] for o in orders[:4]}) == 4
    follows = Counter((o[j], o[j + 1]) for o in orders[:4] for j in range(3))
    assert len(follows) == 12 and set(follows.values()) == {1}  # balanced

    # inside a condition the trials come in the same order for everyone
    def within(plan, c):
        return [
            (t["stimulus"]["sectors"], t["stimulus"]["distance_deg"])
            for t in plan["trials"]
            if t["condition"] == c
        ]

    assert within(plans[0], "HD") == within(plans[1], "HD") == within(plans[5], "HD")


def test_knob_needs_a_participant_number_for_its_row():
    with pytest.raises(UserError, match="no number at its end"):
        make_plan(P.load("knob"), "alice")
    assert make_plan(P.load("knob"), "alice", row=1)["latin_square_row"] == 1


def _write(tmp_path, text):
    p = tmp_path / "bad.toml"
    p.write_text(text)
    return p


GOOD = """
[study]
name = "t"
stimulus = "hand_flow"
responses = ["up", "down", "left", "right"]
[[regions]]
name = "R1"
center_mm = [100.0, 100.0]
hand = "left"
[[phases]]
name = "main"
factors = { region = ["R1"], direction = ["up", "down", "left", "right"] }
repetitions = 2
replays = 1
"""


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            ("repetitions = 2", "repetitions = 0"),
            r"phases\[0\]\.repetitions = 0: must be an integer",
        ),
        (
            ("replays = 1", "replays = -1"),
            r'phases\[0\]\.replays = -1: give an integer 0..100 or "unlimited"',
        ),
        (("replays = 1", 'replays = "many"'), r"replays = 'many'"),
        (('region = ["R1"]', 'region = ["R9"]'), r"factors\.region = 'R9': use one of R1"),
        (('hand = "left"', 'hand = "middle"'), r"regions\[0\]\.hand = 'middle': must be one of"),
        (('stimulus = "hand_flow"', 'stimulus = "smell"'), r"study\.stimulus = 'smell'"),
        (("repetitions = 2", 'repetitions = 2\norder = "sorted"'), r"order = 'sorted'"),
        (("repetitions = 2", 'repetitions = 2\nblock_order = "latin_square"'), "needs block_by"),
        (
            ("repetitions = 2", "repetitions = 2\ncolour = 3"),
            r"phases\[0\]\.colour is not a protocol key",
        ),
        (
            ('responses = ["up", "down", "left", "right"]', 'responses = ["up"]'),
            r"study\.responses",
        ),
        (("center_mm = [100.0, 100.0]", "center_mm = [100.0]"), r"center_mm = \[100\.0\]"),
        (("[study]", "[stdy]"), r"stdy is not a protocol key"),
        (('name = "main"', 'name = "main"\nquestionnaire_after_block = true'), "needs block_by"),
    ],
)
def test_bad_protocols_are_one_line_naming_file_key_value(tmp_path, change, message):
    P.load(_write(tmp_path, GOOD))  # the unchanged protocol is fine
    path = _write(tmp_path, GOOD.replace(*change, 1))
    with pytest.raises(UserError, match=message) as e:
        P.load(path)
    assert "\n" not in str(e.value) and str(path) in str(e.value)


def test_a_knob_distance_must_be_whole_sectors(tmp_path):
    text = P.find("knob").read_text().replace("[135, 270, 450]", "[135, 100, 450]")
    with pytest.raises(UserError, match=r"distance_deg = 100: not a whole number of 8-sector"):
        P.load(_write(tmp_path, text))


def test_unknown_study_and_broken_toml(tmp_path):
    with pytest.raises(UserError, match="no protocol of that name; use one of exp1, exp2, jnd_"):
        P.load("exp9")
    with pytest.raises(UserError, match="not valid TOML"):
        P.load(_write(tmp_path, "[study\n"))
