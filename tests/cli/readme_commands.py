"""Every fenced command of the README runs as written: ``python -m tests.cli.readme_commands``.

The README's ```bash blocks are read in order and each command is run with bash in the
repository (what it writes, outputs/, data/, bench/, runs/, is git-ignored), in the order a
newcomer would type them, since later commands read what earlier ones wrote. It takes several
minutes (identifications and diagnoses), so it is a script run before a release, not part of the
test suite. Skipped, and said so here: commands whose comment says they take minutes (marked
``(minutes)`` in the README),
the two installs (CI runs exactly those, .ci/run), and SLURM (no cluster here).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SKIP = ("(minutes)", "pip install", "imbench_slurm", "hydra/launcher=submitit")


def readme_commands() -> list[str]:
    text = (REPO / "README.md").read_text(encoding="utf-8")
    commands = []
    for block in re.findall(r"```bash\n(.*?)```", text, flags=re.S):
        joined = re.sub(r"\\\n\s*", " ", block)
        for line in joined.splitlines():
            line = line.strip()
            if line and not line.startswith("#"):
                commands.append(line)
    return commands


def run_all() -> list[str]:
    """Run every quick README command in order; returns the failures (command, exit, stderr)."""
    made = [d for d in ("data", "bench", "runs") if not (REPO / d).exists()]
    env = dict(os.environ, PYTHONPATH=str(REPO))
    failures = []
    try:
        for cmd in readme_commands():
            if any(s in cmd for s in SKIP):
                print(f"skip  {cmd}", flush=True)
                continue
            proc = subprocess.run(["bash", "-c", cmd], cwd=REPO, env=env, capture_output=True, text=True,
                                  timeout=1800)
            print(f"{'ok   ' if proc.returncode == 0 else 'FAIL '} {cmd}", flush=True)
            if proc.returncode != 0:
                failures.append(f"{cmd}\n  exit {proc.returncode}: {proc.stderr.strip()[-600:]}")
    finally:
        for d in made:
            shutil.rmtree(REPO / d, ignore_errors=True)
    return failures


if __name__ == "__main__":
    bad = run_all()
    print("\n".join(bad) if bad else "every quick README command ran")
    raise SystemExit(1 if bad else 0)
