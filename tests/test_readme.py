"""The README's quickstarts run as written.

Every fenced code block preceded by an HTML comment ``<!-- test: cli -->`` or
``<!-- test: python -->`` is executed: CLI blocks line by line through the
shell (each line must exit 0), Python blocks with ``exec``. They run in a
temporary directory holding a link to the repository's ``scenes/``, so the
README's relative paths work and nothing is written into the checkout.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
README = REPO / "README.md"
BLOCK = re.compile(r"<!-- test: (cli|python) -->\s*\n```[a-z]*\n(.*?)```", re.S)


def blocks(kind: str) -> list[str]:
    found = [code for k, code in BLOCK.findall(README.read_text()) if k == kind]
    assert found, f"README.md has no <!-- test: {kind} --> block"
    return found


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    (tmp_path / "scenes").symlink_to(REPO / "scenes")
    (tmp_path / "out").mkdir()
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_readme_has_exactly_two_setup_commands():
    text = README.read_text()
    setup = text.split("## Set-up", 1)[1].split("\n## ", 1)[0]
    commands = re.findall(r"```sh\n(.*?)```", setup, re.S)
    assert [c.strip() for c in commands] == ["bash scripts/demo.sh", "bash scripts/test.sh"]


def test_readme_cli_quickstart_runs(workdir):
    env = dict(os.environ)
    env["PATH"] = str(Path(sys.executable).parent) + os.pathsep + env["PATH"]
    assert shutil.which("fgf", path=env["PATH"]), "the fgf command is not installed"
    for block in blocks("cli"):
        for line in block.strip().splitlines():
            if not line.strip() or line.lstrip().startswith("#"):
                continue
            r = subprocess.run(line, shell=True, env=env, capture_output=True, text=True, timeout=600)
            assert r.returncode == 0, f"{line!r} failed ({r.returncode}):\n{r.stderr}"
            assert "Traceback" not in r.stderr


def test_readme_python_quickstart_runs(workdir):
    for block in blocks("python"):
        exec(compile(block, "README.md", "exec"), {"__name__": "__readme__"})
