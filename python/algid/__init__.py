"""algid: on-line algebraic identification of vibrating mass-spring-damper chains."""

from .chain import TABLE1, Chain

__all__ = ["Chain", "TABLE1"]
__version__ = "0.1.0"
