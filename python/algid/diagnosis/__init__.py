"""Sim-to-real gap diagnosis: where the linear chain fails, which unmodelled effect
explains it, and how much of the gap it closes (issue 6)."""

from .candidates import EFFECTS, MAIN_PARAM
from .engine import Diagnosis, diagnose

__all__ = ["EFFECTS", "MAIN_PARAM", "Diagnosis", "diagnose"]
