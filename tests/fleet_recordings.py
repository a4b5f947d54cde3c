"""Generated fleets of recordings for the batch tests and ``bench/fleet.py``: machines (folders)
of simulated chains under the tests' multisine force, with a mix of noise levels and
unmodelled effects, plus malformed and empty files."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from algid.chain import Chain
from algid.recording import Recording, save_recording
from algid.simulator import simulate
from signals import multisine

#: Effects mixed into a fleet (None: the linear chain), cycled over the recordings.
EFFECTS = (
    None,
    {"name": "cubic_stiffness", "location": {"spring": 1}, "params": {"k_cubic": 3e7}},
    {"name": "coulomb_friction", "location": {"dof": 1}, "params": {"force": 1.5}},
)
#: Sensor SNRs [dB] cycled over the recordings.
NOISE_DB = (60.0, 40.0, 30.0)


def recording(chain: Chain, duration_s: float, seed: int, effect=None, noise_db: float | None = 40.0) -> Recording:
    """One simulated recording of ``chain`` at 1 kHz (forces and accelerations)."""
    sim = simulate(
        chain,
        multisine(chain.n, seed),
        duration_s,
        effects=[] if effect is None else [effect],
        noise_db=noise_db,
        noise_on=("accel", "force"),
        seed=seed,
    )
    return Recording(t=sim.t, u=sim.u, a=sim.a)


def write_recording(folder: Path, machine: int, index: int, n: int, duration_s: float, suffix=".npz") -> Path:
    """Recording ``index`` of machine ``machine`` (``folder/m{machine:02d}/rec{index:04d}``): the
    chain ``Chain.random(n, default_rng(machine))``, seed ``1000 machine + index``, whose residues
    pick the effect and the noise level."""
    chain = Chain.random(n, np.random.default_rng(machine))
    (folder / f"m{machine:02d}").mkdir(parents=True, exist_ok=True)
    seed = 1000 * machine + index
    rec = recording(chain, duration_s, seed, EFFECTS[seed % len(EFFECTS)], NOISE_DB[seed % len(NOISE_DB)])
    return save_recording(folder / f"m{machine:02d}" / f"rec{index:04d}{suffix}", rec)


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
