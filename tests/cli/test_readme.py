"""Every fenced command of the README and of docs/ runs as written, from a temporary folder
(tests/cli/readme_commands.py); the long ones say so, and the README stays a short user guide."""

from __future__ import annotations

from tests.cli.readme_commands import REPO, SKIP, commands, documents, python_blocks, quick, run_all


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


def test_every_quick_fenced_command_runs():
    lines = []
    failures = run_all(log=lines.append)
    assert sum(line.startswith("ok") for line in lines) >= 10, lines
    assert not failures, "\n".join(failures)
