"""The README's fenced commands are what the runner (``python -m tests.cli.readme_commands``,
several minutes, run before a release) executes: they parse, and the long ones say so."""

from __future__ import annotations

from tests.cli.readme_commands import SKIP, readme_commands


def test_the_readme_has_commands_and_says_which_take_minutes():
    cmds = readme_commands()
    assert len(cmds) >= 15
    assert any("(minutes)" in c for c in cmds)
    quick = [c for c in cmds if not any(s in c for s in SKIP)]
    assert all(c.startswith(("python -m ", "cp ", "mv ", "mkdir ")) for c in quick), quick
    assert not any(w in c for c in quick for w in (" DIR", "DATE", "TIME")), "placeholders left in a command"
