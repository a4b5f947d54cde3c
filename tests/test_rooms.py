"""The package in rooms (issue 38): few modules at the top, the library never imports its
command line or the tests' oracle, and every moved module still imports by its old name, with
a DeprecationWarning naming the new one."""

import ast
import importlib
import sys
from pathlib import Path

import pytest

import algid
from algid.messages.deprecation import MOVED_MODULES

PACKAGE = Path(algid.__file__).parent


def top_level() -> list[str]:
    """Modules and packages at the top of ``algid``: ``*.py`` but ``__init__``/``__main__``,
    and folders with an ``__init__.py`` (the compiled ``_core*`` extensions are not counted)."""
    modules = [p.stem for p in PACKAGE.glob("*.py") if p.stem not in ("__init__", "__main__")]
    packages = [p.name for p in PACKAGE.iterdir() if (p / "__init__.py").is_file()]
    return sorted(modules + packages)


def imported_modules(path: Path) -> set[str]:
    """Absolute names of the modules a file of the library imports (relative ones resolved)."""
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    package = parts[:-1]
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = package[: len(package) - node.level + 1] if node.level else []
            module = ".".join(base + ([node.module] if node.module else []))
            out.add(module)
            out.update(f"{module}.{alias.name}" for alias in node.names)
    return out


def test_at_most_twelve_modules_at_the_top():
    assert len(top_level()) <= 12, top_level()


@pytest.mark.parametrize("forbidden", ["algid.cli", "algid.estimator.reference", "algid.estimator.network_reference"])
def test_the_library_never_imports_the_command_line_or_the_oracle(forbidden):
    # the oracles: the chain's, and the networks' (which builds on the chain's quadrature)
    oracles = {"estimator/reference.py", "estimator/network_reference.py"}
    allowed = {"cli.py"} if forbidden == "algid.cli" else oracles
    offenders = [
        str(p.relative_to(PACKAGE))
        for p in PACKAGE.rglob("*.py")
        if str(p.relative_to(PACKAGE)) not in allowed and forbidden in imported_modules(p)
    ]
    assert offenders == []


@pytest.mark.parametrize("old", sorted(MOVED_MODULES))
def test_an_old_module_name_imports_the_new_module_with_a_warning(old):
    new = MOVED_MODULES[old]
    sys.modules.pop(old, None)  # the alias of an earlier import, not the module itself
    with pytest.warns(DeprecationWarning, match=f"{old} is deprecated, use {new}"):
        module = importlib.import_module(old)
    assert module is importlib.import_module(new)
    assert module.__spec__.name == new  # the alias leaves the module's own spec alone


def test_an_old_module_name_as_an_attribute_warns():
    name = "chain"
    vars(algid).pop(name, None)
    with pytest.warns(DeprecationWarning, match="algid.chain is deprecated, use algid.model.chain"):
        assert algid.chain.Chain is algid.Chain
