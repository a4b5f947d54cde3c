"""Hostile and malformed input on the command line: every failure is one short line on
stderr and exit code 2, never a traceback, and small inputs cannot ask for huge resources."""

from __future__ import annotations

import io
import subprocess
import sys
import zipfile

import numpy as np
import pytest

from algid.messages import MAX_LINE
from algid.recording import RecordingError, load_recording


def _algid(*args, timeout=120):
    return subprocess.run(
        [sys.executable, "-m", "algid.cli", *map(str, args)], capture_output=True, text=True, timeout=timeout
    )


def _one_line_exit_2(proc, needle: str = "") -> str:
    assert proc.returncode == 2, (proc.returncode, proc.stderr[-2000:])
    assert "Traceback" not in proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, proc.stderr[-2000:]
    assert len(lines[0]) <= MAX_LINE, len(lines[0])
    assert needle.lower() in lines[0].lower(), lines[0]
    return lines[0]


def _good_columns(T=400, n=1, dt=1e-3, seed=0):
    rng = np.random.default_rng(seed)
    cols = {"t": dt * np.arange(T)}
    for i in range(1, n + 1):
        cols[f"u{i}"] = rng.standard_normal(T)
        cols[f"a{i}"] = rng.standard_normal(T)
    return cols


@pytest.mark.parametrize("command", ["identify", "diagnose"])
def test_huge_column_index_is_refused_before_allocation(tmp_path, command):
    path = tmp_path / "r.csv"
    path.write_text("t,u1,a1,u10000000,a10000000\n0,1,2,3,4\n")
    line = _one_line_exit_2(_algid(command, path, "--json", tmp_path / "o.json"), "beyond")
    assert "u10000000" in line


def test_a_huge_header_is_quoted_short(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text("t,u1,a1,a" + "1" * 2_000_000 + "\n0,1,2,3\n")
    _one_line_exit_2(_algid("identify", path, "--json", tmp_path / "o.json"), "beyond")
    rows = "".join(f"{k}e-3,1,2,3\n" for k in range(20))
    path.write_text("t,u1,a1," + "x" * 2_000_000 + "\n" + rows)  # ignored, and named short in the note
    note = load_recording(path).notes[0]
    assert note.startswith("ignored column 'xxx") and len(note) < MAX_LINE


def test_digit_separators_are_not_numbers(tmp_path):
    rows = "".join(f"{k}e-3,1_000,2\n" for k in range(20))
    with pytest.raises(RecordingError, match="cannot parse '1_000'"):
        load_recording(_write(tmp_path, "t,u1,a1\n" + rows))


def _write(tmp_path, text, name="r.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def _npz_bytes(cols) -> bytes:
    buf = io.BytesIO()
    np.savez(buf, **cols)
    return buf.getvalue()


@pytest.mark.parametrize(
    "make,needle",
    [
        (lambda: _npz_bytes(_good_columns())[:-200], "not a readable .npz"),  # truncated
        (lambda: b"PK\x03\x04" + b"\x00" * 300, "not a readable .npz"),  # zip magic, garbage
        (lambda: np.lib.format.magic(1, 0) + b"\x00" * 100, "not a readable .npz"),  # an .npy renamed
        (lambda: _npz_bytes(_good_columns() | {"a1": np.ones((400, 2))}), "expected 1-D"),
        (lambda: _npz_bytes(_good_columns() | {"a1": np.ones(400, complex)}), "not real numeric"),
        (lambda: _npz_bytes(_good_columns() | {"a1": np.ones(400, bool)}), "not real numeric"),
    ],
)
def test_broken_npz_files(tmp_path, make, needle):
    path = tmp_path / "r.npz"
    path.write_bytes(make())
    _one_line_exit_2(_algid("identify", path, "--json", tmp_path / "o.json"), needle)


def test_npz_member_that_declares_more_than_it_holds(tmp_path):
    """A member header may claim 10^10 samples: refused from the header, nothing decompressed."""
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": "<f8", "fortran_order": False, "shape": (10**10,)})
    path = tmp_path / "r.npz"
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as z:
        for name in ("t", "u1", "a1"):
            z.writestr(f"{name}.npy", header.getvalue() + b"\x00" * 64)
    with pytest.raises(RecordingError, match="declares 80000000000 bytes"):
        load_recording(path)


@pytest.mark.parametrize("dt", [1e300, 5e-324, 1e-12])
def test_absurd_sampling_intervals(tmp_path, dt):
    cols = _good_columns()
    cols["t"] = dt * np.arange(cols["t"].size)
    path = tmp_path / "r.npz"
    np.savez(path, **cols)
    for command in ("identify", "diagnose"):
        _one_line_exit_2(_algid(command, path, "--json", tmp_path / "o.json"), "sampling interval")


def test_unexpected_errors_are_one_line_too(tmp_path, monkeypatch, capsys):
    """An error no reader anticipated (here a PermissionError, which root never gets from the
    file system) still ends in one line and exit 2."""
    import algid.cli
    import algid.diagnosis.cli

    def refuse(path, **options):
        raise PermissionError(13, "Permission denied", str(path))

    monkeypatch.setattr(algid.diagnosis.cli, "load_recording", refuse)
    monkeypatch.delenv("ALGID_DEBUG", raising=False)
    code = algid.cli.main(["diagnose", str(tmp_path / "r.npz"), "--json", str(tmp_path / "o.json")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and err[0].startswith("algid diagnose: error: Permission denied: "), err


def test_a_closed_pipe_ends_quietly(tmp_path):
    path = tmp_path / "r.npz"
    np.savez(path, **_good_columns(T=2000))
    cmd = f"{sys.executable} -m algid.cli identify {path} --json {tmp_path / 'o.json'} | head -c 1"
    proc = subprocess.run(["bash", "-o", "pipefail", "-c", cmd], capture_output=True, text=True, timeout=120)
    assert "Traceback" not in proc.stderr and "BrokenPipe" not in proc.stderr, proc.stderr[-2000:]


def test_successful_runs_print_no_numerical_warnings(tmp_path):
    path = tmp_path / "r.npz"
    np.savez(path, **_good_columns(T=2000))
    proc = _algid("diagnose", path, "--json", tmp_path / "o.json", "--quiet")
    assert "RuntimeWarning" not in proc.stderr, proc.stderr[-2000:]


@pytest.mark.parametrize("n", [3.7, 3.0, True, "3", None])
def test_the_number_of_dof_must_be_an_integer(n):
    import algid

    for cls in (algid.ChainEstimator, algid.ContinuousEstimator):
        with pytest.raises(TypeError, match="n must be an integer"):
            cls(n, 1e-3)


@pytest.mark.parametrize(
    "make",
    [
        lambda a: a.astype(complex),
        lambda a: a > 0,
        lambda a: np.ma.masked_array(a, mask=np.zeros_like(a, bool)),
        lambda a: a.astype(object),
    ],
)
def test_signals_must_be_real_numbers(make):
    import algid

    a = np.random.default_rng(0).standard_normal((50, 2))
    for est in (algid.ChainEstimator(2, 1e-3), algid.ContinuousEstimator(2, 1e-3)):
        with pytest.raises(TypeError, match="accel"):
            est.run(make(a), a)
        with pytest.raises(TypeError, match="accel"):
            est.update(make(a[0]), a[0])
    assert np.isfinite(algid.ChainEstimator(2, 1e-3).run(a.astype(np.int64), a)["mass"][:5]).sum() == 0


@pytest.mark.parametrize("kind", ["noise", "zeros"])
def test_diagnose_finds_no_system_in_noise_or_zeros(tmp_path, kind):
    """Independent noise in force and acceleration, or all zeros: the record carries no
    identifiable system; never 'explained within noise'."""
    rng = np.random.default_rng(0)
    T = 5000
    cols = {"t": 1e-3 * np.arange(T)}
    for i in (1, 2):
        cols[f"u{i}"] = rng.standard_normal(T) if kind == "noise" else np.zeros(T)
        cols[f"a{i}"] = rng.standard_normal(T) if kind == "noise" else np.zeros(T)
    path = tmp_path / "r.npz"
    np.savez(path, **cols)
    out = tmp_path / "o.json"
    proc = _algid("diagnose", path, "--json", out, "--quiet")
    assert proc.returncode == 0, proc.stderr
    import json

    d = json.loads(out.read_text())
    assert d["model"]["verdict"] == "no_force_response"
    assert d["effect"] != "none"
    assert "no identifiable system" in d["model"]["reasons"][0]
