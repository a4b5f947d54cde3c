"""The ``batch`` extra: dask[distributed], pyarrow, pandas and tqdm, imported on first use."""

from __future__ import annotations

#: What to install when they are missing.
EXTRA = "pip install 'algid[batch]'"


class BatchDependencyError(ImportError):
    """The batch extra is not installed; ``str(err)`` is one line naming it."""


def require() -> None:
    """Import the batch extra's packages, or raise :class:`BatchDependencyError` naming it."""
    try:
        import distributed  # noqa: F401
        import pandas  # noqa: F401
        import pyarrow.parquet  # noqa: F401
        import tqdm  # noqa: F401
    except ImportError as err:
        raise BatchDependencyError(
            f"batch needs dask[distributed], pyarrow, pandas and tqdm ({err.name or 'a package'} is missing): {EXTRA}"
        ) from None
