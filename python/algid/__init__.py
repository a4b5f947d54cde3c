"""algid: on-line algebraic identification of vibrating mass-spring-damper chains."""

from .chain import TABLE1, Chain
from .continuous import ChangeEvent, ContinuousConfig, ContinuousEstimator
from .estimator import ISA, SIZES, ChainConfig, ChainEstimator, Status
from .fleet import batch
from .identification import Identification, identify
from .recording import Recording, as_recording, load_recording
from .recording.frf_file import FrfData, load_frf

__all__ = [
    "Chain",
    "ChainConfig",
    "ChainEstimator",
    "ChangeEvent",
    "ContinuousConfig",
    "ContinuousEstimator",
    "FrfData",
    "ISA",
    "Identification",
    "Recording",
    "SIZES",
    "Status",
    "TABLE1",
    "as_recording",
    "batch",
    "get_include",
    "identify",
    "load_frf",
    "load_recording",
]
__version__ = "0.1.0"


def get_include() -> str:
    """Directory of the C++ headers shipped in the wheel (``#include <algid/algid.hpp>``)."""
    from pathlib import Path

    return str(Path(__file__).parent / "include")
