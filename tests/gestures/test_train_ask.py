"""What ``t`` on the Gestures panel says before training (issue 27: it started at once,
20 s for 60 samples unsaid): the samples, the procedure, and the time at the pace the
last training of the model took (kept in its metadata), or that none was timed yet."""

from __future__ import annotations

from plugins.gestures.train_ask import train_pace, train_question


def test_the_question_says_the_size_and_the_time_at_the_last_pace():
    model = {"train_s": 20.0, "evaluation": {"n_samples": 60}}
    assert train_pace(model) == 20.0 / 60
    said = train_question({"samples": 90}, model, "2fold", 20.0)
    assert said == (
        "t again within 20 s to train: 2fold on 90 samples (2 folds, then every sample), "
        "about 30 s (the last training's pace, 0.33 s a sample)"
    )


def test_without_a_timed_training_its_time_is_said_as_it_runs():
    said = train_question({"samples": 60}, {}, "loso", 20.0)
    assert "loso on 60 samples (a fold per subject, then every sample)" in said
    assert said.endswith("its time said as it runs (no training of this model timed yet)")
    assert train_pace({"train_s": 5.0, "evaluation": {"n_samples": 0}}) is None
