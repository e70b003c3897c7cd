"""The paper's user studies run from the console (section 5): protocols, participants,
crash-safe trials.

Protocols are data (``studies/exp1.toml``, ``exp2.toml``, ``knob.toml``; ``protocol.py``
checks them); a participant's plan is seeded and stored before the first trial
(``plan.py``); every trial event is appended and fsynced (``store.py``; the files and
their columns: this package's ``README.md``); ``runner.py`` runs a plan with pause, replay
and abort, and resumes after a crash at the next trial of the stored plan.

``haptable study run exp1|exp2|knob --participant P01 --out DIR`` (``cli.py``) and the
Studies screen (``panel.py``, tab F10). Stimuli through the contracts only: the
``FlowEffect`` and ``HandFlowEffect`` effects and the knob's ``KnobTrials``; simulated
participants through a registered ``SimulatedObserver`` (``console.core.contracts``).
"""

from __future__ import annotations

from typing import Any

from console.plugin_api import PanelTab, hookimpl

from . import cli


@hookimpl
def haptable_register_commands(register) -> None:
    register(
        "study",
        cli.configure,
        cli.run,
        help="run the paper's user studies (exp1, exp2, knob): participants, resume",
    )


@hookimpl
def haptable_register_panels(register) -> None:
    def studies_panel(app: Any) -> Any:
        # lazy: Textual loads only with the console's panels
        from .panel import StudiesPane

        return StudiesPane()

    register(
        "studies",
        studies_panel,
        description="user studies: protocol, participant, progress, pause, replay, abort",
        tab=PanelTab("Studies", "f10", 100),
    )


@hookimpl
def haptable_register_recording_readers(register) -> None:
    def study_trial(profile: Any) -> Any:
        from .trial_view import make_reader  # lazy: h5py loads when a file is opened

        return make_reader(profile)

    register(
        "study_trial",
        study_trial,
        description="a study's trial file (record trials): its plans and frames in the console",
    )


@hookimpl
def haptable_register_benchmarks(register) -> None:
    def run(ctx, quick: bool) -> dict:
        # lazy: bench loads when called, not at every haptable start
        from .bench import run_bench

        return run_bench(ctx, quick)

    register(
        "study",
        run,
        help="simulated participants: predicted accuracy per region/pair x direction vs "
        "the paper, trials per second",
    )

    def psychophysics(ctx, quick: bool) -> dict:
        # lazy: as above
        from .bench_psychophysics import run_bench as run_psychophysics

        return run_psychophysics(ctx, quick)

    register(
        "psychophysics",
        psychophysics,
        help="adaptive procedures (QUEST+, 1u2d, 1u3d) on 100 simulated observers: threshold "
        "bias and spread vs the truth, convergence vs 70.7 / 79.4 %",
    )
