"""``gestures synth --renderer R``: options a renderer does not model are refused in one
line that names them and the fix, before anything is written."""

from __future__ import annotations

import pytest

from console.cli.main import main


@pytest.mark.parametrize(
    ("renderer", "options", "named"),
    [
        ("phalanx", ["--lens-distortion"], "--lens-distortion"),
        ("phalanx", ["--randomise"], "--randomise"),
        ("silhouette", ["--exposure-ms", "8"], "--exposure-ms"),
        ("silhouette", ["--dynamic-frames", "4"], "--dynamic-frames"),
    ],
)
def test_options_a_renderer_does_not_take_are_refused(tmp_path, capsys, renderer, options, named):
    out = tmp_path / "set"
    assert main(["gestures", "synth", "--renderer", renderer, *options, "--out", str(out)]) != 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"haptable: error: {named}")
    assert f"the {renderer} renderer does not take" in err[0] and "--renderer twin" in err[0]
    assert not out.exists()
