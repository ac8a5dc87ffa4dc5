"""Every Python block of the READMEs runs as pasted, from the repository's
root (where the README's commands are typed), with no warning."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import warnings

import pytest

from conftest import REPO

READMES = [REPO / "README.md", REPO / "crates" / "softrod-py" / "README.md"]


def python_blocks():
    for path in READMES:
        text = path.read_text(encoding="utf-8")
        for match in re.finditer(r"^```python\n(.*?)^```$", text, re.S | re.M):
            line = text.count("\n", 0, match.start()) + 2
            yield pytest.param(match.group(1), id=f"{path.relative_to(REPO)}:{line}")


BLOCKS = list(python_blocks())


def test_every_readme_has_its_python_block():
    assert len(BLOCKS) >= len(READMES)


@pytest.mark.parametrize("code", BLOCKS)
def test_readme_block_runs_as_pasted(code, capsys):
    cwd = os.getcwd()
    os.chdir(REPO)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            exec(compile(code, "README", "exec"), {"__name__": "__readme__"})
    finally:
        os.chdir(cwd)


def test_the_matplotlib_example_says_in_one_line_what_it_needs(tmp_path):
    """matplotlib is an extra: without it the example fails with one clear
    line, not a traceback (the import is hidden from a fresh interpreter)."""
    script = REPO / "examples" / "python" / "cantilever.py"
    hide = ("import runpy, sys; sys.modules['matplotlib'] = None; "
            "sys.argv = [sys.argv[1], '--out', sys.argv[2]]; "
            "runpy.run_path(sys.argv[0], run_name='__main__')")
    r = subprocess.run([sys.executable, "-c", hide, str(script), str(tmp_path)],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 1, r
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "pip install matplotlib" in lines[0], r.stderr
    assert list(tmp_path.iterdir()) == []
