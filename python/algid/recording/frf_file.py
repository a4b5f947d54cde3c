"""Frequency response functions from an analyser: :func:`load_frf` and :class:`FrfData`.

Sources (every failure raises :class:`~.core.RecordingError` with one line naming it):

* ``.npz`` (``numpy.savez``) holding ``frequency_hz`` (F,) [Hz], ``frf`` complex (responses,
  forces, F), ``quantity`` (``"accelerance"``, ``"mobility"`` or ``"receptance"``) and
  optionally ``response_dof`` (responses,), ``force_dof`` (forces,) (1-based; default 1..)
  and ``coherence`` (real, the shape of ``frf``). The array ``frf`` tells it from a time
  recording (``t``, ``u1``, ``a1`` ... columns);
* UFF 58 ``.uff`` / ``.unv`` of function type 4 (frequency response function) with the
  optional extra ``algid[uff]`` (:func:`.uff.read_uff_frf`): one record per response and
  reference pair, nodes in increasing order as DOF 1..n, coherences (function type 6) if any;
* a mapping with the keys of the ``.npz``.

``H[r, q, f]`` is the response of DOF ``response_dof[r]`` per force on DOF ``force_dof[q]``
at ``frequency_hz[f]``: displacement (receptance [m/N]), velocity (mobility [(m/s)/N]) or
acceleration (accelerance [(m/s^2)/N]) per force, in the units ``units`` names (SI unless it
says otherwise).
"""

from __future__ import annotations

import os
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..messages import quote, quote_path
from .core import RecordingError
from .npz import _DAMAGED
from .units import SI_UNITS

#: FRF quantity -> (motion per force, power of ``i w`` that turns a receptance into it).
QUANTITIES = {"receptance": ("displacement", 0), "mobility": ("velocity", 1), "accelerance": ("acceleration", 2)}
#: The keys of an FRF ``.npz``, required ones first.
NPZ_KEYS = ("frequency_hz", "frf", "quantity", "response_dof", "force_dof", "coherence")


@dataclass(frozen=True)
class FrfData:
    """Measured FRFs of a chain (module docstring).

    frequency_hz : (F,) strictly increasing, >= 0 [Hz]; H : (R, Q, F) complex; quantity :
    ``"accelerance"``, ``"mobility"`` or ``"receptance"``; response_dof (R,), force_dof (Q,) :
    1-based DOF, each named once; coherence : (R, Q, F) in [0, 1], or None; units : by role
    (``{"force": "N", "acceleration": "m/s^2"}``); notes : what the reader did; path : the file.
    """

    frequency_hz: np.ndarray
    H: np.ndarray
    quantity: str
    response_dof: np.ndarray
    force_dof: np.ndarray
    coherence: np.ndarray | None = None
    units: dict = field(default_factory=dict)
    notes: tuple = ()
    path: Path | None = None

    def __post_init__(self) -> None:
        where = self.path.name if self.path is not None else "FRF"
        f, H = _frequencies(self.frequency_hz, where), np.asarray(self.H)
        if self.quantity not in QUANTITIES:
            raise RecordingError(f"{where}: unknown quantity {quote(self.quantity)} (expected {', '.join(QUANTITIES)})")
        if H.ndim != 3 or H.shape[2] != f.size:
            raise RecordingError(f"{where}: frf has shape {H.shape}, expected (responses, forces, {f.size})")
        if not np.all(np.isfinite(H)):
            raise RecordingError(f"{where}: frf holds NaN or inf values")
        rdof = _dofs(self.response_dof, H.shape[0], "response_dof", where)
        fdof = _dofs(self.force_dof, H.shape[1], "force_dof", where)
        coh = None if self.coherence is None else np.asarray(self.coherence, dtype=float)
        if coh is not None and coh.shape != H.shape:
            raise RecordingError(f"{where}: coherence has shape {coh.shape}, expected that of frf {H.shape}")
        if coh is not None and not np.all((coh >= 0) & (coh <= 1)):
            raise RecordingError(f"{where}: coherence outside [0, 1] (or NaN)")
        motion = QUANTITIES[self.quantity][0]
        units = {"force": SI_UNITS["force"], motion: SI_UNITS[motion], **dict(self.units)}
        for name, value in (("frequency_hz", f), ("H", H.astype(complex)), ("response_dof", rdof)):
            object.__setattr__(self, name, value)
        object.__setattr__(self, "force_dof", fdof)
        object.__setattr__(self, "coherence", coh)
        object.__setattr__(self, "units", units)

    @property
    def n(self) -> int:
        """Number of DOF: the highest response or force DOF."""
        return int(max(self.response_dof.max(), self.force_dof.max()))

    @property
    def motion(self) -> str:
        """``"displacement"``, ``"velocity"`` or ``"acceleration"`` per force."""
        return QUANTITIES[self.quantity][0]

    @property
    def unit(self) -> str:
        """Label of ``H``: motion unit per force unit."""
        motion = self.units[self.motion]
        return f"({motion})/{self.units['force']}" if "/" in motion else f"{motion}/{self.units['force']}"

    def receptance(self) -> np.ndarray:
        """``H`` divided by ``(i w)^p`` (p = 0, 1, 2 for receptance, mobility, accelerance):
        (R, Q, F) displacement per force; NaN at 0 Hz for a mobility or accelerance."""
        power = QUANTITIES[self.quantity][1]
        with np.errstate(divide="ignore", invalid="ignore"):
            return self.H / (2j * np.pi * self.frequency_hz) ** power


def _frequencies(f, where: str) -> np.ndarray:
    try:
        f = np.asarray(f, dtype=float)
    except (TypeError, ValueError):
        raise RecordingError(f"{where}: frequency_hz is not numeric") from None
    if f.ndim != 1 or f.size < 2:
        raise RecordingError(f"{where}: frequency_hz has shape {f.shape}, expected (F,) with F >= 2")
    if not np.all(np.isfinite(f)) or f[0] < 0:
        raise RecordingError(f"{where}: frequency_hz must be finite and >= 0")
    if np.any(np.diff(f) <= 0):
        k = int(np.flatnonzero(np.diff(f) <= 0)[0])
        raise RecordingError(
            f"{where}: frequency_hz is not strictly increasing (line {k + 2}: {f[k + 1]:.6g} Hz after {f[k]:.6g} Hz)"
        )
    return f


def _dofs(dofs, count: int, name: str, where: str) -> np.ndarray:
    """1-based DOF numbers, ``1..count`` when not given."""
    if dofs is None:
        return np.arange(1, count + 1)
    d = np.asarray(dofs).reshape(-1)
    if d.size != count or d.dtype.kind not in "iuf" or not np.all(d == np.round(d)):
        raise RecordingError(f"{where}: {name} must hold {count} whole DOF numbers, got {quote(d.tolist())}")
    d = d.astype(int)
    if np.any(d < 1) or np.unique(d).size != d.size:
        raise RecordingError(f"{where}: {name} must name distinct DOF >= 1 (1-based), got {quote(d.tolist())}")
    return d


def is_frf_source(source) -> bool:
    """True for :class:`FrfData`, a mapping with ``frf``, an ``.npz`` holding an array ``frf``,
    or a UFF file with a frequency response function (function type 4) record."""
    if isinstance(source, FrfData):
        return True
    if isinstance(source, Mapping):
        return "frf" in source
    if not isinstance(source, (str, os.PathLike)):
        return False
    path = Path(source)
    ext = path.suffix.lower()
    if not path.is_file():
        return False
    if ext == ".npz":
        try:
            with zipfile.ZipFile(path) as z:
                return "frf.npy" in z.namelist()
        except (zipfile.BadZipFile, OSError):
            return False  # the time-recording reader says what is wrong with it
    if ext in (".uff", ".unv"):
        from .uff import holds_frf

        return holds_frf(path)
    return False


def load_frf(source) -> FrfData:
    """Read and validate the FRFs of ``source`` (an ``.npz`` or UFF path, a mapping with the
    ``.npz`` keys, or :class:`FrfData` itself); module docstring."""
    if isinstance(source, FrfData):
        return source
    if isinstance(source, Mapping):
        return _from_arrays(dict(source), "FRF", None)
    path = Path(source)
    if not path.is_file():
        raise RecordingError(f"no such file: {quote_path(path)}")
    ext = path.suffix.lower()
    if ext == ".npz":
        return _read_npz(path)
    if ext in (".uff", ".unv"):
        from .uff import read_uff_frf

        return read_uff_frf(path)
    raise RecordingError(f"{path.name}: FRFs are read from .npz, .uff or .unv, not {quote(path.suffix)}")


def _read_npz(path: Path) -> FrfData:
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {key: z[key] for key in z.files}
    except _DAMAGED as err:
        raise RecordingError(f"{path.name}: not a readable .npz file ({type(err).__name__})") from None
    return _from_arrays(arrays, path.name, path)


def _from_arrays(arrays: dict, where: str, path: Path | None) -> FrfData:
    """:class:`FrfData` from the ``.npz`` keys (:data:`NPZ_KEYS`); unknown keys are noted."""
    missing = [key for key in NPZ_KEYS[:3] if key not in arrays]
    if missing:
        raise RecordingError(f"{where}: missing {', '.join(missing)} (an FRF file needs {', '.join(NPZ_KEYS[:3])})")
    H = np.asarray(arrays["frf"])
    if H.dtype.kind not in "fiuc":
        raise RecordingError(f"{where}: frf is not numeric (dtype {H.dtype})")
    quantity = np.asarray(arrays["quantity"])
    if quantity.ndim != 0 or quantity.dtype.kind not in "US":
        raise RecordingError(f"{where}: quantity must be one string ({', '.join(QUANTITIES)})")
    extra = sorted(set(arrays) - set(NPZ_KEYS))
    return FrfData(
        frequency_hz=arrays["frequency_hz"],
        H=H,
        quantity=str(quantity),
        response_dof=arrays.get("response_dof"),
        force_dof=arrays.get("force_dof"),
        coherence=arrays.get("coherence"),
        notes=tuple(f"ignored array {quote(key)}" for key in extra),
        path=path,
    )


def save_frf(path, data: FrfData) -> Path:
    """Write ``data`` as an FRF ``.npz`` that :func:`load_frf` reads back exactly (SI units)."""
    path = Path(path)
    arrays = {
        "frequency_hz": data.frequency_hz,
        "frf": data.H,
        "quantity": np.array(data.quantity),
        "response_dof": data.response_dof,
        "force_dof": data.force_dof,
    }
    if data.coherence is not None:
        arrays["coherence"] = data.coherence
    with open(path, "wb") as fh:  # np.savez would append .npz to other spellings
        np.savez(fh, **arrays)
    return path
