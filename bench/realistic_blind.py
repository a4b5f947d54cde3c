"""Realistic blind check of ``algid diagnose`` (issue 16): hidden effects under the nuisances
of measured data.

Measures: top-1 effect, location, main parameter and gap shrink of the diagnosis on three
kinds of rig with sensor and drive nuisances, false alarms, answers ``none`` on real effects,
the wall time per diagnosis. The default (30 seeds, 0:30) is a quick look and writes to
``WORK`` only; the published figures (docs/diagnosis.md, about 20 min) are::

    python bench/realistic_blind.py --seeds 20000:20300 --work /tmp/realistic-20k \
        --results bench/results/realistic_blind.json

Every seed draws a rig and everything about it; the recording (only what the rig measures)
goes to ``WORK/recordings/``, the label to ``WORK/labels/``; the diagnosis runs on the
recording alone through the code path of ``algid diagnose`` and the scoring reads labels
and diagnoses only (as ``bench/blind_diagnosis.py``, whose scoring it shares).

Rigs (probabilities 0.5 / 0.25 / 0.25):

* ``shaker``: the blind check's chain and broadband forcing (``blind_diagnosis.draw_case``,
  n = 1..4, effect size by visibility 0.5-50, accelerometer SNR 40-60 dB), with any of
  the eleven effects (``sensor_highpass`` among them: an AC-coupled accelerometer) or none,
  recorded by accelerometers (or, with probability 0.2, a laser
  vibrometer: velocities) and force sensors, with nuisances each drawn with its own
  probability: white force-sensor noise (always, 40-60 dB); a force-sensor offset (0.5;
  5-50 % of the force RMS); coloured (1/f) sensor noise as strong as the white (0.4);
  mains hum, 50 or 60 Hz and two harmonics, 3x the white noise RMS on every channel
  (0.3); the same anti-alias filter on every channel (0.5; 4th-order Butterworth at
  0.25-0.45 fs, causal); sample jitter (0.3; 1-5 % of the sample period); an extra
  structural mode above the chain's (0.3; a flexible right support or a light appendage
  at 2-4 times the highest natural frequency and 4-8 times the top of the forcing band,
  at most 0.45 fs, not recorded).
* ``axis``: the positioning axis of :func:`algid.simulator.scenarios.positioning_axis` (mass
  2-10 kg, viscous 10-50 N s/m, no spring, closed-loop bang-bang moves, 20 s, encoder of
  0.5-5 um, position only), the force as the drive commands it with 40-60 dB of current
  noise; an unrecorded constant force (0.7; 2-20 % of the force RMS); effect none,
  ``coulomb_friction``, ``stribeck_friction``, ``quadratic_damping`` or ``input_delay``.
* ``device``: the displacement-driven device of :func:`algid.simulator.scenarios.displacement_driven`
  (inertia negligible; m 0.02-0.2 kg, c 50-500 N s/m, k 5e3-5e4 N/m, amplitude 1-5 mm,
  40-60 dB on force and displacement, a force offset with probability 0.5); effect none,
  ``coulomb_friction``, ``clearance`` (a backlash: the spring bites beyond a gap of 5-30 %
  of the amplitude), ``cubic_stiffness`` or ``amplitude_damping``.

Effect sizes on the axis and the device: the effect's force is a share r of the force RMS
drawn log-uniformly in [0.03, 0.3] (a Stribeck peak 1.5-3 times its Coulomb level).

Fresh acquisitions (``--fresh``, issue 35 item 4): on top of its rig's own, every case
draws acquisition nuisances the default run does not generate and nobody tunes on, each
with its own probability, from its own random stream (``[seed, 35]``: the rig, the effect
and the rig's nuisances are those of the default run). The analog channels are the
shaker's forces and accelerations (or velocities) and the device's force and displacement;
the axis's force is the drive's command and its position an encoder, so of these the axis
draws only the encoder steps. In the order of the signal path:

* ``pink`` (0.4): 1/f sensor noise on every analog channel (as the default run's
  :func:`pink`, but with a corner): PSD ``S_w f_c / f``, ``S_w`` the channel's white noise
  PSD (its SNR of the label), corner ``f_c`` 0.5-50 Hz log-uniform.
* ``drift`` (0.3): load-cell baseline drift on every force channel, a linear drift or a
  random walk (0.5 each) reaching 1-10 % of the channel's RMS over the record.
* ``antialias`` (0.3): an anti-alias filter of another family than the default run's
  Butterworth on every analog channel: Chebyshev I (0.5-3 dB ripple), elliptic (0.5-2 dB
  ripple, 40-80 dB stop band) or Bessel; order 2-8, cutoff 0.25-0.45 fs, causal.
* ``skew`` (0.3): a multiplexed ADC: the analog channels, in a random order, sampled
  ``k dt / n_channels`` late (k = 0 .. n_channels - 1; cubic-spline interpolation).
* ``adc16`` (0.3): a 16-bit converter on every analog channel, full scale 1.2-4 times the
  channel's peak (one draw per channel).
* ``decimation`` (0.3): an oversampling converter: every analog channel resampled to R fs
  (R = 2..8, FFT interpolation of the record: the rig is not re-simulated at the higher
  rate), filtered by a linear-phase FIR (Hamming, 8 R to 16 R taps, cutoff 0.4-0.5 of the
  output rate) or a CIC-like cascade of 3-5 moving averages of R samples, and decimated by
  R: the filter's droop, delay and stop band at the output rate.
* ``encoder`` (0.3): positions (the axis and the device) counted by an encoder whose step
  is 1/300 to 1/8000 (log-uniform) of the motion's RMS.

The label's ``fresh`` lists what was drawn, with its parameters; the summary adds
``per_nuisance`` (the scores of the cases that drew each one, and of those that drew none).

Scores (issue 16): as the blind check (top-1, location, main parameter within 20 %, in-band
gap shrink) plus the share of effect cases answered ``none`` and the share of ``none``
answers on an inadmissible linear fit.

    python bench/realistic_blind.py                                              # seeds 0:30, quick look
    python bench/realistic_blind.py --seeds 0:150 --work /tmp/realistic          # tuning seeds
    python bench/realistic_blind.py --seeds 20000:20300 --work /tmp/realistic-20k \
        --results bench/results/realistic_blind.json                             # the report
    python bench/realistic_blind.py --seeds 50000:50150 --fresh --work /tmp/fresh-50k \
        --results bench/results/realistic_blind_fresh.json                       # fresh acquisitions
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy.signal import butter, lfilter

HERE = Path(__file__).resolve().parent
import blind_diagnosis as B  # noqa: E402

from algid.model.chain import Chain  # noqa: E402
from algid.recording import Recording, save_recording  # noqa: E402
from algid.recording import motion as recording_motion  # noqa: E402
from algid.simulator import simulate  # noqa: E402
from algid.simulator.scenarios import displacement_driven, positioning_axis  # noqa: E402

FS = 1000.0
DURATION = 10.0
AXIS_DURATION = 20.0
SHAKER_EFFECTS = B.EFFECTS + B.MORE_EFFECTS
AXIS_EFFECTS = ("none", "coulomb_friction", "stribeck_friction", "quadratic_damping", "input_delay")
DEVICE_EFFECTS = ("none", "coulomb_friction", "clearance", "cubic_stiffness", "amplitude_damping")


def _share(rng) -> float:
    return float(np.exp(rng.uniform(np.log(0.03), np.log(0.3))))


def _rms(x) -> float:
    return float(np.sqrt(np.mean(np.asarray(x) ** 2)))


# ------------------------------------------------------------------------------ nuisances


def pink(T: int, n: int, rng) -> np.ndarray:
    """Unit-RMS 1/f noise (T, n)."""
    f = np.fft.rfftfreq(T)
    g = np.where(f > 0, 1.0 / np.sqrt(np.maximum(f, 1.0 / T)), 0.0)
    w = np.fft.irfft(np.fft.rfft(rng.standard_normal((T, n)), axis=0) * g[:, None], T, axis=0)
    return w / w.std(axis=0)


def sensor_chain(t, u, y, rng, snr_db: float, info: dict) -> tuple[np.ndarray, np.ndarray]:
    """The shaker rig's sensors: white noise on both channels, then the drawn nuisances."""
    T, n = y.shape
    fs = 1.0 / (t[1] - t[0])
    white_y = 10 ** (-snr_db / 20) * y.std(axis=0)
    snr_u = float(rng.uniform(40, 60))
    white_u = 10 ** (-snr_u / 20) * u.std(axis=0)
    info["force_snr_db"] = snr_u
    if rng.uniform() < 0.3:  # jitter: the sample is taken at t_k + delta_k
        j = float(rng.uniform(0.01, 0.05))
        delta = j / fs * rng.standard_normal(T)[:, None]
        u = u + delta * np.gradient(u, 1 / fs, axis=0)
        y = y + delta * np.gradient(y, 1 / fs, axis=0)
        info["jitter_of_dt"] = j
    y = y + white_y * rng.standard_normal((T, n))
    u = u + np.where(np.any(u != 0, axis=0), white_u, 0.0) * rng.standard_normal((T, n))
    if rng.uniform() < 0.4:
        y = y + white_y * pink(T, n, rng)
        info["coloured_noise"] = True
    if rng.uniform() < 0.3:
        f0 = float(rng.choice([50.0, 60.0]))
        hum = sum(np.sin(2 * np.pi * h * f0 * t + rng.uniform(0, 2 * np.pi)) / h for h in (1, 2, 3))[:, None]
        y = y + 3 * white_y * hum / _rms(hum)
        u = u + np.where(np.any(u != 0, axis=0), 3 * white_u, 0.0) * hum / _rms(hum)
        info["mains_hz"] = f0
    if rng.uniform() < 0.5:
        b = rng.uniform(0.05, 0.5, n) * u.std(axis=0) * rng.choice([-1.0, 1.0], n)
        u = u + np.where(np.any(u != 0, axis=0), b, 0.0)
        info["force_offset"] = b.tolist()
    if rng.uniform() < 0.5:
        fc = float(rng.uniform(0.25, 0.45))
        bb, aa = butter(4, 2 * fc)
        u, y = lfilter(bb, aa, u, axis=0), lfilter(bb, aa, y, axis=0)
        info["antialias_of_fs"] = fc
    return u, y


def with_extra_mode(chain: Chain, rng, info: dict) -> Chain:
    """An (n+1)-DOF plant: the chain plus a light mass at its right end, on a flexible
    support (fixed end) or as an appendage (free end), its mode 2-4 x the chain's top and
    4-8 x the top of the forcing band, at most 0.45 fs (a higher mode of the structure,
    above the test)."""
    n = chain.n
    fmax = float(chain.natural_frequencies_hz().max())
    me = 0.1 * float(chain.mass.min())
    fe = min(max(fmax * float(rng.uniform(2.0, 4.0)), B.F_BAND_HZ[1] * float(rng.uniform(4.0, 8.0))), 0.45 * FS)
    ke = me * (2 * np.pi * fe) ** 2
    m = np.r_[chain.mass, me]
    c = np.r_[chain.damping, 0.01 * chain.damping.mean()]
    if chain.boundary == "fixed":  # k_{n+1} split in two springs in series around the light mass:
        kw = chain.stiffness[n]  # the same wall spring at low frequency, a mode ka + kb = me we^2
        S = max(ke, 4.0 * kw)
        root = np.sqrt(max(S * S - 4.0 * S * kw, 0.0))
        ka, kb = 0.5 * (S + root), 0.5 * (S - root)
        k = np.r_[chain.stiffness[:n], ka, kb]
        plant = Chain(m, c, k, "fixed")
    else:
        plant = Chain(m, c, np.r_[chain.stiffness[:n], ke, 0.0], "free")
    info["extra_mode_hz"] = float(plant.natural_frequencies_hz().max())
    return plant


# ---------------------------------------------------------------------------------- rigs


def shaker_case(seed: int, rng) -> tuple[Recording, dict]:
    case = B.draw_case(seed, DURATION, FS, effects=SHAKER_EFFECTS)
    lab, chain = case["label"], case["chain"]
    info: dict = {"rig": "shaker"}
    plant = chain
    loc = lab.get("location") or {}
    if (
        rng.uniform() < 0.3
        and not (chain.boundary == "fixed" and loc.get("spring") == chain.n + 1)
        and chain.n >= 1
        and not (chain.n == 1 and chain.boundary == "fixed")
    ):
        plant = with_extra_mode(chain, rng, info)
    n = chain.n
    u_full = np.zeros((case["u"].shape[0], plant.n))
    u_full[:, :n] = case["u"]
    r = simulate(plant, u_full, DURATION, FS, effects=case["effects"])
    # a vibrometer only where the hidden effect is not the accelerometer's own
    velocity = rng.uniform() < 0.2 and lab["effect"] not in ("sensor_bias", "sensor_lowpass", "sensor_highpass")
    y = (r.v if velocity else r.a)[:, :n]
    u, y = sensor_chain(r.t, r.u[:, :n], y, rng, lab["snr_db"], info)
    info["motion"] = "velocity" if velocity else "acceleration"
    rec = Recording(t=r.t, u=u, v=y) if velocity else Recording(t=r.t, u=u, a=y)
    lab.update(info)
    return rec, lab


def axis_case(seed: int, rng) -> tuple[Recording, dict]:
    m, c = float(rng.uniform(2, 10)), float(rng.uniform(10, 50))
    effect = AXIS_EFFECTS[int(rng.integers(len(AXIS_EFFECTS)))]
    q = float(rng.choice([0.5e-6, 1e-6, 2e-6, 5e-6]))
    probe = positioning_axis(seed, AXIS_DURATION, m, c, encoder_m=q)  # the nominal force level
    u_rms = _rms(probe.recording.u)
    v_rms = _rms(np.gradient(probe.recording.x[:, 0], 1 / FS))
    r = _share(rng)
    params: dict = {}
    if effect == "coulomb_friction":
        params = {"force": r * u_rms}
    elif effect == "stribeck_friction":
        params = {
            "force": r * u_rms,
            "static": r * u_rms * float(rng.uniform(1.5, 3.0)),
            "v_stribeck": float(rng.uniform(0.05, 0.3)) * v_rms,
        }
    elif effect == "quadratic_damping":
        params = {"c_quadratic": r * u_rms / v_rms**2}
    elif effect == "input_delay":
        params = {"delay": float(rng.uniform(0.002, 0.02))}
    effects = [] if effect == "none" else [{"name": effect, "location": {"dof": 1}, "params": params}]
    offset = float(rng.uniform(0.02, 0.2) * u_rms * rng.choice([-1, 1])) if rng.uniform() < 0.7 else 0.0
    if offset:
        effects.append({"name": "force_offset", "location": {"dof": 1}, "params": {"offset": offset}})
    sc = positioning_axis(seed, AXIS_DURATION, m, c, encoder_m=q, effects=effects)
    snr_u = float(rng.uniform(40, 60))
    u = sc.recording.u + 10 ** (-snr_u / 20) * sc.recording.u.std() * rng.standard_normal(sc.recording.u.shape)
    rec = Recording(t=sc.recording.t, u=u, x=sc.recording.x)
    lab = _label(
        seed,
        effect,
        {"dof": 1},
        params,
        Chain([m], [c], [0.0, 0.0]),
        snr_u,
        {"rig": "axis", "encoder_m": q, "force_offset_unrecorded": offset, "share": r},
    )
    return rec, lab


def device_case(seed: int, rng) -> tuple[Recording, dict]:
    m, c = float(rng.uniform(0.02, 0.2)), float(rng.uniform(50, 500))
    k, amp = float(np.exp(rng.uniform(np.log(5e3), np.log(5e4)))), float(rng.uniform(1e-3, 5e-3))
    effect = DEVICE_EFFECTS[int(rng.integers(len(DEVICE_EFFECTS)))]
    snr = float(rng.uniform(40, 60))
    x_rms = amp / np.sqrt(2)
    u_rms = k * x_rms  # the spring dominates a quasi-static device
    v_rms = x_rms * 2 * np.pi * 1.1
    r = _share(rng)
    params: dict = {}
    k_lin = k
    loc = {"dof": 1}
    if effect == "coulomb_friction":
        params = {"force": r * u_rms}
    elif effect == "clearance":
        params = {"gap": float(rng.uniform(0.05, 0.3)) * amp, "k_contact": k}
        k_lin, loc = 0.0, {"spring": 1}
    elif effect == "cubic_stiffness":
        params = {"k_cubic": float(rng.choice([-0.5, 1.0])) * r * k / x_rms**2}
        loc = {"spring": 1}
    elif effect == "amplitude_damping":
        params = {"c_amp": r * u_rms / (x_rms * v_rms)}
        loc = {"spring": 1}
    effects = [] if effect == "none" else [{"name": effect, "location": loc, "params": params}]
    sc = displacement_driven(seed, 20.0, m, c, k_lin, effects, amplitude_m=amp, noise_db=snr)
    u = sc.recording.u
    info = {"rig": "device", "share": r, "amplitude_m": amp}
    if rng.uniform() < 0.5:
        b = float(rng.uniform(0.05, 0.5) * u.std() * rng.choice([-1, 1]))
        u = u + b
        info["force_offset"] = b
    rec = Recording(t=sc.recording.t, u=u, x=sc.recording.x)
    return rec, _label(
        seed, effect, loc if effect != "none" else None, params, Chain([m], [c], [k_lin, 0.0]), snr, info
    )


def _label(seed, effect, loc, params, chain, snr, info) -> dict:
    lab = {
        "seed": seed,
        "n": chain.n,
        "boundary": chain.boundary,
        "snr_db": snr,
        "effect": effect,
        "location": loc if effect != "none" else None,
        "params": {k: float(v) for k, v in params.items()},
        "visibility": float(info.get("share", 0.0)) * 100,
        "chain": {
            "mass": chain.mass.tolist(),
            "damping": chain.damping.tolist(),
            "stiffness": chain.stiffness.tolist(),
        },
    }
    lab.update(info)
    return lab


def draw(seed: int, fresh: bool = False) -> tuple[Recording, dict]:
    """The recording and label of one case (deterministic in ``seed``); ``fresh``: with the
    fresh acquisition nuisances (:func:`fresh_acquisition`)."""
    rng = np.random.default_rng([seed, 16])
    rig = rng.choice(["shaker", "shaker", "axis", "device"])
    rec, lab = {"shaker": shaker_case, "axis": axis_case, "device": device_case}[str(rig)](seed, rng)
    return fresh_acquisition(rec, lab, seed) if fresh else (rec, lab)


# ------------------------------------------------------------------------ fresh acquisitions

FRESH_NUISANCES = ("pink", "drift", "antialias", "skew", "adc16", "decimation", "encoder")


def pink_corner(T: int, n: int, dt: float, f_corner: float, rng) -> np.ndarray:
    """(T, n) 1/f noise of PSD ``S_w f_corner / f`` for a unit-variance white ``S_w``
    (``2 dt``); below the record's first bin it stays at that bin's level, no DC."""
    f = np.fft.rfftfreq(T, dt)
    g = np.where(f > 0, np.sqrt(f_corner / np.maximum(f, f[1])), 0.0)
    return np.fft.irfft(np.fft.rfft(rng.standard_normal((T, n)), axis=0) * g[:, None], T, axis=0)


def _skewed(x: np.ndarray, dt: float, delay: float) -> np.ndarray:
    """The columns of ``x`` sampled ``delay`` [s] late (cubic spline, extrapolated at the end)."""
    from scipy.interpolate import CubicSpline

    t = np.arange(x.shape[0]) * dt
    return CubicSpline(t, x, axis=0, extrapolate=True)(t + delay)


def _decimation_filter(R: int, kind: str, rng, info: dict) -> np.ndarray:
    """Taps, at R times the output rate, of a decimation filter of ``kind``: a linear-phase
    FIR ("fir") or a cascade of moving averages ("cic") (module docstring); one filter for
    every channel of the converter."""
    from scipy.signal import firwin

    if kind == "fir":
        taps = int(rng.integers(8 * R, 16 * R + 1)) | 1
        cut = float(rng.uniform(0.4, 0.5))
        info.update({"filter": "fir", "taps": taps, "cutoff_of_output_nyquist": cut})
        return firwin(taps, cut / R, window="hamming")  # cutoff as a share of the high rate's Nyquist
    stages = int(rng.integers(3, 6))
    h = np.ones(1)
    for _ in range(stages):
        h = np.convolve(h, np.ones(R) / R)
    info.update({"filter": "cic", "stages": stages})
    return h


def _decimated(x: np.ndarray, R: int, h: np.ndarray) -> np.ndarray:
    """The columns of ``x`` resampled to R times their rate (FFT), filtered by the taps
    ``h`` and decimated by R."""
    from scipy.signal import resample

    T = x.shape[0]
    return lfilter(h, [1.0], resample(x, R * T, axis=0), axis=0)[::R][:T]


def fresh_acquisition(rec: Recording, lab: dict, seed: int) -> tuple[Recording, dict]:
    """The record with the fresh acquisition nuisances drawn for ``seed`` (module
    docstring); ``lab["fresh"]`` lists them."""
    from scipy.signal import bessel, cheby1, ellip, sosfilt

    rng = np.random.default_rng([seed, 35])
    dt = float(rec.dt)
    kind, y = recording_motion(rec)
    u = np.array(rec.u, dtype=float)
    y = np.array(y, dtype=float)
    T, n = u.shape
    forced = np.any(u != 0, axis=0)
    analog_y = lab["rig"] != "axis"  # the axis: a commanded force and an encoder
    analog_u = lab["rig"] != "axis"
    fresh: dict = {}
    snr_y = float(lab.get("snr_db", 50.0))
    snr_u = float(lab.get("force_snr_db", snr_y))

    def channels() -> list[tuple[str, int]]:
        return ([("u", i) for i in range(n) if forced[i]] if analog_u else []) + (
            [("y", i) for i in range(n)] if analog_y else []
        )

    def apply(fn) -> None:
        nonlocal u, y
        if analog_u:
            u[:, forced] = fn(u[:, forced])
        if analog_y:
            y = fn(y)

    if rng.uniform() < 0.4 and channels():
        fc = float(np.exp(rng.uniform(np.log(0.5), np.log(50.0))))
        if analog_y:
            y = y + 10 ** (-snr_y / 20) * y.std(axis=0) * pink_corner(T, n, dt, fc, rng)
        if analog_u:
            u = u + np.where(forced, 10 ** (-snr_u / 20) * u.std(axis=0), 0.0) * pink_corner(T, n, dt, fc, rng)
        fresh["pink"] = {"corner_hz": fc}
    if rng.uniform() < 0.3 and analog_u and forced.any():
        share = float(rng.uniform(0.01, 0.1))
        shape = str(rng.choice(["linear", "random_walk"]))
        if shape == "linear":
            d = np.linspace(0.0, 1.0, T)[:, None] * rng.choice([-1.0, 1.0], n)
        else:
            d = np.cumsum(rng.standard_normal((T, n)), axis=0)
            d /= np.max(np.abs(d), axis=0)
        u = u + np.where(forced, share * np.sqrt(np.mean(u**2, axis=0)), 0.0) * d
        fresh["drift"] = {"shape": shape, "of_force_rms": share}
    if rng.uniform() < 0.3 and channels():
        family = str(rng.choice(["cheby1", "ellip", "bessel"]))
        order, fc = int(rng.integers(2, 9)), float(rng.uniform(0.25, 0.45))
        info = {"family": family, "order": order, "cutoff_of_fs": fc}
        if family == "cheby1":
            info["ripple_db"] = float(rng.uniform(0.5, 3.0))
            sos = cheby1(order, info["ripple_db"], 2 * fc, output="sos")
        elif family == "ellip":
            info["ripple_db"], info["stop_db"] = float(rng.uniform(0.5, 2.0)), float(rng.uniform(40.0, 80.0))
            sos = ellip(order, info["ripple_db"], info["stop_db"], 2 * fc, output="sos")
        else:
            sos = bessel(order, 2 * fc, output="sos", norm="phase")
        apply(lambda x: sosfilt(sos, x, axis=0))
        fresh["antialias"] = info
    if rng.uniform() < 0.3 and len(channels()) > 1:
        chans = channels()
        order = rng.permutation(len(chans))
        for k, (which, i) in zip(order, chans):
            delay = k * dt / len(chans)
            if which == "u":
                u[:, i] = _skewed(u[:, i : i + 1], dt, delay)[:, 0]
            else:
                y[:, i] = _skewed(y[:, i : i + 1], dt, delay)[:, 0]
        fresh["skew"] = {
            "channels": len(chans),
            "delays_of_dt": {f"{w}{i + 1}": int(k) / len(chans) for k, (w, i) in zip(order, chans)},
        }
    if rng.uniform() < 0.3 and channels():
        scales = {}
        for which, i in channels():
            x = u if which == "u" else y
            g = float(rng.uniform(1.2, 4.0))
            step = 2.0 * g * float(np.max(np.abs(x[:, i]))) / 2**16
            x[:, i] = np.round(x[:, i] / step) * step
            scales[f"{which}{i + 1}"] = g
        fresh["adc16"] = {"full_scale_of_peak": scales}
    if rng.uniform() < 0.3 and channels():
        R = int(rng.integers(2, 9))
        info = {"factor": R}
        h = _decimation_filter(R, str(rng.choice(["fir", "cic"])), np.random.default_rng([seed, 35, 1]), info)
        apply(lambda x: _decimated(x, R, h))
        fresh["decimation"] = info
    if rng.uniform() < 0.3 and kind == "displacement":
        ratio = float(np.exp(rng.uniform(np.log(300.0), np.log(8000.0))))
        step = float(np.sqrt(np.mean((y - y.mean(axis=0)) ** 2))) / ratio
        y = np.round(y / step) * step
        fresh["encoder"] = {"motion_rms_over_step": ratio, "step_m": step}
    lab = dict(lab, fresh=fresh)
    field = {"acceleration": "a", "velocity": "v", "displacement": "x"}[kind]
    return Recording(t=rec.t, u=u, **{field: y}), lab


# ------------------------------------------------------------------------------ stages


def generate(seed: int, work: Path, fresh: bool = False) -> None:
    rec_path = work / "recordings" / f"case{seed:05d}.npz"
    lab_path = work / "labels" / f"case{seed:05d}.json"
    if rec_path.exists() and lab_path.exists():
        return
    rec, lab = draw(seed, fresh)
    rec_path.parent.mkdir(parents=True, exist_ok=True)
    lab_path.parent.mkdir(parents=True, exist_ok=True)
    save_recording(rec_path, rec)
    lab_path.write_text(json.dumps(lab, indent=1))


def score(lab: dict, res: dict) -> dict:
    row = B.score_case(lab, res)
    row["rig"] = lab["rig"]
    model = res.get("model") or {}
    row["model"] = model.get("verdict")
    row["none_on_inadmissible"] = bool(res["effect"] == "none" and not model.get("admissible", True))
    if "fresh" in lab:
        row["fresh"] = sorted(lab["fresh"])
    return row


SPLIT_KEYS = (
    "cases",
    "top1_accuracy",
    "location_accuracy_among_correct",
    "param_within_20pct_among_correct",
    "median_gap_shrink_real",
    "false_alarm_rate_none",
)


def _split(rows: list[dict]) -> dict:
    s = B.summarize(rows)
    out = {k: s[k] for k in SPLIT_KEYS}
    real = [r for r in rows if r["truth"] != "none"]
    out["false_none_on_effect"] = float(np.mean([r["pred"] == "none" for r in real])) if real else None
    return out


def summarize(rows: list[dict]) -> dict:
    out = B.summarize(rows)
    real = [r for r in rows if r["truth"] != "none"]
    out["false_none_on_effect"] = float(np.mean([r["pred"] == "none" for r in real])) if real else None
    out["none_on_inadmissible"] = float(np.mean([r["none_on_inadmissible"] for r in rows]))
    out["per_rig"] = {}
    for rig in ("shaker", "axis", "device"):
        rs = [r for r in rows if r["rig"] == rig]
        if rs:
            out["per_rig"][rig] = _split(rs)
    if any("fresh" in r for r in rows):
        out["per_nuisance"] = {}
        for name in FRESH_NUISANCES + ("nothing",):
            rs = [r for r in rows if (name in r["fresh"] if name != "nothing" else not r["fresh"])]
            if rs:
                out["per_nuisance"][name] = _split(rs)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="0:30", help="seed list, e.g. 0:150 or 3,7,11:20 (default: 0:30)")
    ap.add_argument("--work", type=Path, default=Path("/tmp/algid-realistic"))
    ap.add_argument("--stage", choices=("all", "generate", "diagnose", "score"), default="all")
    ap.add_argument(
        "--fresh",
        action="store_true",
        help="add the fresh acquisition nuisances (module docstring); use a WORK of its own",
    )
    ap.add_argument(
        "--results",
        type=Path,
        default=None,
        help="summary JSON (and its PNG beside it); default WORK/realistic_blind.json, "
        "the published one is bench/results/realistic_blind.json",
    )
    args = ap.parse_args(argv)
    seeds = B._parse_seeds(args.seeds)
    work = args.work
    if args.results is None:
        args.results = work / "realistic_blind.json"
    if args.stage in ("all", "generate"):
        for k, seed in enumerate(seeds):
            t0 = time.perf_counter()
            generate(seed, work, args.fresh)
            print(
                f"[generate {k + 1}/{len(seeds)}] seed {seed} ({time.perf_counter() - t0:.1f} s)",
                file=sys.stderr,
                flush=True,
            )
    if args.stage in ("all", "diagnose"):
        for k, seed in enumerate(seeds):
            out = work / "diagnoses" / f"case{seed:05d}.json"
            lab = json.loads((work / "labels" / f"case{seed:05d}.json").read_text())
            res = B.diagnose_case(seed, work, lab["boundary"])
            out.write_text(json.dumps(res, indent=1))
            print(
                f"[diagnose {k + 1}/{len(seeds)}] seed {seed} {lab['rig']}: {lab['effect']} -> {res['effect']} "
                f"({res['_wall_s']:.1f} s)",
                file=sys.stderr,
                flush=True,
            )
    if args.stage in ("all", "score"):
        rows = B.score_all(work, seeds, score)
        summary = summarize(rows)
        print(B.confusion_table(summary["confusion"]))
        for key in SPLIT_KEYS + ("false_none_on_effect", "none_on_inadmissible", "wall_s_median", "wall_s_max"):
            print(f"{key:36s} {summary[key]}")
        for rig, s in summary["per_rig"].items():
            print(f"{rig:8s} {s}")
        for name, s in summary.get("per_nuisance", {}).items():
            print(f"{name:10s} {s}")
        args.results.parent.mkdir(parents=True, exist_ok=True)
        args.results.write_text(
            json.dumps({"seeds": args.seeds, "fresh": args.fresh, "summary": summary, "cases": rows}, indent=1)
        )
        B.confusion_png(
            summary["confusion"],
            args.results.with_suffix(".png"),
            f"realistic blind diagnosis, seeds {args.seeds}: top-1 {summary['top1_accuracy']:.0%}",
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
