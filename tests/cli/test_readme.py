"""Every fenced command of the README and of docs/ runs as written, from a temporary folder
(tests/cli/readme_commands.py); the long ones say so, and the README stays a short user guide."""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile

from tests.cli.readme_commands import (
    REPO,
    SKIP,
    commands,
    documents,
    estimates,
    printed_tables,
    python_blocks,
    quick,
    run_all,
)


def test_the_readme_is_a_short_guide_whose_commands_say_which_take_minutes():
    readme = REPO / "README.md"
    assert len(readme.read_text().splitlines()) <= 350
    cmds = [c for f in documents() for c in commands(f)]
    assert len(cmds) >= 15 and any("(minutes)" in c for c in cmds)
    quick_ones = [c for c in cmds if quick(c)]
    assert all(c.startswith(("python -m ", "python examples/", "cp ", "mv ", "mkdir ", "mkdocs ")) for c in quick_ones)
    assert not any(w in c for c in quick_ones for w in (" DIR", "DATE", "TIME", "NAME")), "placeholders left"
    # the two set-up commands: the tests command is what CI runs, verbatim
    assert "python -m pip install -e . && python -m benchmark" in commands(readme)
    test_command = next(c for c in commands(readme) if "pytest" in c)
    assert test_command in (REPO / ".ci" / "run").read_text()
    assert python_blocks(readme) and all(s in SKIP for s in ("(minutes)", "pip install"))


def test_every_quick_fenced_command_runs_and_prints_what_the_readme_shows():
    """... and the README's printed tables are what the main job and the example's identification
    print (estimates within 1e-4: a table pasted under the wrong command is caught)."""
    lines, outputs = [], {}
    failures = run_all(log=lines.append, outputs=outputs)
    assert sum(line.startswith("ok") for line in lines) >= 10, lines
    assert not failures, "\n".join(failures)
    main_job = subprocess.run([sys.executable, "-m", "benchmark", "hydra.run.dir=" + tempfile.mkdtemp()], cwd=REPO,
                              env=dict(os.environ, NUMBA_NUM_THREADS="1"), capture_output=True, text=True, timeout=600)
    printed = [estimates(main_job.stdout), estimates(outputs["python -m benchmark data.path=examples/data/bench_1kw"])]
    shown = printed_tables(REPO / "README.md")
    assert len(shown) == 2 and all(len(t) == 7 for t in shown + printed), (shown, printed)
    for table, run in zip(shown, printed, strict=True):
        assert all(abs(table[k] - run[k]) <= 1e-4 * abs(run[k]) for k in run), (table, run)
