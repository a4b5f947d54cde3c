"""The noise model of a recording (algid.recording.noise): floors, band, encoder resolution, against
signals whose spectra are known in closed form."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import butter, sosfilt

from algid.recording.noise import analyse, channel, encoder_quantum

FS = 1000.0
DT = 1.0 / FS


def _band_limited(T, f_hz, rng, rms=1.0):
    sos = butter(6, f_hz, fs=FS, output="sos")
    x = sosfilt(sos, rng.standard_normal(T))
    return rms * x / np.std(x)


def test_white_floor_gives_the_noise_standard_deviation():
    rng = np.random.default_rng(0)
    for sigma in (1e-3, 0.2, 5.0):
        ch = channel("a1", _band_limited(20000, 30.0, rng) + sigma * rng.standard_normal(20000), DT)
        assert ch.sigma == pytest.approx(sigma, rel=0.1)


def test_band_edge_and_median_frequency_of_a_band_limited_signal():
    rng = np.random.default_rng(1)
    x = _band_limited(40000, 40.0, rng) + 1e-4 * rng.standard_normal(40000)
    ch = channel("u1", x, DT)
    assert 35.0 < ch.f_hi < 60.0  # 99 % of a 6th-order 40 Hz low-pass's power
    assert 10.0 < ch.f_mid < 30.0  # flat to 40 Hz: half the power below ~20 Hz
    assert ch.snr_db > 50.0


def test_a_pure_noise_channel_has_no_band():
    ch = channel("a1", np.random.default_rng(2).standard_normal(8192), DT)
    assert np.isnan(ch.f_hi) and np.isnan(ch.snr_db)


def test_encoder_quantum_detected_and_analogue_readings_rejected():
    rng = np.random.default_rng(3)
    x = np.cumsum(rng.standard_normal(5000)) * 1e-5
    for q in (1e-6, 2.5e-6, 1e-4):
        assert encoder_quantum(q * np.round(x / q)) == pytest.approx(q, rel=1e-9)
    q = 1e-6  # counts stored as float32 metres, as many loggers write them
    stored = (q * np.round(x / q)).astype(np.float32).astype(float)
    assert encoder_quantum(stored) == pytest.approx(q, rel=1e-3)
    assert encoder_quantum(x) == 0.0
    assert encoder_quantum(np.zeros(100)) == 0.0


def test_quantisation_noise_floor_is_q_over_sqrt_12():
    rng = np.random.default_rng(4)
    q = 1e-6
    x = 0.02 * _band_limited(40000, 2.0, rng)
    ch = channel("x1", q * np.round(x / q), DT, quantised=True)
    assert ch.quantum == pytest.approx(q)
    assert ch.sigma == pytest.approx(q / np.sqrt(12), rel=0.25)


def test_band_of_a_record_from_forces_only_when_accelerations_are_derived():
    rng = np.random.default_rng(5)
    T = 20000
    u = _band_limited(T, 20.0, rng)[:, None]
    x = np.cumsum(np.cumsum(u[:, 0])) * DT * DT
    q = 1e-7
    nm = analyse(u, (q * np.round(x / q))[:, None], DT, "displacement")
    assert nm.band_source == "u1" and nm.f_hi < 40.0
    assert nm.quantised
    a_noisy = u + 0.01 * rng.standard_normal((T, 1))
    a_noisy[:, 0] += 0.5 * np.sin(2 * np.pi * 120.0 * np.arange(T) * DT)  # a response mode above the force
    nm = analyse(u, a_noisy, DT, "acceleration")
    assert nm.band_source == "a1" and 110.0 < nm.f_hi < 130.0
    with pytest.raises(ValueError, match="kind"):
        analyse(u, u, DT, "jerk")
