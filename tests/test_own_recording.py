"""A user's first hour (issue 37): a file with the user's own names and units (pandas-style
headers ``time [s]``, ``F1 [N]``, ``acc1 [g]``, a 2048 Hz logger's timestamps rounded to
microseconds, a dropped sample), units said and never guessed, missing samples bridged, the
command line's reading options in ``algid batch`` and in the Python entry points, help that reads
alike, and the README's "Your own recording" section run as written."""

from __future__ import annotations

import argparse
import json
import re
import shlex
from pathlib import Path

import numpy as np
import pytest

import algid
import algid.cli
from algid.model.chain import Chain
from algid.recording import RecordingError, load_recording
from algid.recording.units import STANDARD_GRAVITY
from signals import multisine, simulate_chain

REPO = Path(__file__).resolve().parents[1]
#: The README's example rig: two masses between walls, sampled at 2048 Hz.
RIG = Chain([2.0, 1.0], [3.0, 2.0], [800.0, 400.0, 600.0])
FS_HZ = 2048.0
HEADER = "time [s],F1 [N],F2 [N],acc1 [g],acc2 [g]"


@pytest.fixture(scope="module")
def rig_signals():
    t, a, u, _ = simulate_chain(RIG, multisine(2, seed=4), 2.0, fs_hz=FS_HZ)
    rng = np.random.default_rng(1)
    return t, u, a + 1e-3 * a.std(axis=0) * rng.standard_normal(a.shape)


def write_rig(path: Path, t, u, a, header: str = HEADER, missing=((301, 0),)) -> Path:
    """The rig's file as a logger writes it: timestamps to the microsecond, 6 significant digits,
    accelerations in g, NaN where a sample was dropped."""
    g = a / STANDARD_GRAVITY
    for row, col in missing:
        g[row, col] = np.nan
    rows = (f"{t[k]:.6f},{u[k, 0]:.6g},{u[k, 1]:.6g},{g[k, 0]:.6g},{g[k, 1]:.6g}" for k in range(t.size))
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    return path


@pytest.fixture
def rig_csv(tmp_path, rig_signals):
    return write_rig(tmp_path / "rig.csv", *rig_signals)


def _cli(capsys, *args):
    code = algid.cli.main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


MAPPED = ("--force", "F1,F2", "--accel", "acc1,acc2")


# item 2: units said, never guessed silently


def test_a_column_without_a_unit_is_si_with_a_note(tmp_path, rig_signals):
    t, u, a = rig_signals
    path = write_rig(tmp_path / "bare.csv", t, u, a * STANDARD_GRAVITY, header="time [s],F1 [N],F2,acc1,acc2 [g]")
    rec = load_recording(path, columns={"u": ["F1", "F2"], "a": ["acc1", "acc2"]})
    assert "no unit for F2, acc1: SI assumed (N, m/s^2)" in rec.notes
    np.testing.assert_allclose(rec.a[:5, 0], a[:5, 0], rtol=1e-5)  # acc1 read as m/s^2 (written in "g" / g)
    np.testing.assert_allclose(rec.a[:5, 1], a[:5, 1] * STANDARD_GRAVITY, rtol=1e-5)  # acc2 [g] converted


@pytest.mark.parametrize(
    "units,header_unit,needle",
    [
        ("acceleration=gee", "g", "unknown unit 'gee' for acceleration: did you mean g?"),
        (None, "G", "unknown unit 'G' for acceleration: did you mean g?"),
        ("force=Nm", "g", "unknown unit 'Nm' for force: did you mean N or"),
    ],
)
def test_an_unknown_unit_is_an_error_with_the_nearest_names(tmp_path, rig_signals, units, header_unit, needle):
    header = HEADER.replace("[g]", f"[{header_unit}]")
    path = write_rig(tmp_path / "rig.csv", *rig_signals, header=header)
    with pytest.raises(RecordingError) as info:
        load_recording(
            path, columns={"u": ["F1", "F2"], "a": ["acc1", "acc2"]}, units=units and dict([units.split("=")])
        )
    assert needle in str(info.value)


def test_a_declared_label_is_kept_and_labels_the_results(tmp_path, rig_signals):
    path = write_rig(tmp_path / "rig.csv", *rig_signals)
    rec = load_recording(path, columns={"u": ["F1", "F2"], "a": ["acc1", "acc2"]}, units={"force": "lbs:label"})
    assert rec.units["force"] == "lbs" and rec.units["acceleration"] == "m/s^2"
    assert algid.recording.parameter_units(rec)["k"] == "lbs/m"


# item 3: missing samples


def test_isolated_nans_are_bridged_noted_and_left_out_of_identify(tmp_path, rig_signals):
    t, u, a = rig_signals
    path = write_rig(tmp_path / "rig.csv", t, u, a, missing=((301, 0), (900, 1), (901, 1), (1500, 0)))
    rec = load_recording(path, columns={"u": ["F1", "F2"], "a": ["acc1", "acc2"]})
    assert np.flatnonzero(rec.missing).tolist() == [301, 900, 901, 1500]
    note = next(n for n in rec.notes if "missing" in n)
    assert (
        note.startswith("4 missing values (NaN or inf) in 3 gaps of at most 2 samples") and "acc1 at line 303" in note
    )
    # a straight line between the neighbours: within the signal's curvature of the truth
    assert abs(rec.a[301, 0] - a[301, 0]) < 5e-3 * np.abs(a[:, 0]).max()
    res = algid.identify(rec)
    assert res.screened.rows[[301, 900, 901, 1500]].all()  # the estimators never see those instants
    np.testing.assert_allclose(res.mass, RIG.mass, rtol=1e-3)
    np.testing.assert_allclose(res.stiffness, RIG.stiffness, rtol=1e-3)


def test_empty_fields_are_missing_samples(tmp_path, rig_signals):
    """A logger that writes nothing for a dropped sample (``,,`` or ``""``): the same as NaN."""
    t, u, a = rig_signals
    nan_path = write_rig(tmp_path / "nan.csv", t, u, a, missing=((301, 0), (900, 1)))
    text = nan_path.read_text().replace(",nan,", ",,", 1).replace(",nan\n", ',""\n', 1)
    assert text.count("nan") == 0
    (tmp_path / "empty.csv").write_text(text)
    mapping = {"u": ["F1", "F2"], "a": ["acc1", "acc2"]}
    empty, nans = load_recording(tmp_path / "empty.csv", columns=mapping), load_recording(nan_path, columns=mapping)
    assert np.flatnonzero(empty.missing).tolist() == [301, 900]
    np.testing.assert_array_equal(empty.a, nans.a)
    assert any("2 missing values" in n for n in empty.notes)


def test_diagnose_prints_no_nan(capsys, rig_csv):
    code, out, err = _cli(capsys, "diagnose", rig_csv, *MAPPED)
    assert code == 0, err
    assert not re.search(r"\bnan\b", out.lower()), out


def test_a_long_gap_or_a_mostly_missing_record_is_refused(tmp_path, rig_signals):
    t, u, a = rig_signals
    gap = write_rig(tmp_path / "gap.csv", t, u, a, missing=[(k, 1) for k in range(1000, 1050)])
    with pytest.raises(RecordingError, match="column acc2 misses 50 samples in a row from line 1002"):
        load_recording(gap, columns={"u": ["F1", "F2"], "a": ["acc1", "acc2"]})
    holes = write_rig(tmp_path / "holes.csv", t, u, a, missing=[(k, 0) for k in range(0, t.size, 3)])
    with pytest.raises(RecordingError, match="33 % of the samples miss a value"):
        load_recording(holes, columns={"u": ["F1", "F2"], "a": ["acc1", "acc2"]})


# items 4 and 5: the same options in batch and in Python


def test_python_entry_points_take_the_command_lines_options(rig_csv):
    with pytest.raises(RecordingError, match="missing force columns"):
        algid.identify(rig_csv)
    rec = algid.as_recording(rig_csv, force="F1,F2", accel=["acc1", "acc2"], units="acceleration=g", rate=FS_HZ)
    assert rec.fs_hz == FS_HZ and any("replaced by t = t0 + k" in n for n in rec.notes)
    with pytest.raises(TypeError, match="not a Recording"):
        algid.as_recording(rec, force="F1")
    with pytest.raises(TypeError, match="forc"):
        algid.as_recording(rig_csv, forc="F1")


def test_batch_reads_each_file_with_the_options_and_the_layouts(tmp_path, rig_signals):
    from algid.fleet.inputs import read_layouts
    from algid.fleet.task import Options, run_one

    t, u, a = rig_signals
    (tmp_path / "rig_a").mkdir()
    (tmp_path / "rig_b").mkdir()
    mine = write_rig(tmp_path / "rig_a" / "r1.csv", t, u, a)
    other = tmp_path / "rig_b" / "r2.csv"
    other.write_text(mine.read_text().replace(HEADER, "t [s],u1 [N],u2 [N],a1 [g],a2 [g]", 1))
    layouts = tmp_path / "layouts.toml"
    layouts.write_text('["rig_a/*.csv"]\nforce = "F1,F2"\naccel = "acc1,acc2"\n')
    options = Options(
        estimator="window", reading=json.dumps({"rate": FS_HZ}), layouts=json.dumps(read_layouts(layouts))
    )
    rows = [run_one(str(p), options) for p in (mine, other)]
    assert [r["status"] for r in rows] == ["ok", "ok"], [r.get("error") for r in rows]
    assert rows[0]["m1"] == pytest.approx(rows[1]["m1"], rel=1e-12)  # one record, two layouts
    assert rows[0]["fs_hz"] == FS_HZ
    plain = run_one(str(mine), Options(estimator="window"))
    assert plain["status"] == "failed" and "missing force columns" in plain["error"]


def test_batch_has_every_reading_option_of_identify():
    parser = algid.cli.build_parser()
    sub = next(a for a in parser._actions if a.dest == "command").choices

    def flags(name):
        return {s for a in sub[name]._actions for s in a.option_strings}

    reading = {"--time", "--force", "--accel", "--velocity", "--displacement", "--columns", "--units", "--rate"}
    assert reading | {"--dt", "--group"} <= flags("identify") & flags("diagnose") & flags("batch")


# item 6: help that reads alike


def test_help_reads_alike():
    parser = algid.cli.build_parser()
    sub = next(a for a in parser._actions if a.dest == "command").choices
    for name, p in sub.items():
        text = p.format_help()
        assert "example:\n  algid " + name in text, name
        for action in p._actions:
            takes_value = action.nargs != 0 and action.option_strings and action.help != "==SUPPRESS=="
            if takes_value and action.choices is None:  # never argparse's generated NAME
                assert action.metavar is not None, (name, action.option_strings)
            shown = action.nargs != 0 and action.default not in (None, [], argparse.SUPPRESS) and action.option_strings
            if shown and action.help:
                assert "default" in p._get_formatter()._expand_help(action), (name, action.option_strings)
    assert "RECORDING" in sub["identify"].format_usage() and "RECORDING" in sub["diagnose"].format_usage()
    assert "gee" not in sub["identify"].format_help() and "lbf" in sub["identify"].format_help()


def test_a_blank_in_a_list_is_answered_with_the_subcommands_usage(capsys, rig_csv):
    with pytest.raises(SystemExit) as info:
        algid.cli.main(["identify", str(rig_csv), "--force", "F1", "F2"])
    err = capsys.readouterr().err
    assert info.value.code == 2 and err.startswith("usage: algid identify")
    assert "algid identify: error: unrecognized arguments: F2 (a list is comma-separated: --force F1,F2)" in err


# item 7: the README's "Your own recording" section, run as written


def _section(readme: str, title: str) -> str:
    start = readme.index(f"## {title}")
    return readme[start : readme.index("\n## ", start + 3)]


def _blocks(text: str, kind: str) -> list[str]:
    return re.findall(rf"```{kind}\n(.*?)```", text, flags=re.S)


def _pattern(line: str) -> re.Pattern:
    """A printed line with its numbers free (another run, another noise draw)."""
    number = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:e[-+]?\d+)?"
    parts = re.split(f"({number})", line.strip())
    text = [number if k % 2 else re.sub(r"(?:\\ )+", r"\\s+", re.escape(part)) for k, part in enumerate(parts)]
    return re.compile(r"\s*" + "".join(text) + r"\s*$")


def test_the_readmes_own_recording_section_runs_as_written(tmp_path, rig_signals, capsys, monkeypatch):
    section = _section((REPO / "README.md").read_text(encoding="utf-8"), "Your own recording")
    shown_file, shown_output = _blocks(section, "text")
    assert shown_file.splitlines()[0] == HEADER
    write_rig(tmp_path / "rig.csv", *rig_signals)
    monkeypatch.chdir(tmp_path)
    (commands,) = _blocks(section, "bash")
    lines = [shlex.split(line, comments=True) for line in commands.splitlines() if line.strip()]
    assert [words[:2] for words in lines] == [["algid", "identify"], ["algid", "diagnose"], ["python", "-c"]]
    code, identified, notes = _cli(capsys, *lines[0][1:])
    assert code == 0, notes
    printed = (notes + identified).splitlines()
    for line in shown_output.strip().splitlines():
        assert any(_pattern(line).match(p) for p in printed), (line, printed)
    doc = json.loads((tmp_path / "estimates.json").read_text())
    np.testing.assert_allclose(doc["stiffness"], RIG.stiffness, rtol=1e-3)
    code, diagnosed, _ = _cli(capsys, *lines[1][1:])
    assert code == 0 and "diagnosis: NONE - the linear model explains the data within noise" in diagnosed
    exec(lines[2][2], {})  # the python -c line
    modes = capsys.readouterr().out
    printed_hz = [float(x) for x in re.findall(r"^\s+\d+\s+([\d.]+)", modes, flags=re.M)]
    np.testing.assert_allclose(printed_hz, RIG.modes().frequencies_hz, rtol=1e-3)
