"""The documentation site builds with warnings as errors (mkdocs build --strict: every page in the
nav exists, every link and anchor resolves), and its API reference is written from the docstrings."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def test_the_docs_build_without_warnings(tmp_path):
    env = dict(os.environ, PYTHONPATH=str(REPO))
    proc = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-d", str(tmp_path / "site")],
                          cwd=REPO, env=env, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "WARNING" not in proc.stderr, proc.stderr
    api = re.sub(r"<[^>]+>", " ", (tmp_path / "site" / "api" / "index.html").read_text())
    for text in ("Identify the motor parameters of a data set", "double underscore", "to_motulator",
                 "Write an identification to a MATLAB"):
        assert text in api, text
    # the docstrings' Sphinx roles render as code, not as ":func:" before it
    assert not re.search(r":(func|class|meth|mod|data|attr):", api), \
        re.findall(r".{40}:(?:func|class|meth|mod):.{40}", api)
