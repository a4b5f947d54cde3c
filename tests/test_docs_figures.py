"""The docs' measured figures match bench/results: tools/figures.py rebuilds every generated
block in memory from the result files and compares it with the pages."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_generated_figures_match_the_results():
    out = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "figures.py")], capture_output=True, text=True, timeout=60
    )
    assert out.returncode == 0, out.stdout + out.stderr


def test_the_check_fails_on_a_stale_page():
    page = ROOT / "docs" / "demo.md"
    text = page.read_text()
    assert "<!-- figures:demo-runs -->" in text
    stale = text.replace("<!-- figures:demo-runs -->\n", "<!-- figures:demo-runs -->\nhand-edited\n", 1)
    code = (
        "import importlib.util, sys\n"
        f"s = importlib.util.spec_from_file_location('figures', {str(ROOT / 'tools' / 'figures.py')!r})\n"
        "f = importlib.util.module_from_spec(s); s.loader.exec_module(f)\n"
        "text = sys.stdin.read()\n"
        "print('same' if f.fill(text, 'docs/demo.md') == text else 'differs')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], input=stale, capture_output=True, text=True, timeout=60)
    assert out.stdout.strip() == "differs", out.stderr
