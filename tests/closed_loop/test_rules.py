"""Both lookup-table rules played on the twin (plugins.twin.plate.rule_check): the
perceptual tables give more achieved contrast over all pairs and under the hand regions,
and on the accelerance-derived map the paper's rule picks a low bin the plate does not
really play while the perceptual rule keeps a tactile frequency. The steady-state
shortcut used for all pairs is checked against the time response through the gate."""

from __future__ import annotations

import pytest

from .conftest import REGIONS

PLAYED = ((51, 52),)


@pytest.fixture(scope="module")
def rules(loop_outputs, loop_profile, measured_map, loop_plugins):
    from plugins.twin.plate.rule_check import compare_rules, format_rules

    with loop_outputs() as out:
        res = compare_rules(
            out,
            loop_profile,
            measured_map,
            plugins=loop_plugins,
            played_pairs=PLAYED,
            regions=REGIONS,
        )
    print("\n" + format_rules(res))
    return res


def test_perceptual_tables_give_more_contrast_on_the_twin(rules):
    paper, per = rules["paper"], rules["perceptual"]
    for name in ("all_pairs", "under_hand"):
        assert per[name]["contrast_db_median"] > paper[name]["contrast_db_median"] + 6
        assert per[name]["passive_felt_pct"] < paper[name]["passive_felt_pct"]
        assert per[name]["felt_jnd_median"] > paper[name]["felt_jnd_median"]
        # the active point still reaches (nearly) the target level
        assert per[name]["active_sl_db_median"] > 15
    assert per["played"]["min_contrast_db"] > paper["played"]["min_contrast_db"]


def test_accelerance_map_frequencies_and_what_the_plate_does(rules):
    paper, per = rules["paper"]["accelerance"], rules["perceptual"]["accelerance"]
    assert paper["51->52_hz"] < 20 and 150 <= per["51->52_hz"] <= 300
    assert paper["below_20hz_pct"] > 50 and per["below_20hz_pct"] < 1
    # the paper's low-bin entries come from noise: on the plate the flow is not felt
    assert paper["active_sl_db_median"] < 0 < per["active_sl_db_median"]


def test_steady_state_matches_the_played_flow(rules, loop_profile, measured_map, loop_effects):
    from plugins.twin.plate.closed_loop import twin_of
    from plugins.twin.plate.rule_check import steady_levels

    for rule in ("paper", "perceptual"):
        t = loop_effects[0].tables(vmap=measured_map, rule=rule)
        a, b = measured_map.point_index(51), measured_map.point_index(52)
        lv = steady_levels(loop_profile, twin_of(loop_profile), t, [(a, b)])
        row = rules[rule]["played"]["rows"][0]  # part 1 of 51 -> 52
        assert row["frequency_hz"] == lv["frequency_hz"][0]
        assert lv["contrast_db"][0] == pytest.approx(row["ach_contrast_db"], abs=1.0)
        assert lv["active_sl_db"][0] == pytest.approx(row["ach_active_sl_db"], abs=1.0)
