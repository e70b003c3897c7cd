"""The signal library against a careless or unlucky user (issue 25): a bad entry is one
line and the others stay usable; the file is checked for kind and size before it is read;
a write never makes the library unreadable, keeps every entry, the file's mode and owner,
and goes through a symlink to its target."""

from __future__ import annotations

import os
import stat
import tomllib

import pytest

import console.config.signal_library_file as signal_file
from console.cli.main import main
from console.config.signal_library import add_signal, library_path, read_library, remove_signal
from console.core.errors import UserError

BIG = "1" * 400
OK = "sine(250 Hz, 20 V, 1 s) * ramp(10 ms)"
GOOD = f'[signals.good]\nexpr = "{OK}"\n\n'


def one_error(capsys) -> str:
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("haptable: error:") and "internal error" not in err
    return lines[0]


@pytest.fixture
def lib():
    path = library_path("sim")
    path.parent.mkdir(parents=True, exist_ok=True)
    return path


@pytest.mark.parametrize(
    ("entry", "says"),
    [
        (f'[signals.bad]\nexpr = "sine({BIG} Hz, 1 V, 1 s)"\n', "400 characters long"),
        (f'[signals.bad]\nexpr = "{OK} * 7000 dB"\n', "outside -200..200 dB"),
        (f'[signals.bad]\nexpr = "{"-" * 900}{OK}"\n', "900 signs in a row"),
        (f'[signals.bad]\nexpr = "noise(1 V, 1 s, seed={BIG})"\n', "400 characters long"),
        (f'[signals.bad]\nexpr = "{OK} * {BIG}"\n', "400 characters long"),
        ('[signals.bad]\nexpr = "sine(250 Hz, 1 V, 1 s) #\\u001b[2J"\n', "'\\x1b' at column"),
        ('[signals.bad]\nexpr = "sine(250 Hz, 1 V, 1 s)\\u0000"\n', "'\\x00'"),
        (f'[signals."tone\\n"]\nexpr = "{OK}"\n', "starting with a letter or digit"),
        ('[signals.bad]\nexpr = "silence(1 s)"\nnotes = [1, 2.5, nan, 1979-05-27T07:32:00Z]\n', "unknown key 'notes'"),
        ('[signals.bad]\nexpr = "silence(1 s)"\n[signals.bad.sub]\n"a b" = "\\u007f\\""\n', "unknown key 'sub'"),
    ],
)  # fmt: skip
def test_a_saved_bad_entry_breaks_nothing_else(capsys, lib, entry, says):
    lib.write_text(GOOD + entry)
    bad = tomllib.loads(entry)["signals"]
    assert main(["signals", "list"]) == 2
    out = capsys.readouterr()
    assert "good" in out.out and out.err.count("\n") == 1 and says in out.err
    assert "[signals." in out.err and "signals.toml" in out.err
    assert main(["signals", "show", "good"]) == 0
    capsys.readouterr()
    assert main(["signals", "add", "new", OK]) == 0
    kept = tomllib.loads(lib.read_text())["signals"]
    assert set(kept) == {"good", "new", *bad}
    assert repr({k: kept[k] for k in bad}) == repr(bad)  # as it was (nan too)
    (name,) = bad
    assert main(["signals", "show", name]) == 2
    assert says in one_error(capsys)
    assert main(["signals", "rm", name]) == 0
    assert main(["signals", "list"]) == 0


def _fifo(p):
    os.mkfifo(p)


def _zero(p):
    p.symlink_to("/dev/zero")


def _folder(p):
    p.mkdir()


def _huge(p):
    p.write_text(GOOD + ("# " + "x" * 1000 + "\n") * 2000)


def _loop(p):
    p.symlink_to(p)


def _not_utf8(p):
    p.write_bytes(GOOD.encode() + b'[signals.b]\nexpr = "silence(1 s) \xff"\n')


@pytest.mark.timeout(60, method="signal")
@pytest.mark.parametrize(
    ("make", "says"),
    [
        (_fifo, "a FIFO (named pipe), not a signal library"),
        (_zero, "a character device, not a signal library"),
        (_folder, "a folder, not a signal library"),
        (_huge, "too large for a signal library (at most 1.0 MB)"),
        (_loop, "a symlink loop"),
        (_not_utf8, "not UTF-8 text (byte 0xff on line 5)"),
    ],
)
def test_a_library_that_is_not_a_small_file_is_one_line_never_a_hang(capsys, lib, make, says):
    make(lib)
    before = os.lstat(lib)
    for argv in (["list"], ["add", "new", OK], ["show", "good"], ["rm", "good"]):
        assert main(["signals", *argv]) == 2, argv
        assert says in one_error(capsys)
    after = os.lstat(lib)
    assert (after.st_mode, after.st_size, after.st_mtime_ns) == (
        before.st_mode,
        before.st_size,
        before.st_mtime_ns,
    )


def test_names_match_the_pattern_in_full(capsys, lib):
    for bad in ("tone\n", "tone ", " tone", "tö", "a" * 41, "-a"):
        assert main(["signals", "add", "--", bad, OK]) == 2
        assert "starting with a letter or digit" in one_error(capsys)
    assert not lib.exists()


@pytest.mark.parametrize(
    ("expr", "says"),
    [
        ("sine(1e12 Hz, 20 V, 1 s) * ramp(10 ms)", "half the outputs' sample rate"),
        ("sine(250 Hz, 300 V, 1 s) * ramp(10 ms)", "[limits] piezo_min_v, piezo_max_v"),
        (f"{OK} * 100000", "[limits] max_plan_s"),
        ("sine(5 Hz, 50 %, 1 s)", "a ratio, not volts"),
    ],
)
def test_add_refuses_a_signal_that_can_never_play(capsys, lib, expr, says):
    assert main(["signals", "add", "x", expr]) == 2
    line = one_error(capsys)
    assert "can never play" in line and says in line and "nothing saved" in line
    assert not lib.exists()


def test_a_read_only_library_is_refused_and_kept(capsys, lib):
    lib.write_text(GOOD)
    lib.chmod(0o444)
    assert main(["signals", "add", "new", OK]) == 2
    assert "read-only (mode 0444)" in one_error(capsys)
    assert main(["signals", "rm", "good"]) == 2
    assert "chmod u+w" in one_error(capsys)
    assert lib.read_text() == GOOD and stat.S_IMODE(lib.stat().st_mode) == 0o444


def test_mode_and_owner_are_kept(lib):
    lib.write_text(GOOD)
    lib.chmod(0o640)
    add_signal(lib, "new", OK)
    assert stat.S_IMODE(lib.stat().st_mode) == 0o640
    if os.geteuid() == 0:  # only root can give a file away
        os.chown(lib, 1234, 1234)
        remove_signal(lib, "new")
        st = lib.stat()
        assert (st.st_uid, st.st_gid, stat.S_IMODE(st.st_mode)) == (1234, 1234, 0o640)
    assert set(read_library(lib).entries) >= {"good"}


def test_a_symlinked_library_is_written_through(lib, tmp_path):
    shared = tmp_path / "shared" / "signals.toml"
    shared.parent.mkdir()
    shared.write_text(GOOD)
    shared.chmod(0o664)
    lib.symlink_to(shared)
    add_signal(lib, "new", OK)
    assert lib.is_symlink() and os.readlink(lib) == str(shared)
    assert set(tomllib.loads(shared.read_text())["signals"]) == {"good", "new"}
    assert stat.S_IMODE(shared.stat().st_mode) == 0o664
    assert sorted(p.name for p in shared.parent.iterdir()) == ["signals.toml", "signals.toml.lock"]


def test_a_dangling_symlink_is_written_through_or_refused(lib, tmp_path):
    lib.symlink_to(tmp_path / "later.toml")
    add_signal(lib, "new", OK)  # its folder exists: the file it names is created
    assert (
        lib.is_symlink()
        and "new" in tomllib.loads((tmp_path / "later.toml").read_text())["signals"]
    )
    lib.unlink()
    lib.symlink_to(tmp_path / "nowhere" / "x.toml")
    with pytest.raises(UserError, match="whose folder does not exist; nothing was written"):
        add_signal(lib, "new", OK)
    assert lib.is_symlink() and not (tmp_path / "nowhere").exists()


@pytest.mark.timeout(60, method="signal")
@pytest.mark.parametrize(
    ("make", "says"),
    [
        (os.mkfifo, "a FIFO (named pipe), not a lock file"),
        (os.mkdir, "a folder, not a lock file"),
        (lambda p: os.symlink("/dev/null", p), "a symlink, not a lock file"),
    ],
)
def test_a_lock_file_that_is_not_a_file_is_one_line(capsys, lib, make, says):
    lib.write_text(GOOD)
    make(lib.with_name("signals.toml.lock"))
    assert main(["signals", "add", "new", OK]) == 2
    assert says in one_error(capsys)
    assert lib.read_text() == GOOD


def test_a_write_that_would_not_read_back_is_refused(lib, monkeypatch):
    lib.write_text(GOOD)
    monkeypatch.setattr(signal_file, "dump", lambda signals: '[signals.tone\n]\nexpr = "x"\n')
    with pytest.raises(UserError, match="would not read back after this change"):
        add_signal(lib, "new", OK)
    assert lib.read_text() == GOOD


def test_dump_round_trips_whatever_toml_holds():
    text = (
        '[signals.odd]\nexpr = "silence(1 s)"\n"key with space" = "tab\\there \\u007f \\"q\\" \\\\"\n'
        "n = -0.0\nbig = 1e300\ninf = -inf\nwhen = 1979-05-27\nat = 07:32:00.5\n"
        'list = [[1, 2], {a = true}]\n[signals."ünï"]\nexpr = "silence(1 s)"\n'
        "[signals.t]\nx = 1\n[signals.t.deeper.still]\ny = 2\n"
    )
    signals = tomllib.loads(text)["signals"]
    out = signal_file.dump(signals)
    assert tomllib.loads(out)["signals"] == signals
    assert signal_file._reads_back(out) is None


def test_api_refuses_what_argv_can_carry(lib):
    for kwargs, says in (
        ({"description": "caf\udce9"}, "one printable line"),
        ({"expr": f"{OK} #\udcff"}, "not a printable character"),
    ):
        args = {"name": "x", "expr": OK, **kwargs}
        with pytest.raises(UserError, match=says):
            add_signal(lib, args.pop("name"), args.pop("expr"), **args)
    assert not lib.exists()


def test_a_write_never_grows_the_library_beyond_what_reading_accepts(lib, monkeypatch):
    monkeypatch.setattr(signal_file, "MAX_ENTRIES", 3)
    for name in ("a", "b", "c"):
        add_signal(lib, name, OK)
    before = lib.read_text()
    with pytest.raises(UserError, match="would hold 4 signals, more than the 3"):
        add_signal(lib, "d", OK)
    add_signal(lib, "c", "silence(1 s)", replace=True)  # a replacement still fits
    lib.write_text(before + '\n[signals.d]\nexpr = "silence(1 s)"\n')
    with pytest.raises(UserError, match="4 signals, more than the 3 a library keeps"):
        read_library(lib)
    monkeypatch.setattr(signal_file, "MAX_ENTRIES", 1000)
    monkeypatch.setattr(signal_file, "MAX_LIBRARY_BYTES", len(lib.read_bytes()) + 10)
    with pytest.raises(UserError, match="would grow beyond"):
        add_signal(lib, "e", OK)
    assert "e" not in read_library(lib).entries
