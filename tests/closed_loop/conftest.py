"""Session fixtures: the sim profile's twin map measured once through the registered
vibrometer, its lookup tables, and the closed-loop rows (flows played through the
safety gate on the twin outputs, then into the plate twin).

The map is the full default sweep (0-625 Hz, 0.1 Hz lines, 84 points, 5 excitations,
3 sweeps): ~5 s on an idle 2-core machine. Parts are 1.5 s (the paper's Fig. 9).
"""

from __future__ import annotations

from pathlib import Path

import pytest

#: What the tests play (a subset of the benchmark's): the paper's 51/52 both ways, a
#: diagonal pair (Fig. 10 style) both ways, and a long pair driven by PB.
PAIRS = ((51, 52), (52, 51), (27, 40), (40, 27), (14, 71))
#: Hand regions (centre mm) and the directions played there: "left"/"down" are the same
#: two parts in the other order (same tones; only the ring-down overlap differs), so one
#: per axis is played here; the benchmark plays all four. (580, 150) is a clean case;
#: the other two are where a scan of the whole table (haptable bench closed-loop) found
#: failures: ring-down overlap at the switch (281.73, 223.645) and, at the right edge,
#: an active side that ends below the 3-JND line plus the overlap (641.73, 163.645).
REGIONS = ((580.0, 150.0), (281.73, 223.645), (641.73, 163.645))
DIRECTIONS = ("right", "up")


@pytest.fixture(scope="session")
def loop_plugins():
    from console.config.plugins import load_plugins

    return load_plugins()


@pytest.fixture(scope="session")
def loop_profile(loop_plugins):
    from console.config.profile import load_profile

    return load_profile("sim", loop_plugins)


@pytest.fixture(scope="session")
def measured_map(loop_profile, loop_plugins):
    from plugins.twin.plate.loop_play import measured_map, one_blas_thread

    with one_blas_thread():
        return measured_map(loop_profile, loop_plugins)


@pytest.fixture(scope="session")
def loop_effects(loop_profile, loop_plugins):
    """The registered flow and hand_flow effects with the check's 1.5 s parts."""
    from plugins.twin.plate.loop_play import effects_of

    return effects_of(loop_profile, loop_plugins)


@pytest.fixture(scope="session")
def loop_tables(measured_map, loop_effects):
    """The paper's tables (largest absolute difference, Fig. 8) of the measured map."""
    return loop_effects[0].tables(vmap=measured_map, min_contrast_db=0.0)


@pytest.fixture(scope="session")
def loop_outputs(loop_profile, loop_plugins):
    """Opens the sim outputs (fast-forward) for the time of a ``with`` block: each row set
    plays on outputs of its own, closed after, rather than a kernel kept idle for the
    rest of the session."""

    def opened():
        from console.kernel.client import open_outputs

        return open_outputs(loop_profile, loop_plugins, fast=True)

    return opened


@pytest.fixture(scope="session")
def pair_rows(loop_outputs, loop_profile, loop_tables, loop_plugins):
    from plugins.twin.plate.loop_check import flow_pairs_check
    from plugins.twin.plate.loop_report import format_pairs

    with loop_outputs() as out:
        rows = flow_pairs_check(
            out, loop_profile, loop_tables, PAIRS, plugins=loop_plugins, ringdown_gap_k=0
        )
    print("\nclosed loop, flows between points (um; tone amplitude at the part's frequency):")
    print(format_pairs(rows))
    return rows


@pytest.fixture(scope="session")
def region_rows(loop_outputs, loop_profile, measured_map, loop_plugins):
    from plugins.twin.plate.loop_check import hand_regions_check
    from plugins.twin.plate.loop_report import format_regions

    with loop_outputs() as out:
        rows = hand_regions_check(
            out,
            loop_profile,
            measured_map,
            REGIONS,
            DIRECTIONS,
            plugins=loop_plugins,
            ringdown_gap_k=0,
        )
    print("\nclosed loop, flows under a hand (square levels, um; X = 3 JND above threshold):")
    print(format_regions(rows))
    return rows


@pytest.fixture(scope="session")
def option_pair_rows(loop_outputs, loop_profile, measured_map, loop_plugins):
    """The same pairs with a 10 dB contrast floor and a 3-decay-time ring-down gap."""
    from plugins.twin.plate.loop_check import flow_pairs_check
    from plugins.twin.plate.loop_report import format_pairs

    with loop_outputs() as out:
        rows = flow_pairs_check(
            out,
            loop_profile,
            measured_map,
            PAIRS,
            plugins=loop_plugins,
            min_contrast_db=10.0,
            ringdown_gap_k=3.0,
        )
    print("\nclosed loop, the same flows with min_contrast_db 10 and ringdown_gap_k 3:")
    print(format_pairs(rows))
    return rows


@pytest.fixture(scope="session")
def gap_pair_rows(loop_outputs, loop_profile, loop_tables, loop_plugins):
    """The paper's tables with only the ring-down gap (3 decay times)."""
    from plugins.twin.plate.loop_check import flow_pairs_check

    with loop_outputs() as out:
        return flow_pairs_check(
            out, loop_profile, loop_tables, PAIRS, plugins=loop_plugins, ringdown_gap_k=3.0
        )


@pytest.fixture(scope="session")
def gap_region_rows(loop_outputs, loop_profile, measured_map, loop_plugins):
    """The hand regions played with the ring-down gap (3 decay times)."""
    from plugins.twin.plate.loop_check import hand_regions_check
    from plugins.twin.plate.loop_report import format_regions

    with loop_outputs() as out:
        rows = hand_regions_check(
            out,
            loop_profile,
            measured_map,
            REGIONS,
            DIRECTIONS,
            plugins=loop_plugins,
            ringdown_gap_k=3.0,
        )
    print("\nclosed loop, flows under a hand with ringdown_gap_k 3:")
    print(format_regions(rows))
    return rows


def pytest_collection_modifyitems(items) -> None:
    """Every closed-loop test on one xdist worker: the session fixtures above (the twin's
    measured map, the tables, the pair and region rows: ~20 s) are computed once, not on
    each worker that runs one of these tests."""
    here = Path(__file__).parent
    for item in items:
        if here in Path(item.fspath).parents:
            item.add_marker(pytest.mark.xdist_group("closed_loop"))
