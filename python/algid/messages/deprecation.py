"""Deprecated names: the old spellings keep working for a while and say, with a
``DeprecationWarning``, which name replaced them."""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
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


#: Modules that moved when the package was arranged in rooms (issue 38), by their old name;
#: the old name imports the new module, once with a ``DeprecationWarning`` (remove in 0.3).
MOVED_MODULES = {
    "algid.chain": "algid.model.chain",
    "algid.modal": "algid.model.modal",
    "algid.frf": "algid.model.frf",
    **{
        f"algid.{name}": f"algid.control.{name}"
        for name in (
            "controller",
            "control_law",
            "controller_log",
            "estimate_gate",
            "held_input",
            "trajectories",
            "positioning",
            "demo",
        )
    },
    "algid.scenarios": "algid.simulator.scenarios",
    "algid.noise": "algid.recording.noise",
    "algid.continuous": "algid.estimator.continuous",
    "algid.reference": "algid.estimator.reference",
    "algid.display": "algid.messages.display",
    "algid.progress": "algid.messages.progress",
    "algid.deprecation": "algid.messages.deprecation",
}


class MovedModules(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """``import algid.chain`` and ``from algid.chain import Chain`` give the moved module
    (``algid.model.chain``) with a ``DeprecationWarning`` naming its new place."""

    def find_spec(self, fullname, path=None, target=None):
        if fullname not in MOVED_MODULES:
            return None
        return importlib.machinery.ModuleSpec(fullname, self)

    def create_module(self, spec):
        new = MOVED_MODULES[spec.name]
        # stacklevel 2 is the importing line: warnings skips the frames of importlib
        warnings.warn(f"module {spec.name} is deprecated, use {new}", DeprecationWarning, stacklevel=2)
        module = importlib.import_module(new)
        self.spec_of = getattr(self, "spec_of", {})
        self.spec_of[new] = module.__spec__
        return module

    def exec_module(self, module) -> None:
        """Nothing to run (the new module is imported); give it back its own ``__spec__``,
        which the import system set to the old name's."""
        module.__spec__ = self.spec_of[module.__name__]


def install_moved_modules() -> None:
    """Make the old module names importable (once per process)."""
    if not any(isinstance(finder, MovedModules) for finder in sys.meta_path):
        sys.meta_path.append(MovedModules())


def moved_module(old: str):
    """The module ``old`` moved to, with a ``DeprecationWarning`` pointed at the caller's
    caller (``algid.chain.Chain`` written as an attribute); None if ``old`` did not move."""
    new = MOVED_MODULES.get(old)
    if new is None:
        return None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        module = importlib.import_module(old)
    warn_renamed(f"module {old}", new, stacklevel=4)
    return module
