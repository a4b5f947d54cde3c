"""``algid batch`` / :func:`algid.batch`: a generated fleet (good, malformed, empty files) on a
local Dask cluster, the rows against ``algid identify`` and ``algid diagnose`` run one by one,
resume after a kill, the same batch through a separately started scheduler and worker."""

from __future__ import annotations

import json
import math
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("distributed")
pytest.importorskip("pyarrow")
pd = pytest.importorskip("pandas")

import algid  # noqa: E402
from algid.cli import main  # noqa: E402
from algid.diagnosis import EFFECTS  # noqa: E402
from algid.fleet.engine import local_cluster  # noqa: E402
from algid.fleet.inputs import InputError, expand  # noqa: E402
from algid.fleet.store import ResultStore  # noqa: E402
from algid.fleet.summary import summary  # noqa: E402
from algid.fleet.task import Options, content_key  # noqa: E402
from algid.recording import RecordingError, load_recording  # noqa: E402
from fleet_recordings import write_bad, write_fleet  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
# child processes import the algid these tests run (the installed one), plus the tests' helpers
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join([str(Path(algid.__file__).parents[1]), str(REPO / "tests")])}


@pytest.fixture(scope="module")
def fleet(tmp_path_factory) -> Path:
    """Two 3-DOF machines and one 1-DOF machine, 3 recordings of 2 s each, and three bad files."""
    root = tmp_path_factory.mktemp("fleet")
    write_fleet(root / "three", 2, 3, 3, 2.0)
    write_fleet(root / "one", 1, 3, 1, 2.0, suffix=".csv")
    write_bad(root / "bad")
    (root / "three" / "notes.md").write_text("not a recording")
    return root


@pytest.fixture(scope="module")
def client():
    from distributed import Client

    with local_cluster(2) as cluster, Client(cluster) as c:
        yield c


@pytest.fixture(scope="module")
def diagnosed(fleet, client, tmp_path_factory):
    out = tmp_path_factory.mktemp("out")
    return out, algid.batch(fleet, out, client, diagnose=True)


@pytest.mark.slow
def test_the_workers_import_the_algid_these_tests_run(client):
    """Workers start with this process's ``sys.path``: a module that put the checkout's python/
    (no compiled core there) ahead of the installed algid would break every worker."""
    assert set(client.run(lambda: __import__("algid").__file__).values()) == {algid.__file__}


@pytest.mark.slow
def test_a_folder_of_good_malformed_and_empty_recordings(fleet, diagnosed):
    out, table = diagnosed
    assert table.attrs["counts"] == {"ok": 9, "failed": 3, "skipped": 0}
    assert sorted(table["path"]) == [str(p) for p in expand(fleet)]
    failed = table[table["status"] == "failed"].set_index("name")
    for name in ("malformed.csv", "empty.csv", "truncated.npz"):
        with pytest.raises(RecordingError) as err:
            load_recording(fleet / "bad" / name)
        assert failed.loc[name, "error"] == str(err.value)
    assert "notes.md" not in set(table["name"])
    stored = ResultStore(out).read()
    assert len(stored) == 12 and stored["key"].is_unique
    assert set(stored["effect"].dropna()) <= set(EFFECTS) | {"none", "unknown"}


@pytest.mark.parametrize("rel", ["three/m01/rec0002.npz", "one/m00/rec0001.csv"])
@pytest.mark.slow
def test_rows_equal_identify_and_diagnose_run_one_by_one(fleet, diagnosed, tmp_path, rel):
    path = fleet / rel
    assert main(["identify", str(path), "--json", str(tmp_path / "i.json"), "--quiet"]) == 0
    assert main(["diagnose", str(path), "--json", str(tmp_path / "d.json"), "--quiet"]) == 0
    ident = json.loads((tmp_path / "i.json").read_text())
    diag = json.loads((tmp_path / "d.json").read_text())
    row = diagnosed[1].set_index("path").loc[str(path)]
    for p in ident["parameters"]:
        for column, value in ((p["name"], p["value"]), (f"sigma_{p['name']}", p["sigma"])):
            assert row[column] == value or (value is None and math.isnan(row[column]))
    assert (row["valid"], row["estimator"], row["n"]) == (ident["valid"], ident["estimator"], ident["n"])
    assert (row["effect"], row["gap_before"], row["gap_after"]) == (
        diag["effect"],
        diag["gap_before"],
        diag["gap_after"],
    )
    assert (json.loads(row["location"]), json.loads(row["params"])) == (diag["location"], diag["params"])


@pytest.mark.slow
def test_a_second_run_skips_every_recording_it_has(fleet, diagnosed, client):
    out, first = diagnosed
    again = algid.batch(fleet, out, client, diagnose=True)
    assert again.attrs["counts"] == {"ok": 0, "failed": 0, "skipped": 12}
    pd.testing.assert_frame_equal(
        again.sort_values("path").reset_index(drop=True), first.sort_values("path").reset_index(drop=True)
    )
    assert len(ResultStore(out).parts()) == 1  # nothing written twice


def test_the_key_is_the_content_the_version_and_the_options(fleet, tmp_path):
    src = fleet / "one" / "m00" / "rec0000.csv"
    copy = tmp_path / "elsewhere.csv"
    copy.write_bytes(src.read_bytes())
    assert content_key(copy, Options()) == content_key(src, Options())
    assert content_key(src, Options(diagnose=True)) != content_key(src, Options())
    assert content_key(src, Options(replicates=9)) != content_key(src, Options())
    copy.write_bytes(src.read_bytes() + b"\n")
    assert content_key(copy, Options()) != content_key(src, Options())
    with pytest.raises(ValueError, match="replicates must be >= 2"):
        Options(replicates=1)


def test_a_row_written_twice_is_read_once(tmp_path):
    store = ResultStore(tmp_path)
    rows = [{"key": "a", "path": "/x/a.csv", "status": "ok"}, {"key": None, "path": "/x/b.csv", "status": "failed"}]
    store.write(rows)
    store.write([{**rows[0], "status": "failed"}, rows[1]])
    table = store.read()
    assert len(table) == 2 and table.set_index("path").loc["/x/a.csv", "status"] == "failed"
    assert store.done() == frozenset({"a"})


def test_inputs_are_files_folders_and_patterns(fleet):
    folder = expand(fleet / "one")
    assert [p.name for p in folder] == ["rec0000.csv", "rec0001.csv", "rec0002.csv"]
    assert expand([fleet / "one", str(fleet / "one" / "*" / "rec000[12].csv")]) == folder
    assert expand(str(fleet / "**" / "*.npz")) == sorted(p.resolve() for p in fleet.rglob("*.npz"))
    with pytest.raises(InputError, match="no such file or folder"):
        expand(fleet / "missing")
    with pytest.raises(InputError, match="no recordings"):
        expand(str(fleet / "*.parquet"))


def test_the_summary_flags_a_machine_whose_stiffness_moved():
    t = pd.to_datetime([0, 3600, 7200], unit="s", utc=True)
    rows = {"status": "ok", "valid": True, "recorded_at": t}
    steady = pd.DataFrame({**rows, "machine": "a", "k1": [100.0, 101.0, 102.0], "sigma_k1": [1.0, 1.0, 1.0]})
    moved = pd.DataFrame({**rows, "machine": "b", "k1": [100.0, 100.0, 90.0], "sigma_k1": [1.0, 1.0, 2.0]})
    table = summary(pd.concat([moved, steady], ignore_index=True)).set_index("machine")
    assert table.loc["a", "stiffness_shift_z"] == pytest.approx(2.0 / math.sqrt(2.0))
    assert table.loc["b", "stiffness_shift_z"] == pytest.approx(10.0 / math.sqrt(5.0))
    assert list(table["moved"]) == [False, True] and list(table["recordings"]) == [3, 3]


def test_a_task_runs_the_bootstrap_on_its_own_thread(fleet, monkeypatch):
    """A worker takes a core: inside run_one the bootstrap's parallel_map does not start a thread
    per core (which oversubscribed the cores: a single worker used 1.56 of 2)."""
    import threading

    from algid import parallel
    from algid.fleet import task
    from algid.identification import surrogate

    monkeypatch.setattr(os, "cpu_count", lambda: 8)
    callers = set()
    real = surrogate.parallel_map

    def spy(fn, items, progress=None):
        return real(lambda x: (callers.add(threading.get_ident()), fn(x))[1], items, progress)

    monkeypatch.setattr(surrogate, "parallel_map", spy)
    good = sorted((fleet / "three").rglob("*.npz"))[0]
    row = task.run_one(str(good), Options(estimator="window"))  # the single window's uncertainty: a bootstrap
    assert row["status"] == "ok" and callers == {threading.get_ident()}
    callers.clear()
    spy(lambda x: x, list(range(8)))  # outside a task: a pool of threads
    assert callers and threading.get_ident() not in callers and parallel._threads is None


def test_a_missing_extra_is_one_line_naming_it(monkeypatch, capsys, tmp_path):
    monkeypatch.setitem(sys.modules, "distributed", None)
    assert main(["batch", str(tmp_path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "algid[batch]" in err and err.startswith("algid batch: error:")


def _parts(out: Path) -> list[Path]:
    return sorted((out / "results").glob("part-*.parquet"))


@pytest.mark.slow
def test_a_killed_batch_resumes_without_losing_or_repeating_a_row(fleet, diagnosed, client, tmp_path):
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "algid.cli", "batch", str(fleet), "--out", str(out), "--diagnose"]
    proc = subprocess.Popen(cmd + ["--workers", "1", "--part-rows", "1", "--quiet"], env=ENV, start_new_session=True)
    try:
        deadline = time.monotonic() + 90
        while len(_parts(out)) < 3 and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.02)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # the client and its worker processes, at once
        proc.wait()
    written = len(ResultStore(out).read())
    assert 3 <= written < 12, "the batch was not killed half way"
    resumed = algid.batch(fleet, out, client, diagnose=True)
    assert resumed.attrs["counts"]["skipped"] == written
    assert sum(resumed.attrs["counts"].values()) == 12
    raw = pd.concat([pd.read_parquet(p) for p in _parts(out)], ignore_index=True)
    assert len(raw) == 12 and raw["key"].is_unique  # every recording once, none twice
    columns = ["path", "key", "status", "error", "k1", "sigma_k1", "effect", "gap_after"]
    first = diagnosed[1][columns].sort_values("path").reset_index(drop=True)
    again = resumed[columns].sort_values("path").reset_index(drop=True)
    pd.testing.assert_frame_equal(again, first, check_dtype=False)


def _profiled(dask_worker) -> tuple[bool, int, int, int]:
    import dask

    profile = dask.config.get("distributed.worker.profile.enabled"), len(dask_worker.profile_history)
    return (*profile, dask_worker.monitor.maxlen, dask.config.get("distributed.admin.low-level-log-length"))


@pytest.mark.parametrize("workers", [2, 1])
@pytest.mark.slow
def test_a_worker_killed_mid_batch_loses_and_repeats_nothing(fleet, tmp_path, workers):
    """With one worker its death also loses the scattered keys of the output, which the
    batch scatters again."""
    from distributed import Client

    killed = []
    with local_cluster(workers) as cluster, Client(cluster) as c:
        victim = next(iter(c.run(os.getpid).values()))

        def kill_once(counts: dict, total: int) -> None:
            if not killed:
                os.kill(victim, signal.SIGKILL)  # the nanny starts a new worker; Dask reruns its tasks
                killed.append(sum(counts.values()))

        table = algid.batch(fleet / "three", tmp_path, c, progress=kill_once)
        # the restarted worker too runs without Dask's profiler and with short in-memory logs
        assert set(c.run(_profiled).values()) == {(False, 0, 600, 100)}
    assert killed and table.attrs["counts"] == {"ok": 6, "failed": 0, "skipped": 0}
    raw = pd.concat([pd.read_parquet(p) for p in _parts(tmp_path)], ignore_index=True)
    assert len(raw) == 6 and raw["key"].is_unique


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def scheduler():
    """A ``dask scheduler`` and a ``dask worker`` started as separate processes; torn down after."""
    from distributed import Client

    address = f"tcp://127.0.0.1:{_free_port()}"
    mod = [sys.executable, "-m"]
    procs = [
        subprocess.Popen(
            mod
            + [
                "distributed.cli.dask_scheduler",
                "--host",
                "127.0.0.1",
                "--port",
                address.rsplit(":", 1)[1],
                "--no-dashboard",
            ],
            env=ENV,
            stderr=subprocess.DEVNULL,
        )
    ]
    procs.append(
        subprocess.Popen(
            mod
            + [
                "distributed.cli.dask_worker",
                address,
                "--nworkers",
                "1",
                "--nthreads",
                "1",
                "--no-dashboard",
                "--memory-limit",
                "2GiB",
            ],
            env=ENV,
            stderr=subprocess.DEVNULL,
        )
    )
    try:
        with Client(address, timeout="30s") as c:
            c.wait_for_workers(1, timeout=60)
        yield address
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


@pytest.mark.slow
def test_the_same_batch_through_a_scheduler_address(fleet, diagnosed, scheduler, tmp_path, capsys):
    out = tmp_path / "out"
    assert (
        main(["batch", str(fleet / "three" / "m00"), str(fleet / "bad"), "--out", str(out), "--scheduler", scheduler])
        == 0
    )
    err = capsys.readouterr().err
    assert err.strip().splitlines()[-1].startswith("algid batch: 3 ok, 3 failed, 0 skipped")
    remote = ResultStore(out).read().set_index("path").sort_index()
    local = diagnosed[1].set_index("path").loc[remote.index]
    columns = ["status", "error", "n", "valid"] + [c for c in local.columns if c[0] in "mck" and c[1:].isdigit()]
    pd.testing.assert_frame_equal(remote[columns], local[columns], check_dtype=False)
    assert set(remote["worker_pid"].dropna()).isdisjoint(set(local["worker_pid"]))
    machines = pd.read_csv(out / "summary.csv").set_index("machine")
    assert machines.loc["m00", "ok"] == 3 and machines.loc["bad", "failed"] == 3
    assert all((out / f).stat().st_size > 0 for f in ("histories.png", "verdicts.png"))
    assert main(["batch", str(fleet / "bad"), "--out", str(tmp_path / "bad"), "--scheduler", scheduler]) == 3
