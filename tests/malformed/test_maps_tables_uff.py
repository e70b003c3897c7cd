"""A corpus of malformed vibration maps, lookup tables, UFF files and grid arguments.

Every case runs the real ``haptable`` command in-process and must end with ONE line on
stderr (``haptable: error: ...``, exit 2) naming the file (or the argument) and the
offending key or value: never a traceback, an internal error (exit 3) or a silent
success. The files are generated here (nothing binary is committed).
"""

from __future__ import annotations

import io
import json
import struct
import zipfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from console.cli.main import main
from console.core.types import EXCITATIONS

F_HZ = np.arange(0.0, 651.0, 25.0)


# ---------------------------------------------------------------------- the good files
@pytest.fixture(scope="module")
def good(tmp_path_factory) -> dict:
    """A small valid map (84 points, 27 bins) and the tables built from it."""
    from console.files.vibration_map import save_map
    from plugins.vibrotactile.analytic_plate import analytic_map
    from plugins.vibrotactile.tables import build_tables, save_tables

    d = tmp_path_factory.mktemp("good")
    m = analytic_map(freq_hz=F_HZ)
    mp = save_map(d / "map.npz", m)
    tp = save_tables(d / "tables.npz", build_tables(m, 650.0))
    return {"map": mp, "tables": tp, "vmap": m}


def arrays(path: Path) -> dict[str, np.ndarray]:
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def put(path: Path, blob: bytes | str) -> Path:
    """Write ``blob`` to ``path`` and return the path."""
    path.write_bytes(blob.encode() if isinstance(blob, str) else blob)
    return path


def write_npz(path: Path, data: dict) -> Path:
    with open(path, "wb") as fh:
        np.savez(fh, **data)
    return path


def changed(src: Path, dst: Path, drop: tuple[str, ...] = (), **new) -> Path:
    data = {k: v for k, v in arrays(src).items() if k not in drop}
    data.update(new)
    return write_npz(dst, data)


def meta_of(src: Path, prefix: str = "") -> dict:
    return json.loads(str(arrays(src)[f"{prefix}meta_json"]))


def npy_bytes(header: dict, payload: bytes = b"") -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, header)
    return buf.getvalue() + payload


def zip_with(path: Path, members: dict[str, bytes], method=zipfile.ZIP_STORED) -> Path:
    with zipfile.ZipFile(path, "w", method) as z:
        for name, blob in members.items():
            z.writestr(name, blob)
    return path


def lying_size(src: Path, dst: Path, size: int) -> Path:
    """``src`` with every member's declared uncompressed size set to ``size`` (< 4 GiB)."""
    blob = bytearray(src.read_bytes())
    with zipfile.ZipFile(src) as z:
        infos = z.infolist()
    for info in infos:  # local header: uncompressed size at offset 22
        struct.pack_into("<I", blob, info.header_offset + 22, size)
    cd = blob.find(b"PK\x01\x02")
    while cd != -1:  # central directory entry: uncompressed size at offset 24
        struct.pack_into("<I", blob, cd + 24, size)
        cd = blob.find(b"PK\x01\x02", cd + 4)
    dst.write_bytes(bytes(blob))
    return dst


# ---------------------------------------------------------------------- UFF writers
def uff58(path: Path, nodes=(1, 2, 3), *, binary=False, data=None, f=None, kind=8, **over):
    import pyuff

    f = np.arange(0.0, 101.0, 10.0) if f is None else f
    sets = []
    for n in nodes:
        d = np.full(f.size, 1e-6 * 50, complex) if data is None else data
        kw = dict(
            binary=int(binary),
            func_type=4,
            rsp_node=int(n),
            rsp_dir=3,
            ref_node=1,
            ref_dir=3,
            ord_data_type=6,
            num_pts=f.size,
            abscissa_spacing=0,
            abscissa_min=float(f[0]),
            abscissa_inc=0.0,
            abscissa_spec_data_type=18,
            ordinate_spec_data_type=kind,
            orddenom_spec_data_type=1,  # the generator voltage ("general", unit V)
            orddenom_axis_units_lab="V",
            data=d,
            x=f,
            id1="vibrometer",
            rsp_ent_name="pt",
            ref_ent_name="gen",
        )
        kw.update(over)
        sets.append(pyuff.prepare_58(**kw))
    pyuff.UFF(str(path)).write_sets(sets, mode="overwrite")
    return path


def uff_text_edit(path: Path, old: str, new: str, count: int = 1) -> Path:
    text = path.read_text()
    assert old in text, old
    path.write_text(text.replace(old, new, count))
    return path


# ---------------------------------------------------------------------- the cases
@dataclass(frozen=True)
class Case:
    """``make(dir, good) -> (argv, words)``: every word must be in the one line."""

    id: str
    kind: str  # map | tables | uff | args
    make: Callable[[Path, dict], tuple[list[str], list[str]]]


def _map(name, build, *words, cmd=("frf", "info")):
    def make(d, g):
        p = build(d, g)
        return [*cmd, str(p)], [str(p), *words]

    return Case(name, "map", make)


def _mapkey(name, *words, drop=(), **new):
    return _map(name, lambda d, g: changed(g["map"], d / "m.npz", drop, **new), *words)


def _meta(name, edit, *words):
    def build(d, g):
        if callable(edit):
            meta = meta_of(g["map"])
            edit(meta)
            text = json.dumps(meta)
        else:
            text = edit
        return changed(g["map"], d / "m.npz", meta_json=np.array(text))

    return _map(name, build, "meta_json", *words)


def _frf(g, fn):
    frf = arrays(g["map"])["frf_um_per_v"].copy()
    fn(frf)
    return frf


def _bomb(d, g):
    """A real deflate bomb: 40 MB of zeros in ~40 kB (the limit is lowered to 8 MB)."""
    p = d / "bomb.npz"
    n = 40 * 2**20 // 16
    with (
        zipfile.ZipFile(p, "w", zipfile.ZIP_DEFLATED) as z,
        z.open("frf_um_per_v.npy", "w", force_zip64=True) as fh,
    ):
        np.lib.format.write_array_header_1_0(
            fh, {"descr": "<c16", "fortran_order": False, "shape": (n,)}
        )
        zeros = bytes(2**20)
        for _ in range(40):
            fh.write(zeros)
    return p


def _huge_header(d, g):
    hdr = {"descr": "<c16", "fortran_order": False, "shape": (10**12,)}
    return zip_with(d / "huge.npz", {"frf_um_per_v.npy": npy_bytes(hdr, b"\0" * 64)})


def _crc(d, g):
    src = write_npz(d / "plain.npz", arrays(g["map"]))  # stored: the payload is visible
    blob = bytearray(src.read_bytes())
    i = blob.find(b"\x93NUMPY", blob.find(b"freq_hz.npy"))
    blob[i + 200] ^= 0xFF
    (d / "crc.npz").write_bytes(bytes(blob))
    return d / "crc.npz"


def _bad_header(d, g):
    return zip_with(d / "hdr.npz", {"freq_hz.npy": b"\x93NUMPY\x01\x00\x10\x00{garbage}      \n"})


MAP_CASES = [
    _map("empty", lambda d, g: put(d / "e.npz", b""), "empty"),
    _map(
        "truncated",
        lambda d, g: put(d / "t.npz", g["map"].read_bytes()[:3000]),
        "zip",
    ),
    _map("text", lambda d, g: put(d / "x.npz", "hello\n"), "zip"),
    _map(
        "npy-not-npz",
        lambda d, g: (np.save(d / "a.npy", np.zeros(3)), d / "a.npy")[1],
        "npz",
    ),
    _map(
        "pickle-file",
        lambda d, g: put(d / "p.npz", __import__("pickle").dumps({"a": 1})),
        "zip",
    ),
    _map(
        "member-not-npy",
        lambda d, g: zip_with(d / "r.npz", {"readme.txt": b"hi"}),
        "readme.txt",
    ),
    _mapkey(
        "object-array",
        "frf_um_per_v",
        "pickle",
        frf_um_per_v=np.array([{"a": 1}, None], dtype=object),
    ),
    _map("header-1e12-elements", _huge_header, "frf_um_per_v"),
    _map(
        "declared-4gb",
        lambda d, g: lying_size(g["map"], d / "lie.npz", 0xFFFF0000),
        "uncompressed",
    ),
    _map("deflate-bomb", _bomb, "uncompressed"),
    _map("crc-corrupt", _crc, "freq_hz"),
    _map("bad-npy-header", _bad_header, "freq_hz"),
    *[_mapkey(f"missing-{k}", k, drop=(k,)) for k in ("frf_um_per_v", "freq_hz", "points")],
    *[_mapkey(f"missing-{k}", k, drop=(k,)) for k in ("points_mm", "masked", "meta_json")],
    _mapkey("missing-excitations", "excitations", drop=("excitations",)),
    _mapkey("extra-key", "calibration", calibration=np.ones(3)),
    _map(
        "frf-real",
        lambda d, g: changed(g["map"], d / "m.npz", frf_um_per_v=np.abs(_frf(g, lambda a: a))),
        "frf_um_per_v",
        "complex",
    ),
    _mapkey("frf-strings", "frf_um_per_v", frf_um_per_v=np.array(["1+1j", "2"])),
    _mapkey("freq-strings", "freq_hz", freq_hz=np.array([f"{x:g}" for x in F_HZ])),
    _mapkey("freq-complex", "freq_hz", freq_hz=F_HZ + 1j),
    _mapkey("points-float", "points", "3.5", points=np.r_[3.5, np.arange(2.0, 85.0)]),
    _mapkey("points-strings", "points", points=np.array([str(i) for i in range(1, 85)])),
    _mapkey("masked-float", "masked", masked=np.linspace(0, 1, F_HZ.size)),
    _mapkey("excitations-numbers", "excitations", excitations=np.arange(5)),
    _mapkey("excitations-2d", "excitations", excitations=np.array([EXCITATIONS] * 2)),
    _mapkey("frf-2d", "frf_um_per_v", "shape", frf_um_per_v=np.ones((5, 84), complex)),
    _mapkey(
        "frf-points-mismatch", "frf_um_per_v", "shape", frf_um_per_v=np.ones((5, 80, 27), complex)
    ),
    _mapkey("freq-2d", "freq_hz", freq_hz=np.ones((27, 2))),
    _mapkey("points_mm-3cols", "points_mm", points_mm=np.zeros((84, 3))),
    _mapkey("masked-length", "masked", masked=np.zeros(5, bool)),
    _map(
        "frf-nan",
        lambda d, g: changed(
            g["map"], d / "m.npz", frf_um_per_v=_frf(g, lambda a: a.__setitem__((1, 5, 9), np.nan))
        ),
        "NaN",
        "PB",
    ),
    _mapkey("freq-inf", "freq_hz", freq_hz=np.r_[F_HZ[:-1], np.inf]),
    _map(
        "frf-1e300",
        lambda d, g: changed(
            g["map"], d / "m.npz", frf_um_per_v=_frf(g, lambda a: a.__setitem__((2, 7, 4), 1e300))
        ),
        "frf_um_per_v",
        "1e+300",
    ),
    _map(
        "frf-1e7",
        lambda d, g: changed(
            g["map"], d / "m.npz", frf_um_per_v=_frf(g, lambda a: a.__setitem__((0, 0, 3), 1e7j))
        ),
        "frf_um_per_v",
        "1e+07",
    ),
    _mapkey("points_mm-1e300", "points_mm", points_mm=np.r_[[[1e300, 0.0]], np.zeros((83, 2)) + 5]),
    _mapkey("freq-1e300", "freq_hz", "1e+300", freq_hz=np.r_[F_HZ[:-1], 1e300]),
    _mapkey("points-duplicate", "points", "duplicate", points=np.r_[1, np.arange(1, 84)]),
    _mapkey("points-zero", "points", "0", points=np.arange(0, 84)),
    # point ids are the measurement's node numbers (2..85 is a valid map); 0 is none
    _mapkey("points-0", "points", "0", points=np.arange(0, 84)),
    _mapkey("points-negative", "points", "-3", points=np.r_[-3, np.arange(2, 85)]),
    _mapkey("points-int-overflow", "points", points=np.r_[2**40, np.arange(2, 85)]),
    _mapkey("freq-negative", "freq_hz", "negative", freq_hz=F_HZ - 10),
    _mapkey("freq-unsorted", "freq_hz", freq_hz=F_HZ[[1, 0, *range(2, 27)]]),
    _mapkey("freq-duplicate", "freq_hz", freq_hz=np.r_[0.0, F_HZ[1:-1], F_HZ[-2]]),
    _mapkey("freq-one-bin", "freq_hz", freq_hz=np.array([25.0])),
    _mapkey(
        "excitation-unknown", "excitations", "PX", excitations=np.array([*EXCITATIONS[:4], "PX"])
    ),
    _mapkey(
        "no-points",
        "points",
        frf_um_per_v=np.ones((5, 0, 27), complex),
        points=np.zeros(0, np.int64),
        points_mm=np.zeros((0, 2)),
    ),
    _meta("meta-bad-json", "{not json", "JSON"),
    _meta("meta-deep-nesting", "[" * 100_000 + "]" * 100_000, "nest"),
    _meta("meta-deep-50", '{"format": ' + "[" * 50 + "]" * 50 + "}", "nest"),
    _meta("meta-list", "[1, 2]", "object"),
    _meta("meta-no-format", lambda m: m.pop("format"), "format"),
    _meta("meta-no-version", lambda m: m.pop("version"), "version"),
    _meta("meta-version-text", lambda m: m.update(version="abc"), "version"),
    _meta("meta-version-float", lambda m: m.update(version=1.5), "version"),
    _meta("meta-version-2", lambda m: m.update(version=2), "version"),
    _meta("meta-format-other", lambda m: m.update(format="something-else"), "format"),
    _meta("meta-no-units", lambda m: m.pop("units"), "units"),
    _meta("meta-units-wrong", lambda m: m["units"].update(frf="m/V"), "units.frf"),
    _meta("meta-units-list", lambda m: m.update(units=["um/V"]), "units"),
    _meta("meta-provenance-list", lambda m: m.update(provenance=[1]), "provenance"),
    _meta("meta-gain-text", lambda m: m["provenance"].update(gain="fifty"), "gain"),
    _mapkey("meta-not-string", "meta_json", meta_json=np.arange(3)),
    _map(
        "build-from-bad-map",
        lambda d, g: changed(g["map"], d / "m.npz", freq_hz=np.array([f"{x:g}" for x in F_HZ])),
        "freq_hz",
        cmd=("tables", "build", "--out", "/dev/null/never"),
    ),
    _map(
        "export-bad-map",
        lambda d, g: changed(g["map"], d / "m.npz", points=np.arange(0, 84)),
        "points",
        cmd=("frf", "export", "--out", "/dev/null/never"),
    ),
]


def _tab(name, *words, drop=(), cmd="flow", **new):
    def make(d, g):
        p = changed(g["tables"], d / "t.npz", drop, **new)
        if cmd == "flow":
            argv = ["flow", str(p), "--from", "51", "--to", "52"]
        else:
            argv = ["tables", "query", str(p), "--active", "51", "--passive", "52"]
        return argv, [str(p), *words]

    return Case(name, "tables", make)


def _tabf(name, fn, *words, cmd="flow"):
    """A tables case whose new arrays are computed from the good ones."""

    def make(d, g):
        data = arrays(g["tables"])
        fn(data)
        p = write_npz(d / "t.npz", data)
        argv = (
            ["flow", str(p), "--from", "51", "--to", "52"]
            if cmd == "flow"
            else ["tables", "query", str(p), "--active", "51", "--passive", "52"]
        )
        return argv, [str(p), *words]

    return Case(name, "tables", make)


def _set(key, idx, value):
    def fn(data):
        a = data[key].copy()
        a[idx] = value
        data[key] = a

    return fn


def _tab_raw(name, build, *words):
    def make(d, g):
        p = build(d, g)
        return ["flow", str(p), "--from", "51", "--to", "52"], [str(p), *words]

    return Case(name, "tables", make)


def _meta_tab(data):
    meta = json.loads(str(data["map_meta_json"]))
    del meta["units"]
    data["map_meta_json"] = np.array(json.dumps(meta))


TABLE_CASES = [
    _tab_raw("empty", lambda d, g: put(d / "e.npz", b""), "empty"),
    _tab_raw(
        "truncated",
        lambda d, g: put(d / "t.npz", g["tables"].read_bytes()[:-300]),
        "zip",
    ),
    _tab_raw(
        "declared-4gb",
        lambda d, g: lying_size(g["tables"], d / "lie.npz", 0xFFFF0000),
        "uncompressed",
    ),
    *[
        _tab(f"missing-{k}", k, drop=(k,))
        for k in ("map_meta_json", "freq_hz", "actuator", "band_hz", "map_hash", "map_points")
    ],
    _tab("missing-max_diff-query", "max_diff_um_per_v", drop=("max_diff_um_per_v",), cmd="query"),
    _tab("wrong-map-hash", "map_hash", map_hash=np.array("0" * 64)),
    _tab("map-hash-number", "map_hash", map_hash=np.array(5)),
    _tab("max_diff-shape", "max_diff_um_per_v", "shape", max_diff_um_per_v=np.zeros((84, 3))),
    _tab("tables-83-points", "max_diff_um_per_v", "84", max_diff_um_per_v=np.zeros((83, 83))),
    _tabf("max_diff-nan", _set("max_diff_um_per_v", (50, 51), np.nan), "max_diff_um_per_v"),
    _tabf("max_diff-1e300", _set("max_diff_um_per_v", (50, 51), 1e300), "max_diff_um_per_v"),
    _tabf(
        "max_diff-above-map",
        _set("max_diff_um_per_v", (50, 51), 3.0),
        "max_diff_um_per_v",
        cmd="query",
    ),
    _tabf("freq-outside-band", _set("freq_hz", (50, 51), 5000.0), "freq_hz", "5000"),
    _tabf("freq-not-a-bin", _set("freq_hz", (50, 51), 333.0), "freq_hz", "333"),
    _tabf("freq-nan", _set("freq_hz", (50, 51), np.nan), "freq_hz"),
    _tabf("freq-negative", _set("freq_hz", (50, 51), -25.0), "freq_hz"),
    _tabf("freq-masked-bin", _set("freq_hz", (50, 51), 0.0), "freq_hz"),
    _tab("band-above-nyquist", "band_hz", "Nyquist", band_hz=np.array(1e5)),
    _tab("band-nan", "band_hz", band_hz=np.array(np.nan)),
    _tab("band-negative", "band_hz", band_hz=np.array(-5.0)),
    _tab("band-string", "band_hz", band_hz=np.array("650")),
    _tab("band-array", "band_hz", band_hz=np.array([650.0, 1.0])),
    _tab("contrast-nan", "min_contrast_db", min_contrast_db=np.array(np.nan)),
    _tab("contrast-negative", "min_contrast_db", min_contrast_db=np.array(-3.0)),
    _tabf("actuator-7", _set("actuator", (50, 51), 7), "actuator", "7"),
    _tabf("actuator-minus1", _set("actuator", (50, 51), -1), "actuator", "-1"),
    _tab("actuator-float", "actuator", actuator=np.zeros((84, 84))),
    _tab("actuator-shape", "actuator", actuator=np.zeros((84,), np.int8)),
    _tab("extra-key", "notes", notes=np.array("hi")),
    _tab("object-array", "actuator", "pickle", actuator=np.array([None, {}], dtype=object)),
    _tab("map-freq-unsorted", "map_freq_hz", map_freq_hz=F_HZ[::-1].copy()),
    _tab("map-meta-bad-json", "map_meta_json", map_meta_json=np.array("{")),
    _tabf("map-meta-no-units", _meta_tab, "units"),
    _tab("map-points-zero", "map_points", map_points=np.arange(0, 84)),
    _tab_raw(
        "a-map-not-tables",
        lambda d, g: changed(g["map"], d / "m.npz", points=np.arange(0, 84)),
        "points",
    ),
]


def _uff(name, build, *words, extra=()):
    """A UFF case; with ``extra`` arguments the line names the argument, not the file."""

    def make(d, g):
        p = build(d)
        argv = ["frf", "import", f"PA={p}", "--allow-missing", "--out", str(d / "o.npz"), *extra]
        return argv, [*words] if extra else [str(p), *words]

    return Case(name, "uff", make)


def _trunc(frac):
    def build(d):
        p = uff58(d / "a.uff")
        text = p.read_text()
        p.write_text(text[: int(len(text) * frac)])
        return p

    return build


def _trunc_b(nbytes):
    def build(d):
        p = uff58(d / "b.uff", binary=True)
        p.write_bytes(p.read_bytes()[:-nbytes])
        return p

    return build


def _nan_uff(token):
    """pyuff writes NaN as 0: put the token in the text as an exporter would."""

    def build(d):
        p = uff58(d / "a.uff")
        return uff_text_edit(p, "  4.00000e+01   5.00000000000e-05", f"  4.00000e+01   {token:>17}")

    return build


UFF_CASES = [
    _uff("empty", lambda d: put(d / "a.uff", ""), "UFF"),
    _uff("text", lambda d: put(d / "a.uff", "hello world\n" * 5), "UFF"),
    _uff("binary-garbage", lambda d: put(d / "a.uff", bytes(range(256)) * 8), "UFF"),
    _uff("missing", lambda d: d / "nope.uff", "no such"),
    _uff("directory", lambda d: (d / "dir.uff").mkdir() or d / "dir.uff", "UFF"),
    _uff("truncated-90", _trunc(0.9), "dataset"),
    _uff("truncated-50", _trunc(0.5), "dataset"),
    _uff("truncated-header", _trunc(0.05), "UFF"),
    _uff("58b-truncated", _trunc_b(40), "UFF"),
    _uff("58b-truncated-more", _trunc_b(300), "UFF"),
    _uff("nan", _nan_uff("nan"), "NaN"),
    _uff("inf", _nan_uff("-inf"), "inf"),
    _uff("huge-frf", lambda d: uff58(d / "a.uff", data=np.full(11, 1e290, complex)), "node 1"),
    _uff(
        "wrong-length",
        lambda d: uff_text_edit(uff58(d / "a.uff"), "        11         0", "        14         0"),
        "dataset",
    ),
    _uff(
        "fewer-points-declared",
        lambda d: uff_text_edit(uff58(d / "a.uff"), "        11         0", "         3         0"),
        "dataset",
    ),
    _uff(
        "node-not-a-number",
        lambda d: uff_text_edit(uff58(d / "a.uff"), "pt         1   3", "pt         x   3"),
        "node 0",
    ),
    _uff("unknown-node-500", lambda d: uff58(d / "a.uff", nodes=(1, 500)), "500"),
    _uff("node-0", lambda d: uff58(d / "a.uff", nodes=(0, 1)), "node 0"),
    _uff("node-duplicate", lambda d: uff58(d / "a.uff", nodes=(1, 1)), "node 1"),
    _uff(
        "real-ordinate", lambda d: uff58(d / "a.uff", data=np.ones(11), ord_data_type=4), "complex"
    ),
    _uff("ordinate-kind-3", lambda d: uff58(d / "a.uff", kind=3), "ordinate"),
    _uff("not-frf", lambda d: uff58(d / "a.uff", func_type=1), "func_type"),
    _uff("negative-freq", lambda d: uff58(d / "a.uff", f=np.arange(-20.0, 81.0, 10.0)), "negative"),
    _uff("gain-nan", lambda d: uff58(d / "a.uff"), "--gain", "nan", extra=("--gain", "nan")),
    _uff("gain-zero", lambda d: uff58(d / "a.uff"), "--gain", extra=("--gain", "0")),
    _uff(
        "mask-nan",
        lambda d: uff58(d / "a.uff"),
        "--mask-below-hz",
        extra=("--mask-below-hz", "nan"),
    ),
]


def _args(name, argv_tail, *words, cmd="query"):
    def make(d, g):
        if cmd == "query":
            argv = ["tables", "query", str(g["tables"]), *argv_tail]
        elif cmd == "flow":
            argv = ["flow", str(g["tables"]), *argv_tail]
        elif cmd == "point":
            argv = ["point", str(g["tables"]), *argv_tail]
        else:
            argv = ["tables", "build", str(g["map"]), "--out", str(d / "t.npz"), *argv_tail]
        return argv, list(words)

    return Case(name, "args", make)


ARG_CASES = [
    _args("active-1e300", ["--active", "1e300", "--passive", "52"], "1e300"),
    _args("active-3.5", ["--active", "3.5", "--passive", "52"], "3.5"),
    _args("active-0", ["--active", "0", "--passive", "52"], "0"),
    _args("active-85", ["--active", "85", "--passive", "52"], "85"),
    _args("active-minus5", ["--active", "-5", "--passive", "52"], "-5"),
    _args("active-empty", ["--active", "", "--passive", "52"], "point"),
    _args("active-nan-xy", ["--active", "nan,nan", "--passive", "52"], "nan"),
    _args("active-inf-xy", ["--active", "inf,100", "--passive", "52"], "inf"),
    _args("active-1e300-xy", ["--active", "1e300,1e300", "--passive", "52"], "1e+300"),
    _args("active-outside", ["--active", "5000,3", "--passive", "52"], "5000"),
    _args("active-3-coords", ["--active", "1,2,3", "--passive", "52"], "1,2,3"),
    _args("flow-to-nan", ["--from", "51", "--to", "nan,100"], "nan", cmd="flow"),
    _args(
        "flow-ringdown-nan",
        ["--from", "51", "--to", "52", "--ringdown-k", "nan"],
        "nan",
        cmd="flow",
    ),
    _args("point-1e300", ["1e300"], "1e300", cmd="point"),
    _args("point-nan", ["nan,5"], "nan", cmd="point"),
    _args("build-band-nan", ["--band-hz", "nan"], "--band-hz", cmd="build"),
    _args("build-band-negative", ["--band-hz", "-5"], "--band-hz", cmd="build"),
    _args("build-band-1e300", ["--band-hz", "1e300"], "--band-hz", cmd="build"),
    _args("build-contrast-nan", ["--min-contrast-db", "nan"], "--min-contrast-db", cmd="build"),
]

CASES = MAP_CASES + TABLE_CASES + UFF_CASES + ARG_CASES


def run_case(case: Case, d: Path, g: dict, capsys, monkeypatch) -> tuple[int, str, list[str]]:
    """Run one case; returns (exit code, stderr, the words the line must hold)."""
    import console.files.npz_safe as npz_safe

    monkeypatch.setenv("HAPTABLE_CACHE_DIR", str(d / "cache"))
    monkeypatch.setattr(npz_safe, "MAX_TOTAL_BYTES", 8 * 2**20, raising=False)
    argv, words = case.make(d, g)
    capsys.readouterr()
    rc = main(argv)
    return rc, capsys.readouterr().err, words


@pytest.mark.parametrize("case", CASES, ids=[f"{c.kind}-{c.id}" for c in CASES])
def test_malformed_input_one_line(case, good, tmp_path, capsys, monkeypatch):
    rc, err, words = run_case(case, tmp_path, good, capsys, monkeypatch)
    lines = err.strip().splitlines()
    assert rc == 2, f"exit {rc}: {err!r}"
    assert len(lines) == 1, err
    assert lines[0].startswith("haptable: error: ")
    for w in words:
        assert w in lines[0], f"{w!r} not in {lines[0]!r}"


def test_tables_with_another_maps_hash_refused_with_that_map(good, tmp_path):
    """The flow effect given a map AND a tables file: tables built from another map are
    refused (its stimuli would pair one plate's frequencies with another's amplitudes)."""
    from console.config.plugins import load_plugins
    from console.config.profile import load_profile
    from console.core.errors import UserError
    from console.files.vibration_map import save_map
    from plugins.vibrotactile.analytic_plate import SSPlate, analytic_map

    other = save_map(tmp_path / "other.npz", analytic_map(SSPlate(zeta=0.02), freq_hz=F_HZ))
    pm = load_plugins()
    eff = pm.get("effect", "flow").factory(load_profile("sim", pm))
    eff.render(51, 52, vmap=good["map"], tables=good["tables"])  # the same map: fine
    with pytest.raises(UserError) as e:
        eff.render(51, 52, vmap=other, tables=good["tables"])
    msg = str(e.value)
    assert "\n" not in msg and str(good["tables"]) in msg and "map_hash" in msg
    assert str(other) in msg


def test_console_vibration_screen_loads_refuse_with_one_line(good, tmp_path):
    """The Vibration screen's ``load`` and ``import`` raise only ``UserError`` (a worker
    that raised anything else would stop the console)."""
    from console.config.plugins import load_plugins
    from console.config.profile import load_profile
    from console.core.errors import UserError
    from console.session import vibration as vs

    pm = load_plugins()
    prof = load_profile("sim", pm)
    bad_map = changed(good["map"], tmp_path / "m.npz", points=np.arange(0.5, 84))
    with pytest.raises(UserError, match="points"):
        vs.load_map(bad_map)
    empty = tmp_path / "a.uff"
    empty.write_text("")
    with pytest.raises(UserError, match="a.uff"):
        vs.import_uff_files(prof, pm, [f"PA={empty}"])
    bomb = lying_size(good["map"], tmp_path / "lie.npz", 0xFFFF0000)
    with pytest.raises(UserError, match="uncompressed"):
        vs.load_map(bomb)


def test_damaged_tables_cache_entry_is_rebuilt_not_used(good, tmp_path):
    """A cache entry that is a valid archive with wrong content (another size of table,
    an empty file) is rebuilt, never used nor a crash."""
    from console.files.vibration_map import load_map
    from plugins.vibrotactile.lazy import tables_cached
    from plugins.vibrotactile.tables import build_tables

    m = load_map(good["map"])
    ref = build_tables(m, 650.0)
    tables_cached(m, 650.0, tmp_path)
    (entry,) = tmp_path.glob("tables-*.npz")
    write_npz(entry, {"max_diff_um_per_v": np.zeros((3, 3)), "freq_hz": np.zeros((3, 3))})
    t = tables_cached(m, 650.0, tmp_path)
    assert np.array_equal(t.actuator, ref.actuator)
    entry.write_bytes(b"")
    t = tables_cached(m, 650.0, tmp_path)
    assert np.array_equal(t.freq_hz, ref.freq_hz, equal_nan=True)


def test_read_npz_checks_size_before_reading(tmp_path):
    """The shared reader: the bound is a parameter; within it the arrays come back."""
    from console.core.errors import UserError
    from console.files.npz_safe import read_npz

    p = write_npz(tmp_path / "a.npz", {"x": np.zeros(1000), "s": np.array("text")})
    got = read_npz(p, what="test file", fix="fix it")
    assert np.array_equal(got["x"], np.zeros(1000)) and str(got["s"]) == "text"
    with pytest.raises(UserError, match=r"a\.npz: the archive declares .* above the 4,000"):
        read_npz(p, what="test file", fix="fix it", max_bytes=4000)
