"""The ``[recording]`` profile section: off by default; where a run is recorded and how."""

from __future__ import annotations

from console.plugin_api import Field

#: lossless codecs for the frames: HDF5's deflate at level 1 (compressed by zlib outside
#: HDF5, which lets go of the GIL: the frame loop runs meanwhile) or lzf (h5py's filter)
CODECS = ("gzip1", "lzf")

FIELDS = {
    "enabled": Field("bool", False, help="record every demo run into an HDF5 file"),
    "path": Field(
        "str",
        "",
        help="the file (relative: to the profile's folder); empty: "
        "recording-<UTC time>.h5 in HapTable's data directory",
    ),
    "codec": Field("str", "gzip1", choices=CODECS, help="lossless frame compression"),
    "queue_frames": Field(
        "int", 240, min=8, max=10000, help="frames waiting for the writer before one is dropped"
    ),
    "flush_s": Field(
        "float", 0.5, min=0.05, max=60.0, help="flush to disk this often (a crash loses less)"
    ),
    "study_trials": Field(
        "bool",
        False,
        help="record each study trial into its participant's folder (study run --record)",
    ),
    "replay_file": Field(
        "str", "", help="the recording the camera driver 'replay' plays (at its recorded pace)"
    ),
}
