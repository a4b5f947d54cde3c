"""Deprecated names: the old spellings keep working for a while and say, with a
``DeprecationWarning``, which name replaced them."""

from __future__ import annotations

import warnings


def warn_renamed(old: str, new: str, stacklevel: int = 3) -> None:
    """``DeprecationWarning``: ``old`` is now ``new`` (pointed at the caller's caller)."""
    warnings.warn(f"{old} is deprecated, use {new}", DeprecationWarning, stacklevel=stacklevel)


def renamed_method(old: str, new: str):
    """A method ``old`` that warns and calls the method ``new`` with the same arguments."""

    def alias(self, *args, **kwargs):
        warn_renamed(f"{type(self).__name__}.{old}()", f"{new}()")
        return getattr(self, new)(*args, **kwargs)

    alias.__name__ = alias.__qualname__ = old
    alias.__doc__ = f"Deprecated name of :meth:`{new}` (warns)."
    return alias


class Histories(dict):
    """The histories a ``run()`` returns, by name; a renamed key still answers ``out[old]``
    (not ``get`` or ``in``), with a ``DeprecationWarning`` naming the new key."""

    def __init__(self, data: dict, renamed: dict[str, str]) -> None:
        super().__init__(data)
        self.renamed = dict(renamed)

    def __missing__(self, key):
        new = self.renamed.get(key)
        if new is None:
            raise KeyError(key)
        warn_renamed(f"run()[{key!r}]", f"run()[{new!r}]")
        return self[new]
