"""Generated fleets of recordings for the batch tests: machines (folders) of simulated chains
(:func:`algid.simulator.scenarios.write_fleet_recording`, shared with ``bench/fleet.py``), plus
malformed and empty files."""

from __future__ import annotations

from pathlib import Path

from algid.simulator.scenarios import FLEET_EFFECTS as EFFECTS
from algid.simulator.scenarios import fleet_recording as recording
from algid.simulator.scenarios import write_fleet_recording as write_recording

__all__ = ["EFFECTS", "recording", "write_bad", "write_fleet", "write_recording"]


def write_fleet(folder: Path, machines: int, per_machine: int, n: int, duration_s: float, suffix=".npz") -> list[Path]:
    """``machines`` folders of ``per_machine`` recordings each (:func:`write_recording`)."""
    return [write_recording(folder, i, j, n, duration_s, suffix) for i in range(machines) for j in range(per_machine)]


def write_bad(folder: Path) -> dict[str, Path]:
    """A malformed CSV (a field that is not a number), an empty file and a truncated npz."""
    folder.mkdir(parents=True, exist_ok=True)
    bad = {"malformed": folder / "malformed.csv", "empty": folder / "empty.csv", "truncated": folder / "truncated.npz"}
    bad["malformed"].write_text("t,u1,a1\n" + "".join(f"{k / 1000},1.0,{'x' if k == 5 else 0.5}\n" for k in range(20)))
    bad["empty"].write_bytes(b"")
    bad["truncated"].write_bytes(b"PK\x03\x04 not really a zip")
    return bad
