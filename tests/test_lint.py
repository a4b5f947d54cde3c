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
