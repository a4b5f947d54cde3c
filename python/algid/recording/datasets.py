"""The measured data sets the project checks itself on, as the project keeps them (one ``.npz``
per record with a ``PROVENANCE.md``, in ``../shared/data`` beside a checkout): Silverbox (an
electronic Duffing oscillator) and the F-16 ground vibration test with one shaker, read into
:class:`~algid.recording.Recording` s. Used by ``bench/real_data_diagnosis.py``, the how-tos
(``docs/howto/``) and the tests on measured data.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .core import Recording

#: The band [Hz] around the F-16's wing-torsion mode of :func:`f16_modal_recording`.
F16_BAND_HZ = (6.5, 8.2)


def silverbox_recording(data: Path, part: str = "all") -> Recording:
    """Silverbox SNLS80mV as a recording: u1 = V1 [V], x1 = V2 [V] (volt units)."""
    z = np.load(data / "silverbox" / "SNLS80mV.npz")
    fs = float(z["fs"])
    u, y = z["V1_input_V"].astype(float), z["V2_output_V"].astype(float)
    sl = {"arrow": slice(0, 40000), "multisine": slice(40000, None), "all": slice(None)}[part]
    u, y = u[sl], y[sl]
    return Recording(t=np.arange(u.size) / fs, u=u, x=y, units={"force": "V", "displacement": "V"})


def f16_arrays(data: Path, level: int, kind: str = "FullMSine") -> tuple[np.ndarray, np.ndarray, float]:
    path = next((data / "f16_gvt").glob(f"{kind}_Level{level}*.npz"))
    z = np.load(path)
    return z["force_N"].astype(float), z["acc"].astype(float), float(z["fs"])


def f16_chain_recording(data: Path, level: int) -> Recording:
    """3-DOF chain [shaker point, wing side, payload side]; force on DOF 1 only."""
    F, acc, fs = f16_arrays(data, level)
    u = np.zeros_like(acc)
    u[:, 0] = F
    return Recording(t=np.arange(F.size) / fs, u=u, a=acc)


def f16_modal_recording(data: Path, level: int, channel: int = 1) -> Recording:
    """Wing-side acceleration and force band-passed around the torsion mode (1 DOF)."""
    from scipy.signal import butter, sosfiltfilt

    F, acc, fs = f16_arrays(data, level)
    sos = butter(4, F16_BAND_HZ, btype="bandpass", fs=fs, output="sos")
    return Recording(t=np.arange(F.size) / fs, u=sosfiltfilt(sos, F), a=sosfiltfilt(sos, acc[:, channel]))
