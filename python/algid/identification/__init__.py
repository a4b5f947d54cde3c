"""Whole-record identification: :func:`identify` chooses the estimator from the recording,
gives every estimate a standard deviation and a verdict (``algid identify``)."""

from .engine import identify
from .plan import Plan
from .result import Identification
from .verdicts import Verdict

__all__ = ["Identification", "Plan", "Verdict", "identify"]
