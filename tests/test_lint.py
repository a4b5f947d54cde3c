"""The lint configuration holds: ruff (check and format) and clang-format over the tree, as
``.ci/lint`` runs them (the tools are pinned in the ``test`` extra)."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def test_lint_is_clean():
    missing = [tool for tool in ("ruff", "clang-format") if shutil.which(tool) is None]
    if missing:
        pytest.fail(f"{', '.join(missing)} not found: install the test extra (pip install '.[test]')")
    proc = subprocess.run(["bash", str(REPO / ".ci" / "lint")], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-6000:]


def _oversized(path: Path, limits: dict[type, int]) -> list[str]:
    import ast

    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        limit = next((v for k, v in limits.items() if isinstance(node, k)), None)
        length = getattr(node, "end_lineno", 0) - getattr(node, "lineno", 0) + 1
        if limit is not None and length > limit:
            found.append(f"{path.relative_to(REPO)}:{node.lineno} {node.name} ({length} lines > {limit})")
    return found


def test_python_functions_and_classes_fit_a_screenful():
    """No function over 120 lines and no class over 250 outside bench/ (house style)."""
    import ast

    limits = {ast.ClassDef: 250, ast.FunctionDef: 120, ast.AsyncFunctionDef: 120}
    files = [p for folder in ("python", "tests", "examples") for p in sorted((REPO / folder).rglob("*.py"))]
    assert files
    oversized = [line for path in files for line in _oversized(path, limits)]
    assert not oversized, "\n".join(oversized)
