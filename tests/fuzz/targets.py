"""Fuzz targets of the recording reader and the command line, shared by the atheris drivers
(``reader.py``, ``cli.py``) and the short hypothesis run of the test suite
(``tests/test_fuzz_targets.py``).

An input is bytes: byte 0 picks the file kind (:data:`KINDS`: an extension, and whether the
rest is written as it is or wrapped first: compressed, zipped, or split into the ``.npy``
members of an npz), byte 1 options (bit 0: pass ``dt = 1 ms``), the rest is the file's content.
The property: the reader returns a valid :class:`~algid.recording.Recording` or raises one
:class:`~algid.recording.RecordingError` with a one-line message; the command line returns 0,
2 or 3 and every exit 2 ends in one line of at most 200 characters; nothing else, ever.
"""

from __future__ import annotations

import bz2
import contextlib
import gzip
import io
import lzma
import os
import sys
import tempfile
import warnings
import zipfile
from pathlib import Path

import numpy as np

from algid.messages import MAX_LINE
from algid.recording import DT_RANGE_S, MIN_SAMPLES, Recording, RecordingError, load_recording

#: Separates the members of an npz input: ``name \0 npy-bytes`` parts joined by it.
NPZ_SPLIT = b"\n--\n"
#: Longest message a reader may raise, whatever the input (a few names quoted to 80
#: characters each; the command line shortens it to 200).
MAX_MESSAGE = 1000
#: How long a harness started without ``-runs`` or ``-max_total_time`` fuzzes [s].
DEFAULT_SECONDS = 120


def _zip_one(content: bytes) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        z.writestr("rec.csv", content)
    return buf.getvalue()


def _npz(content: bytes) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        for part in content.split(NPZ_SPLIT):
            name, _, npy = part.partition(b"\0")
            z.writestr(name.decode("latin-1") + ".npy", npy)
    return buf.getvalue()


#: (extension, wrap): the file kinds an input's first byte picks.
KINDS = (
    (".csv", None),
    (".tsv", None),
    (".txt", None),
    (".csv.gz", None),
    (".csv.gz", gzip.compress),
    (".csv.bz2", None),
    (".csv.bz2", bz2.compress),
    (".csv.xz", None),
    (".csv.xz", lzma.compress),
    (".csv.zip", None),
    (".csv.zip", _zip_one),
    (".npz", None),
    (".npz", _npz),
    (".h5", None),
    (".uff", None),
)


def skipped(data: bytes) -> bool:
    """Whether the input is an HDF5 file and ``ALGID_FUZZ_HDF5=0``: libhdf5's own allocation and
    loop on damaged attributes (docs/reliability.md, finding 8) would end every short run."""
    return os.environ.get("ALGID_FUZZ_HDF5") == "0" and KINDS[data[0] % len(KINDS) if data else 0][0] == ".h5"


def file_of(data: bytes, folder: Path) -> tuple[Path, float | None]:
    """The file an input describes, written into ``folder``, and the ``dt`` to pass."""
    kind = data[0] % len(KINDS) if data else 0
    flags = data[1] if len(data) > 1 else 0
    suffix, wrap = KINDS[kind]
    content = data[2:]
    path = folder / f"rec{suffix}"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # zipfile warns of a member named twice: the reader's case
        path.write_bytes(wrap(content) if wrap else content)
    return path, (1e-3 if flags & 1 else None)


def check_recording(rec: Recording) -> None:
    """What a recording the reader returns must satisfy."""
    T, n = rec.u.shape
    assert rec.t.shape == (T,) and T >= MIN_SAMPLES and n >= 1
    assert DT_RANGE_S[0] <= rec.dt <= DT_RANGE_S[1]
    assert np.all(np.diff(rec.t) > 0)
    for arr in (rec.u, rec.a, rec.v, rec.x):
        assert arr is None or (arr.shape == (T, n) and arr.dtype == np.float64 and np.isfinite(arr).all())


def check_message(err: BaseException) -> None:
    """A reader's error: one line, bounded."""
    text = str(err)
    assert "\n" not in text and 0 < len(text) <= MAX_MESSAGE, repr(text[:300])


def reader(data: bytes, folder: Path) -> Recording | None:
    """The reader's property on one input; any other exception escapes."""
    if skipped(data):
        return None
    path, dt = file_of(data, folder)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # h5py, pyuff and numpy warn on odd files; not the property
            rec = load_recording(path, dt=dt)
    except RecordingError as err:
        check_message(err)
        return None
    check_recording(rec)
    return rec


def command(data: bytes, folder: Path, name: str) -> int:
    """``algid NAME FILE --quiet`` in this process on the file ``data`` describes; an
    exception the command does not turn into its exit code escapes (``algid.cli.main``
    would hide it behind its catch-all, so the subcommand is called directly)."""
    from algid.cli import build_parser

    if skipped(data):
        return 0
    path, dt = file_of(data, folder)
    argv = [name, str(path), "--quiet"] + (["--dt", "0.001"] if dt else [])
    args = build_parser().parse_args(argv)
    err = io.StringIO()
    with warnings.catch_warnings(), contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        code = int(args.func(args) or 0)
    lines = err.getvalue().splitlines()
    assert code in (0, 2, 3), (code, lines)
    if code == 2:
        assert len(lines) == 1 and len(lines[0]) <= MAX_LINE, lines
    return code


# ---- seeds: small valid files of every kind, the corpus the fuzzers start from ----------------
def _signals(T: int = 256, n: int = 2) -> dict[str, np.ndarray]:
    """A small recording: a 1-DOF-per-column oscillation, enough to pass every check."""
    t = np.arange(T) * 1e-3
    cols = {"t": t}
    for i in range(1, n + 1):
        cols[f"u{i}"] = np.sin(2 * np.pi * 7 * i * t)
        cols[f"a{i}"] = np.cos(2 * np.pi * 5 * i * t) * i
    return cols


def _csv(cols: dict[str, np.ndarray], sep: str = ",", decimal: str = ".") -> bytes:
    lines = [sep.join(cols)]
    for row in zip(*cols.values()):
        lines.append(sep.join(f"{v:.6g}".replace(".", decimal) for v in row))
    return ("\n".join(lines) + "\n").encode()


def _npy(arr: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.save(buf, arr)
    return buf.getvalue()


def _h5(cols: dict[str, np.ndarray]) -> bytes:
    import h5py

    buf = io.BytesIO()
    with h5py.File(buf, "w") as f:
        for name, arr in cols.items():
            f[name] = arr
            f[name].attrs["units"] = "s" if name == "t" else ("N" if name[0] == "u" else "m/s^2")
    return buf.getvalue()


def _uff(cols: dict[str, np.ndarray]) -> bytes:
    import pyuff

    dt = float(cols["t"][1] - cols["t"][0])
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "rec.uff"
        uff = pyuff.UFF(str(path))
        for name, arr in cols.items():
            if name == "t":
                continue
            kind = 13 if name[0] == "u" else 12
            data = pyuff.prepare_58(
                func_type=1, rsp_node=int(name[1:]), rsp_dir=1, ref_node=1, ref_dir=1, id1=name,
                ordinate_spec_data_type=kind, data=arr, x=cols["t"], abscissa_min=0.0, abscissa_inc=dt,
                abscissa_spacing=1, num_pts=arr.size, abscissa_axis_units_lab="s", return_full_dict=True,
            )  # fmt: skip
            data = {key: (0 if value is None else value) for key, value in data.items()}
            uff.write_sets(data, mode="add")
        return path.read_bytes()


def seeds() -> list[bytes]:
    """One input per file kind, each a valid small recording (as the harness encodes it)."""
    cols = _signals()
    csv = _csv(cols)
    kind = {k: i for i, k in enumerate(KINDS)}
    members = NPZ_SPLIT.join(name.encode() + b"\0" + _npy(arr) for name, arr in cols.items())
    content = {
        (".csv", None): csv,
        (".tsv", None): _csv(cols, "\t", ","),
        (".txt", None): _csv(cols, " "),
        (".csv.gz", None): gzip.compress(csv),
        (".csv.gz", gzip.compress): csv,
        (".csv.bz2", None): bz2.compress(csv),
        (".csv.bz2", bz2.compress): csv,
        (".csv.xz", None): lzma.compress(csv),
        (".csv.xz", lzma.compress): csv,
        (".csv.zip", None): _zip_one(csv),
        (".csv.zip", _zip_one): csv,
        (".npz", None): _npz(members),
        (".npz", _npz): members,
        (".h5", None): _h5(cols),
        (".uff", None): _uff(cols),
    }
    return [bytes([kind[k], 0]) + body for k, body in content.items()]


def write_corpus(folder: Path) -> Path:
    """The seeds as files of a libFuzzer corpus folder (created when missing)."""
    folder.mkdir(parents=True, exist_ok=True)
    for i, data in enumerate(seeds()):
        (folder / f"seed{i:02d}").write_bytes(data)
    return folder


def fuzz(name: str, one_input, timeout: int) -> None:
    """Run atheris (libFuzzer's engine) on ``one_input(data, folder)`` with libFuzzer's command
    line (``-max_total_time=3600``, ``-runs=N``, ...). Without ``-runs`` or ``-max_total_time``
    the run stops after :data:`DEFAULT_SECONDS` (libFuzzer's own default is to run until a
    finding); without ``-timeout`` an input that runs longer than ``timeout`` seconds is a
    finding (libFuzzer's own default is 1200 s, and the time limit is only checked between
    inputs, so one hanging input would hold the run that long). Without a corpus folder on the
    command line the seeds go to ``build/fuzz/NAME`` and the fuzzer grows that corpus; findings
    are written to ``build/fuzz/NAME-crash-*`` (``NAME-timeout-*`` for a hang)."""
    import atheris

    argv = list(sys.argv)
    argv[0] = f"{sys.executable} {Path(argv[0]).resolve()}"  # what -fork=N runs its jobs with
    if not any(a.startswith(("-runs=", "-max_total_time=")) for a in argv[1:]):
        argv.insert(1, f"-max_total_time={DEFAULT_SECONDS}")
    if not any(a.startswith("-timeout=") for a in argv[1:]):
        argv.insert(1, f"-timeout={timeout}")
    out = Path(__file__).resolve().parents[2] / "build" / "fuzz"
    if not any(not a.startswith("-") for a in argv[1:]):
        argv.append(str(write_corpus(out / name)))
    if not any(a.startswith("-artifact_prefix=") for a in argv):
        argv.insert(1, f"-artifact_prefix={out / name}-")
    folder = Path(tempfile.mkdtemp(prefix=f"algid-fuzz-{name}-"))
    atheris.Setup(argv, lambda data: one_input(data, folder))
    atheris.Fuzz()
