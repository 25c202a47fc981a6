"""Every Python example in the README runs as written (in a fresh
interpreter, in a temporary folder, with matplotlib's Agg backend) and
prints passing results: no "False" and no "FAILED" (the examples print the
verdicts of chi-square and z-tests)."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

README = Path(__file__).resolve().parent.parent / "README.md"
BLOCKS = re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), re.S)


def test_the_readme_has_examples():
    assert len(BLOCKS) >= 4


@pytest.mark.parametrize("index", range(len(BLOCKS)))
def test_readme_example_runs_and_passes(index, tmp_path):
    code = BLOCKS[index]
    if "mitsuba" in code:
        pytest.importorskip("mitsuba", reason="the example uses Mitsuba 3")
    env = dict(os.environ, MPLBACKEND="Agg")
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, f"README example {index} failed:\n{code}\n{out.stderr}"
    assert "False" not in out.stdout and "FAILED" not in out.stdout, (
        f"README example {index} printed a failing result:\n{out.stdout}")
