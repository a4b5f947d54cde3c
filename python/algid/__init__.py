"""algid: on-line algebraic identification of vibrating mass-spring-damper chains."""

from .estimator import ISA, SIZES, ChainConfig, ChainEstimator, Status
from .estimator.continuous import ChangeEvent, ContinuousConfig, ContinuousEstimator
from .fleet import batch
from .identification import Identification, identify
from .messages.deprecation import install_moved_modules, moved_module
from .model.chain import TABLE1, Chain
from .model.network import Network, NetworkModel
from .recording import Recording, as_recording, load_recording
from .recording.frf_file import FrfData, load_frf

install_moved_modules()

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
    "Network",
    "NetworkModel",
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


def __getattr__(name: str):
    """A moved module by its old name (``algid.chain``), with a ``DeprecationWarning``."""
    module = moved_module(f"algid.{name}")
    if module is None:
        raise AttributeError(f"module 'algid' has no attribute {name!r}")
    return module
