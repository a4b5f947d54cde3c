"""Recordings shaped like those real rigs write, with their truth: for tests, benchmarks and
the realistic blind check.

* :func:`positioning_axis`: a slow machine axis (mass and viscous friction, no spring:
  natural frequency zero) under closed-loop bang-bang moves, position from an incremental
  encoder only, force as the drive commands it (held between samples). Any simulator
  effect of its DOF (dry friction, a constant force the drive's sensor does not see ...).
* :func:`displacement_driven`: a device whose motion is imposed (a testing machine, a
  shaker in displacement control) at 0.5-2 Hz, so that its inertia is negligible against
  its spring, damping and friction; force and displacement measured. Any simulator effect
  of its one DOF or spring (dry friction, a clearance or backlash, micro-slip ...).

* :func:`torsion_frame`, :func:`half_car`, :func:`lattice`: the spring networks of issue 39
  (:data:`NETWORKS`), and :func:`network_recording`, a record of one of them.

* :func:`write_fleet_recording`: one recording of a generated fleet of machines (folders)
  for ``algid batch``: simulated chains with a mix of noise levels and effects.

Each of the first two returns a :class:`Scenario`: the :class:`~algid.recording.Recording` as a data logger
would write it (only the signals the rig measures), the true chain, and what else acts.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..control.positioning import BangBangReference, PositioningController
from ..model.chain import Chain
from ..model.network import Network, NetworkModel
from ..recording import Recording, save_recording
from . import effect_forces, simulate
from .exact import multisine


@dataclass
class Scenario:
    """A generated recording and its truth.

    recording : what the rig's logger writes; chain : the linear part of the plant (a
    :class:`~algid.model.network.NetworkModel` for a network);
    effects : unmodelled effects (simulator ``Effect`` dicts); info : scenario settings.
    """

    recording: Recording
    chain: Chain
    effects: list = field(default_factory=list)
    info: dict = field(default_factory=dict)


def positioning_axis(
    seed: int = 0,
    duration_s: float = 20.0,
    mass_kg: float = 5.0,
    viscous_ns_m: float = 25.0,
    encoder_m: float = 1e-6,
    effects: Sequence = (),
    stroke_m: float = 0.05,
    a_max: float = 4.0,
    fs_hz: float = 1000.0,
) -> Scenario:
    """A ball-screw axis moving between random targets within ``+-stroke_m`` (module
    docstring), with any simulator ``effects`` of its DOF (dry friction, an unrecorded
    constant force, a drive delay ...). The drive's feedforward assumes 80 % of the mass
    and half the friction; its PID (``kp`` 8e3 N/m, ``kd`` 160 N s/m, ``ki`` 4e4 N/(m s)
    and a force limit of 12 N, each per kg of mass) closes the loop on the encoder."""
    rng = np.random.default_rng(seed)
    moves = max(2, int(np.ceil(duration_s / 0.5)))
    ref = BangBangReference(
        rng.uniform(-stroke_m, stroke_m, (moves, 1)), a_max=a_max, dwell_s=float(rng.uniform(0.3, 0.6))
    )
    m = mass_kg
    ctl = PositioningController(
        ref, f_max=12.0 * m, kp=8e3 * m, kd=160.0 * m, ki=4e4 * m, m0=0.8 * m, c0=0.5 * viscous_ns_m
    )
    chain = Chain([mass_kg], [viscous_ns_m], [0.0, 0.0])
    sim = simulate(
        chain,
        None,
        duration_s,
        fs_hz,
        controller=ctl,
        mode="sampled",
        effects=list(effects),
        encoder_resolution_m=encoder_m,
    )
    rec = Recording(t=sim.t, u=sim.u, x=sim.x_meas)
    return Scenario(rec, chain, list(effects), {"encoder_m": encoder_m, "moves": moves, "fs_hz": fs_hz})


def displacement_driven(
    seed: int = 0,
    duration_s: float = 20.0,
    mass_kg: float = 0.05,
    damping_ns_m: float = 200.0,
    stiffness_n_m: float = 2e4,
    effects: Sequence = (),
    amplitude_m: float = 2e-3,
    noise_db: float = 50.0,
    fs_hz: float = 1000.0,
) -> Scenario:
    """Imposed displacement: three sines at 0.5, 1.1 and 1.9 Hz (random phases) of total
    amplitude about ``amplitude_m``; the force is what the device needs for that motion,
    ``m x'' + c x' + k x`` minus the forces of ``effects`` (simulator effects of DOF 1 and
    spring 1, :func:`algid.simulator.effect_forces`: dry friction, a clearance, micro-slip
    ...); white noise of ``noise_db`` SNR on force and displacement. A backlash (a spring
    that only bites beyond a gap) is ``stiffness_n_m=0`` with a ``clearance`` effect."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(round(duration_s * fs_hz))) / fs_hz
    f = np.array([0.5, 1.1, 1.9])
    ph = rng.uniform(0, 2 * np.pi, f.size)
    w = 2 * np.pi * f
    amp = amplitude_m / np.sqrt(f.size)
    x = amp * np.sin(np.outer(t, w) + ph).sum(axis=1)[:, None]
    v = amp * (w * np.cos(np.outer(t, w) + ph)).sum(axis=1)[:, None]
    a = -amp * (w**2 * np.sin(np.outer(t, w) + ph)).sum(axis=1)[:, None]
    chain = Chain([mass_kg], [damping_ns_m], [stiffness_n_m, 0.0])
    u = mass_kg * a + damping_ns_m * v + stiffness_n_m * x - effect_forces(chain, effects, t, x, v, duration_s)
    ratio = 10.0 ** (-noise_db / 20.0)
    u_meas = u + ratio * np.std(u) * rng.standard_normal(u.shape)
    x_meas = x + ratio * np.std(x) * rng.standard_normal(x.shape)
    return Scenario(
        Recording(t=t, u=u_meas, x=x_meas),
        chain,
        list(effects),
        {"frequencies_hz": f.tolist(), "noise_db": noise_db, "fs_hz": fs_hz},
    )


def impact_test(
    seed: int = 0,
    modes: int = 5,
    hits: int = 4,
    duration_s: float = 4.0,
    fs_hz: float = 10000.0,
    noise_db: float = 50.0,
) -> Scenario:
    """An impact-hammer test of a clamped structure: a chain of ``modes`` masses (a clamped
    beam's first modes, about 20-400 Hz) struck ``hits`` times at DOF 1 with half-sine
    pulses of 0.5-1.5 ms, its force and the velocity of DOF 1 recorded (a laser vibrometer
    at the drive point), ``noise_db`` SNR on both. As a one-DOF record, it carries more
    modes than the chain has DOF."""
    rng = np.random.default_rng(seed)
    m = rng.uniform(0.05, 0.2, modes)
    k = np.sort(rng.uniform(2e4, 2e5, modes + 1))[::-1]
    k[-1] = 0.0
    chain = Chain(m, 0.002 * np.sqrt(k[:-1] * m) * 2, k, "free")
    T = int(round(duration_s * fs_hz))
    t = np.arange(T) / fs_hz
    u = np.zeros((T, modes))
    for start in np.sort(rng.uniform(0.05, duration_s - 0.5, hits)):
        width = float(rng.uniform(0.5e-3, 1.5e-3))
        on = (t >= start) & (t < start + width)
        u[on, 0] += float(rng.uniform(20, 100)) * np.sin(np.pi * (t[on] - start) / width)
    sim = simulate(chain, u, duration_s, fs_hz, force_interp="linear")
    ratio = 10.0 ** (-noise_db / 20.0)
    f_meas = sim.u[:, :1] + ratio * np.std(sim.u[:, 0]) * rng.standard_normal((T, 1))
    v_meas = sim.v[:, :1] + ratio * np.std(sim.v[:, 0]) * rng.standard_normal((T, 1))
    return Scenario(
        Recording(t=t, u=f_meas, v=v_meas),
        chain,
        [],
        {"natural_hz": chain.natural_frequencies_hz().tolist(), "hits": hits, "fs_hz": fs_hz},
    )


#: Effects mixed into a fleet (None: the linear chain), cycled over the recordings.
FLEET_EFFECTS = (
    None,
    {"name": "cubic_stiffness", "location": {"spring": 1}, "params": {"k_cubic": 3e7}},
    {"name": "coulomb_friction", "location": {"dof": 1}, "params": {"force": 1.5}},
)
#: Sensor SNRs [dB] cycled over the recordings.
FLEET_NOISE_DB = (60.0, 40.0, 30.0)


def fleet_recording(
    chain: Chain, duration_s: float, seed: int, effect=None, noise_db: float | None = 40.0
) -> Recording:
    """One recording of a fleet (``algid batch``'s tests and ``bench/fleet.py``): ``chain``
    at 1 kHz under the tests' multisine force (:func:`algid.simulator.exact.multisine`),
    forces and accelerations with ``noise_db`` of sensor noise."""
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


def write_fleet_recording(folder: Path, machine: int, index: int, n: int, duration_s: float, suffix=".npz") -> Path:
    """Recording ``index`` of machine ``machine`` (``folder/m{machine:02d}/rec{index:04d}``): the
    chain ``Chain.random(n, default_rng(machine))``, seed ``1000 machine + index``, whose residues
    pick the effect and the noise level."""
    chain = Chain.random(n, np.random.default_rng(machine))
    (folder / f"m{machine:02d}").mkdir(parents=True, exist_ok=True)
    seed = 1000 * machine + index
    effect, noise_db = FLEET_EFFECTS[seed % len(FLEET_EFFECTS)], FLEET_NOISE_DB[seed % len(FLEET_NOISE_DB)]
    rec = fleet_recording(chain, duration_s, seed, effect, noise_db)
    return save_recording(folder / f"m{machine:02d}" / f"rec{index:04d}{suffix}", rec)


# --- spring networks (issue 39) --------------------------------------------------------------


def torsion_frame(seed: int = 39) -> NetworkModel:
    """A torsionally coupled 3-storey frame, 9 DOF: ``x, y, theta`` of floor f are DOF
    ``3f-2, 3f-1, 3f`` (the rotation as the arc ``r theta`` [m] at the floor's radius of
    gyration, its mass the floor's). Springs join the three DOF of a floor (eccentric
    stiffness couples sway and twist), each DOF to the same DOF of the floor above, and the
    first floor's three DOF to ground. Masses 1-3 kg, springs 1e3-1e4 N/m, dampers 1-5 N s/m
    drawn from ``seed``."""
    pairs = []
    for f in range(3):
        x, y, th = 3 * f + 1, 3 * f + 2, 3 * f + 3
        pairs += [(x, y), (x, th), (y, th)]
        below = (0, 0, 0) if f == 0 else (x - 3, y - 3, th - 3)
        pairs += list(zip(below, (x, y, th)))
    return _drawn(Network(9, pairs), seed)


def half_car(seed: int = 39) -> NetworkModel:
    """A half-car, 4 DOF: the body as two points (front DOF 1, rear DOF 2) joined by the
    body's spring, each over its wheel (front DOF 3, rear DOF 4) on a suspension spring, the
    wheels on tyre springs to ground. Body points 2.5-3 kg, wheels 1 kg, tyres 8e3-1e4 N/m,
    suspensions 1.5e3-2.5e3 N/m, the body spring 4e3-6e3 N/m, from ``seed``."""
    rng = np.random.default_rng(seed)
    net = Network(4, [(1, 2), (3, 1), (4, 2), (0, 3), (0, 4)])
    m = np.array([rng.uniform(2.5, 3.0), rng.uniform(2.5, 3.0), 1.0, 1.0])
    k = np.array([rng.uniform(4e3, 6e3), *rng.uniform(1.5e3, 2.5e3, 2), *rng.uniform(8e3, 1e4, 2)])
    return NetworkModel(net, m, rng.uniform(1.0, 5.0, 4), k)


def lattice(seed: int = 39) -> NetworkModel:
    """A 3x3 lattice, 9 DOF (row r, column c is DOF ``3r + c + 1``): springs along every edge,
    both diagonals of each of the four cells, and the four corners to ground; the centre DOF
    has eight springs. Values as :func:`torsion_frame`'s."""
    dof = lambda r, c: 3 * r + c + 1  # noqa: E731
    pairs = [(dof(r, c), dof(r, c + 1)) for r in range(3) for c in range(2)]
    pairs += [(dof(r, c), dof(r + 1, c)) for r in range(2) for c in range(3)]
    for r in range(2):
        for c in range(2):
            pairs += [(dof(r, c), dof(r + 1, c + 1)), (dof(r, c + 1), dof(r + 1, c))]
    pairs += [(0, dof(r, c)) for r in (0, 2) for c in (0, 2)]
    return _drawn(Network(9, pairs), seed)


def _drawn(net: Network, seed: int) -> NetworkModel:
    """Masses 1-3 kg, dampers 1-5 N s/m, springs 1e3-1e4 N/m (log-uniform) drawn from ``seed``."""
    rng = np.random.default_rng(seed)
    k = np.exp(rng.uniform(np.log(1e3), np.log(1e4), net.size))
    return NetworkModel(net, rng.uniform(1.0, 3.0, net.n), rng.uniform(1.0, 5.0, net.n), k)


#: The issue's example networks by name.
NETWORKS = {"frame": torsion_frame, "half_car": half_car, "lattice": lattice}


def network_model(name: str, seed: int = 39) -> NetworkModel:
    """The example network ``name`` (one of :data:`NETWORKS`)."""
    if name not in NETWORKS:
        raise ValueError(f"unknown network {name!r}: one of {', '.join(NETWORKS)}")
    return NETWORKS[name](seed)


def network_recording(
    name: str, duration_s: float = 1.0, seed: int = 0, noise_db: float | None = None, fs_hz: float = 1000.0
) -> Scenario:
    """A recording of the example network ``name`` (:data:`NETWORKS`) under the tests'
    multisine force on every DOF (:func:`algid.simulator.exact.multisine`), accelerations and
    forces with ``noise_db`` of sensor noise (None: noise-free)."""
    model = network_model(name)
    sim = simulate(
        model, multisine(model.n, seed), duration_s, fs_hz, noise_db=noise_db, noise_on=("accel", "force"), seed=seed
    )
    return Scenario(Recording(t=sim.t, u=sim.u, a=sim.a), model, [], {"network": name, "noise_db": noise_db})
