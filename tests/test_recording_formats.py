"""Recordings as rigs write them: pandas exports with an index, ``time`` and units in the
header, semicolons and decimal commas, tabs, blanks, compressed files, extra columns, no
time column, column mappings, HDF5 and UFF 58, DataFrames; each read back to the exact
values written, and the hostile variants refused in one line."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

import algid.cli
from algid.model.chain import TABLE1
from algid.recording import Recording, RecordingError, load_recording, parameter_units, save_recording
from algid.recording.units import STANDARD_GRAVITY
from signals import multisine, simulate_chain

T, DT = 64, 1e-3


def _signals(n=2, seed=0):
    rng = np.random.default_rng(seed)
    t = 0.25 + DT * np.arange(T)
    return t, rng.standard_normal((T, n)), rng.standard_normal((T, n))


def _frame(t, u, a, time="time [s]", force="u{} [N]", accel="a{} (m/s^2)", extra=True):
    cols = {time: t}
    cols |= {force.format(i + 1): u[:, i] for i in range(u.shape[1])}
    cols |= {accel.format(i + 1): a[:, i] for i in range(a.shape[1])}
    if extra:
        cols["temperature [C]"] = np.full(t.size, 21.5)
    return pd.DataFrame(cols)


def _same(rec, t, u, a, exact=True):
    check = np.testing.assert_array_equal if exact else lambda x, y: np.testing.assert_allclose(x, y, rtol=1e-15)
    check(rec.t, t)
    check(rec.u, u)
    check(rec.a, a)


def test_pandas_export_with_index_time_and_units(tmp_path):
    t, u, a = _signals()
    path = tmp_path / "rig.csv"
    _frame(t, u, a).to_csv(path)  # pandas' default: the index as a first, unnamed column
    rec = load_recording(path)
    _same(rec, t, u, a)
    assert rec.n == 2 and rec.units == {"time": "s", "force": "N", "acceleration": "m/s^2"}
    assert rec.notes == ["ignored columns '' (index), 'temperature [C]'"]


@pytest.mark.parametrize(
    "name,sep,decimal",
    [("rig.csv", ";", ","), ("rig.tsv", "\t", "."), ("rig.txt", "\t", ","), ("rig.csv", "|", ".")],
)
def test_delimiters_and_decimal_commas(tmp_path, name, sep, decimal):
    t, u, a = _signals()
    path = tmp_path / name
    _frame(t, u, a, time="Time [s]", force="U{}", accel="A{}").to_csv(path, sep=sep, decimal=decimal, index=False)
    _same(load_recording(path), t, u, a)


def test_blank_separated_text_with_units_after_the_names(tmp_path):
    t, u, a = _signals(n=1)
    rows = "".join(f"{float(t[k])!r}   {float(u[k, 0])!r}  {float(a[k, 0])!r}\n" for k in range(T))
    path = tmp_path / "rig.txt"
    path.write_text("# exported by the rig\nt (s)   u1 [N]  a1 (m/s^2)\n" + rows)
    _same(load_recording(path), t, u, a)


@pytest.mark.parametrize("compression", [".gz", ".bz2", ".xz", ".zip"])
def test_compressed_files(tmp_path, compression):
    t, u, a = _signals()
    path = tmp_path / f"rig.csv{compression}"
    _frame(t, u, a).to_csv(path, index=False)
    rec = load_recording(path)
    _same(rec, t, u, a)
    assert rec.notes == ["ignored column 'temperature [C]'"]


def test_convertible_units_become_si_with_a_note(tmp_path):
    t, u, a = _signals(n=1)
    frame = pd.DataFrame({"t [ms]": t * 1e3, "u1 [kN]": u[:, 0], "a1 [g]": a[:, 0], "x1 [mm]": a[:, 0]})
    path = tmp_path / "rig.csv"
    frame.to_csv(path, index=False)
    rec = load_recording(path)
    np.testing.assert_allclose(rec.t, t, rtol=1e-15)
    np.testing.assert_array_equal(rec.u[:, 0], u[:, 0] * 1e3)
    np.testing.assert_array_equal(rec.a[:, 0], a[:, 0] * STANDARD_GRAVITY)
    np.testing.assert_array_equal(rec.x[:, 0], a[:, 0] * 1e-3)
    assert rec.is_si() and "acceleration g -> m/s^2 (x 9.80665)" in rec.notes
    assert "displacement mm -> m (x 0.001)" in rec.notes and "force kN -> N (x 1000)" in rec.notes


def test_units_that_are_not_si_are_labels_and_survive_a_round_trip(tmp_path):
    t, u, a = _signals(n=1)
    frame = pd.DataFrame({"t": t, "u1 [V]": u[:, 0], "x1 [V]": a[:, 0]})
    path = tmp_path / "silverbox_like.csv"
    frame.to_csv(path, index=False)
    rec = load_recording(path)
    np.testing.assert_array_equal(rec.x[:, 0], a[:, 0])
    assert rec.units == {"time": "s", "force": "V", "displacement": "V"} and not rec.is_si()
    assert parameter_units(rec) == {"m": "V s^2/V", "c": "V s/V", "k": "V/V"}
    for ext in (".csv", ".npz"):
        back = load_recording(save_recording(tmp_path / f"back{ext}", rec))
        assert back.units == rec.units
        np.testing.assert_array_equal(back.x, rec.x)
    assert (tmp_path / "back.csv").read_text().splitlines()[0] == "t [s],u1 [V],x1 [V]"
    assert rec.notes == ["no unit for t: SI assumed (s)"] and back.notes == []
    # the option overrides the header: a plain file labelled as volts
    plain = load_recording(save_recording(tmp_path / "plain.csv", Recording(t=t, u=u, x=a)), units={"force": "V"})
    assert parameter_units(plain) == {"m": "V s^2/m", "c": "V s/m", "k": "V/m"}


def test_parameter_units_follow_the_motion_measured():
    t, u, a = _signals(n=1)
    assert parameter_units(Recording(t=t, u=u, a=a)) == {"m": "kg", "c": "N s/m", "k": "N/m"}
    volts = Recording(t=t, u=u, a=a, units={"acceleration": "V"})
    assert parameter_units(volts) == {"m": "N/V", "c": "N/(V s)", "k": "N/(V s^2)"}
    counts = Recording(t=t, u=u, v=a, units={"force": "V", "velocity": "counts"})
    assert parameter_units(counts) == {"m": "V s/counts", "c": "V/counts", "k": "V/(counts s)"}


def test_column_mapping_and_no_time_column(tmp_path):
    t, u, a = _signals()
    frame = pd.DataFrame(
        {"F_shaker": u[:, 0], "F_2": u[:, 1], "acc_wing": a[:, 0], "acc_payload [g]": a[:, 1], "Comment": "ok"}
    )
    path = tmp_path / "rig.csv"
    frame.to_csv(path, index=False)
    columns = {"force": ["F_shaker", "F_2"], "a": ["acc_wing", "acc_payload"]}
    rec = load_recording(path, columns=columns, dt=DT)
    np.testing.assert_allclose(rec.t, DT * np.arange(T), rtol=0, atol=0)
    np.testing.assert_array_equal(rec.u, u)
    np.testing.assert_array_equal(rec.a[:, 0], a[:, 0])
    np.testing.assert_array_equal(rec.a[:, 1], a[:, 1] * STANDARD_GRAVITY)
    assert rec.notes[0] == "ignored column 'Comment'" and rec.notes[-1] == "no time column: t = k * 0.001 s"
    frame.insert(0, "Time", t)
    frame.to_csv(path, index=False)
    rec = load_recording(path, columns={"t": "Time", **columns})
    np.testing.assert_array_equal(rec.t, t)


def test_dataframes_in_and_out():
    t, u, a = _signals()
    rec = load_recording(_frame(t, u, a))
    _same(rec, t, u, a)
    indexed = Recording.from_frame(_frame(t, u, a, time="time").set_index("time"))
    _same(indexed, t, u, a)
    volts = Recording(t=t, u=u, a=a, units={"force": "V"})
    frame = volts.to_frame()
    assert list(frame.columns) == ["t", "u1", "u2", "a1", "a2"]
    back = Recording.from_frame(frame)
    _same(back, t, u, a)
    assert back.units == {"time": "s", "force": "V", "acceleration": "m/s^2"}


def test_hdf5_datasets_in_a_group(tmp_path):
    h5py = pytest.importorskip("h5py")
    t, u, a = _signals()
    path = tmp_path / "rig.h5"
    with h5py.File(path, "w") as fh:
        g = fh.create_group("run1")
        g["time"] = t
        g["u1"], g["u2"] = u[:, 0], u[:, 1]
        for i in range(2):
            g[f"a{i + 1}"] = a[:, i] / STANDARD_GRAVITY
            g[f"a{i + 1}"].attrs["units"] = "g"
        g["meta"] = np.arange(3)
        fh["other"] = np.zeros(5)
    rec = load_recording(path, group="run1")
    np.testing.assert_array_equal(rec.t, t)
    np.testing.assert_array_equal(rec.u, u)
    np.testing.assert_allclose(rec.a, a, rtol=1e-15)
    assert rec.notes[0] == "ignored column 'meta'"
    with pytest.raises(RecordingError, match="no group 'run2'"):
        load_recording(path, group="run2")
    with pytest.raises(RecordingError, match="rig.h5: missing force columns"):
        load_recording(path)  # the root holds a group and an unrelated dataset


def test_hostile_hdf5_and_uff_files(tmp_path):
    h5py = pytest.importorskip("h5py")
    pytest.importorskip("pyuff")
    for name, needle in (("r.h5", "r.h5: not a readable HDF5 file"), ("r.uff", "r.uff: no time responses")):
        (tmp_path / name).write_text("t,u1,a1\n0,1,2\n")
        with pytest.raises(RecordingError, match=needle):
            load_recording(tmp_path / name)
    t, u, a = _signals(n=1)
    with h5py.File(tmp_path / "r.h5", "w") as fh:
        fh["t"], fh["u1"], fh["a1"] = t, np.column_stack([u, u]), a[:-1, 0]
    with pytest.raises(RecordingError, match="array 'u1' has shape \\(64, 2\\), expected 1-D"):
        load_recording(tmp_path / "r.h5")


def _uff58(id1, node, data_type, unit, data, dt=DT):
    import pyuff

    zero = dict.fromkeys(
        [
            "abscissa_len_unit_exp",
            "abscissa_force_unit_exp",
            "abscissa_temp_unit_exp",
            "ordinate_len_unit_exp",
            "ordinate_force_unit_exp",
            "ordinate_temp_unit_exp",
            "orddenom_spec_data_type",
            "orddenom_len_unit_exp",
            "orddenom_force_unit_exp",
            "orddenom_temp_unit_exp",
            "z_axis_spec_data_type",
            "z_axis_len_unit_exp",
            "z_axis_force_unit_exp",
            "z_axis_temp_unit_exp",
        ],
        0,
    )
    return pyuff.prepare_58(
        func_type=1,
        id1=id1,
        rsp_node=node,
        rsp_dir=1,
        ref_node=node,
        ref_dir=1,
        ordinate_spec_data_type=data_type,
        ordinate_axis_units_lab=unit,
        abscissa_spec_data_type=17,
        abscissa_axis_units_lab="s",
        orddenom_axis_units_lab="",
        z_axis_axis_units_lab="",
        z_axis_value=0.0,
        abscissa_spacing=1,
        abscissa_min=0.0,
        abscissa_inc=dt,
        num_pts=data.size,
        data=data,
        x=dt * np.arange(data.size),
        **zero,
    )


def test_uff58_time_responses(tmp_path):
    pyuff = pytest.importorskip("pyuff")
    rng = np.random.default_rng(3)
    # values with 8 significant digits: UFF's ASCII records keep 12
    u, a = np.round(rng.standard_normal((2, T, 2)), 8)
    path = tmp_path / "rig.uff"
    sets = [
        _uff58("acc payload", 20, 12, "g", a[:, 1]),
        _uff58("shaker 1", 10, 13, "N", u[:, 0]),
        _uff58("acc wing", 10, 12, "m/s^2", a[:, 0]),
        _uff58("shaker 2", 20, 13, "N", u[:, 1]),
        _uff58("strain", 30, 3, "ue", u[:, 1]),
    ]
    pyuff.UFF(str(path)).write_sets(sets, mode="overwrite")
    rec = load_recording(path)
    assert rec.n == 2 and rec.dt == pytest.approx(DT, rel=1e-12)
    np.testing.assert_allclose(rec.t, DT * np.arange(T), rtol=0, atol=1e-15)
    np.testing.assert_array_equal(rec.u, u)
    np.testing.assert_array_equal(rec.a[:, 0], a[:, 0])
    np.testing.assert_allclose(rec.a[:, 1], a[:, 1] * STANDARD_GRAVITY, rtol=1e-15)
    assert rec.notes[0] == "ignored column 'strain'"
    mapped = load_recording(path, columns={"u": ["shaker 2"], "x": ["acc wing"]}, units={"x": "V"})
    np.testing.assert_array_equal(mapped.x[:, 0], a[:, 0])
    assert mapped.units == {"time": "s", "force": "N", "displacement": "V"}


def test_missing_optional_packages_name_their_extra(tmp_path, monkeypatch):
    import sys

    for ext, module, extra in ((".h5", "h5py", "hdf5"), (".uff", "pyuff", "uff")):
        path = tmp_path / f"r{ext}"
        path.write_bytes(b"x")
        monkeypatch.setitem(sys.modules, module, None)  # import raises ImportError
        with pytest.raises(RecordingError, match=rf"need the {module} package: pip install 'algid\[{extra}\]'"):
            load_recording(path)
    t, u, a = _signals()
    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(RecordingError, match=r"DataFrames need the pandas package: pip install 'algid\[pandas\]'"):
        Recording(t=t, u=u, a=a).to_frame()


def _text(tmp_path, text, name="r.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def _rows(k_max=20, sep=",", fields=("1", "2")):
    return "".join(f"{k}e-3{sep}{sep.join(fields)}\n" for k in range(k_max))


HOSTILE = [
    ("t;u1;a1\n" + _rows(sep=";") + "0,02;1\n", "ragged row at line 22: 2 fields"),
    ("t\tu1\ta1\n" + _rows(sep="\t", fields=("1", "x")), "line 2, column 'a1': cannot parse 'x'"),
    ("t [samples],u1,a1\n" + _rows(), "unknown unit 'samples' for time"),
    ("t,u1 [N],u2 [V],a1,a2\n" + _rows(fields=("1", "2", "3", "4")), "force columns in different units: N, V"),
    ("t,time,u1,a1\n" + _rows(fields=("0", "1", "2")), "two time columns, 't' and 'time'"),
    ("t,u1 [N],u1 [V],a1\n" + _rows(fields=("1", "2", "3")), "duplicate column 'u1'"),
    ("u1,a1\n" + _rows(), "missing column 't'"),
]


@pytest.mark.parametrize("text,needle", HOSTILE)
def test_hostile_text_files_fail_in_one_line(tmp_path, text, needle):
    with pytest.raises(RecordingError) as info:
        load_recording(_text(tmp_path, text))
    assert "\n" not in str(info.value) and needle in str(info.value), str(info.value)


def test_hostile_archives_and_mappings(tmp_path):
    import gzip
    import zipfile

    (tmp_path / "r.csv.gz").write_bytes(gzip.compress(b"t,u1,a1\n" + _rows().encode())[:-30])
    with pytest.raises(RecordingError, match=r"r.csv.gz: not a readable .gz file \(EOFError\)"):
        load_recording(tmp_path / "r.csv.gz")
    (tmp_path / "r.csv.gz").write_bytes(b"not gzip at all")
    with pytest.raises(RecordingError, match="not a readable .gz file"):
        load_recording(tmp_path / "r.csv.gz")
    with zipfile.ZipFile(tmp_path / "r.csv.zip", "w") as z:
        z.writestr("a.csv", "t,u1,a1\n")
        z.writestr("b.csv", "t,u1,a1\n")
    with pytest.raises(RecordingError, match="holds one file, this one holds 2"):
        load_recording(tmp_path / "r.csv.zip")
    path = _text(tmp_path, "t,u1,a1\n" + _rows())
    with pytest.raises(RecordingError, match="no column 'F' for force"):
        load_recording(path, columns={"u": "F"})
    with pytest.raises(RecordingError, match="unknown role 'torque'"):
        load_recording(path, columns={"torque": "u1"})
    with pytest.raises(RecordingError, match="column 'u1' given for two signals"):
        load_recording(path, columns={"u": "u1", "a": "u1"})
    with pytest.raises(RecordingError, match="units: unknown role 'speed'"):
        load_recording(path, units={"speed": "m/s"})
    rec = load_recording(path, dt=0.002)  # --rate / --dt replace a time column, with a note
    assert rec.dt == pytest.approx(0.002) and any("time column replaced" in n for n in rec.notes)


@pytest.fixture(scope="module")
def table1(tmp_path_factory):
    return simulate_chain(TABLE1, multisine(3), 0.3)


def _cli(capsys, *args):
    code = algid.cli.main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_done_when_a_pandas_csv_with_time_and_units_goes_through_identify(tmp_path, capsys, table1):
    t, a, u, _ = table1
    path = tmp_path / "rig.csv"
    _frame(t, u, a / STANDARD_GRAVITY, accel="a{} [g]").to_csv(path)
    out = tmp_path / "est.json"
    code, stdout, stderr = _cli(capsys, "identify", path, "--json", out)
    assert code == 0, stderr
    doc = json.loads(out.read_text())
    np.testing.assert_allclose(doc["mass"], TABLE1.mass, rtol=1e-6)
    np.testing.assert_allclose(doc["stiffness"], TABLE1.stiffness, rtol=1e-6)
    assert doc["units"] == {"m": "kg", "c": "N s/m", "k": "N/m"}
    assert doc["recording_notes"] == [
        "ignored columns '' (index), 'temperature [C]'",
        "acceleration g -> m/s^2 (x 9.80665)",
    ]
    assert "algid identify: note: ignored columns '' (index), 'temperature [C]'" in stderr
    assert "m1 =" in stdout and " kg" in stdout


def test_identification_to_frame_in_the_recording_units(table1):
    import algid

    t, a, u, _ = table1
    res = algid.identify(Recording(t=t, u=u * 0.1, a=a, units={"force": "V"}))
    frame = res.to_frame()
    assert list(frame.index) == res.names and list(frame["unit"][:3]) == ["V s^2/m"] * 3
    np.testing.assert_array_equal(frame["value"].to_numpy(), res.theta)
    np.testing.assert_allclose(frame.loc[["m1", "m2", "m3"], "value"], TABLE1.mass * 0.1, rtol=1e-6)
    assert frame["status"].tolist() == [v.status for v in res.verdicts]


def test_identify_labels_volts_and_reads_a_file_without_time(tmp_path, capsys, table1):
    t, a, u, _ = table1
    volts_per_newton = 0.1
    path = tmp_path / "rig.tsv"
    frame = pd.DataFrame({f"F{i + 1}": u[:, i] * volts_per_newton for i in range(3)})
    frame = frame.join(pd.DataFrame({f"acc{i + 1}": a[:, i] for i in range(3)}))
    frame.to_csv(path, sep="\t", index=False)
    out = tmp_path / "est.json"
    code, stdout, stderr = _cli(
        capsys,
        "identify",
        path,
        "--json",
        out,
        "--force",
        "F1,F2,F3",
        "--accel",
        "acc1,acc2,acc3",
        "--rate",
        1 / (t[1] - t[0]),
        "--units",
        "force=V",
    )
    assert code == 0, stderr
    doc = json.loads(out.read_text())
    np.testing.assert_allclose(doc["mass"], TABLE1.mass * volts_per_newton, rtol=1e-6)
    assert doc["units"] == {"m": "V s^2/m", "c": "V s/m", "k": "V/m"}
    assert "V/m" in stdout and "N/m" not in stdout


def test_cli_option_errors_are_one_line(tmp_path, capsys):
    path = _text(tmp_path, "u1,a1\n" + _rows(fields=("2",)))
    (tmp_path / "map.json").write_text("[1, 2]")
    for args, needle in (
        (("--rate", "0"), "--rate must be a positive number"),
        (("--units", "force"), "--units: expected ROLE=UNIT, got 'force'"),
        (("--columns", tmp_path / "map.json"), "must hold a JSON object"),
        (("--columns", tmp_path / "none.json"), "--columns: cannot read"),
    ):
        for command in ("identify", "diagnose"):
            code, _, stderr = _cli(capsys, command, path, "--json", tmp_path / "o.json", *args)
            lines = stderr.strip().splitlines()
            assert code == 2 and len(lines) == 1 and needle in lines[0], stderr


def test_silverbox_read_as_volts_by_mapping(shared_data):
    """The real Silverbox record (no time column, V1 and V2 in volts) read by a mapping."""
    path = shared_data / "silverbox" / "SNLS80mV.npz"
    fs = 1e7 / 2**14
    rec = load_recording(
        path,
        columns={"force": "V1_input_V", "displacement": "V2_output_V"},
        units={"force": "V", "displacement": "V"},
        dt=1 / fs,
    )
    with np.load(path) as z:
        np.testing.assert_array_equal(rec.u[:, 0], z["V1_input_V"])
        np.testing.assert_array_equal(rec.x[:, 0], z["V2_output_V"])
    assert rec.fs_hz == pytest.approx(fs, rel=1e-12) and rec.n == 1
    assert parameter_units(rec) == {"m": "V s^2/V", "c": "V s/V", "k": "V/V"}
    assert rec.notes == ["ignored column 'fs'", "no time column: t = k * 0.0016384 s"]
