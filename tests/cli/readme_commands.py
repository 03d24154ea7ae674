"""Every fenced command of the README and of docs/ runs as written.

The ```bash blocks of each file are read in order and each command is run with bash in a fresh
temporary folder per file, as a user who cloned the repository would type them there (the folder
holds a copy of ``examples/`` and ``plugins/genesis_example/``, which the commands name; later
commands read what earlier ones wrote). The README's ```python blocks run as scripts in that
folder too. Skipped, and said so here: commands whose comment says they take minutes (marked
``(minutes)``), the installs (CI runs exactly those: .ci/run), and SLURM (no cluster here). A
command already run from an earlier file is not run again.

``tests/cli/test_readme.py`` runs the quick ones in the test suite; ``python -m
tests.cli.readme_commands`` runs them by hand and prints each.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SKIP = ("(minutes)", "pip install", "imbench_slurm", "hydra/launcher=submitit")
#: What a command may name that the repository holds (copied into the temporary folder).
SHIPPED = ("examples", "plugins/genesis_example")


def documents() -> list[Path]:
    """The README, then every page of docs/."""
    return [REPO / "README.md", *sorted((REPO / "docs").rglob("*.md"))]


def commands(path: Path) -> list[str]:
    """The fenced bash commands of one file, in order (a line continued with a backslash joined)."""
    out = []
    for block in re.findall(r"```bash\n(.*?)```", path.read_text(encoding="utf-8"), flags=re.S):
        for line in re.sub(r"\\\n\s*", " ", block).splitlines():
            line = line.strip()
            if line and not line.startswith("#"):
                out.append(line)
    return out


def python_blocks(path: Path) -> list[str]:
    """The fenced Python snippets of a file that use the API (not the plugin/effect templates)."""
    return [b for b in re.findall(r"```python\n(.*?)```", path.read_text(encoding="utf-8"), flags=re.S)
            if b.lstrip().startswith("from benchmark import api")]


def bare(cmd: str) -> str:
    """The command without its trailing comment (the same command in two files runs once)."""
    return re.sub(r"\s+#.*$", "", cmd)


def quick(cmd: str) -> bool:
    return not any(s in cmd for s in SKIP)


def printed_tables(path: Path) -> list[dict[str, float]]:
    """The identification tables a file shows as printed (plain fenced blocks that start with
    the ``parameter unit`` header), each as parameter -> estimate."""
    blocks = re.findall(r"```\n(parameter unit.*?)```", path.read_text(encoding="utf-8"), flags=re.S)
    return [estimates(b) for b in blocks]


def estimates(text: str) -> dict[str, float]:
    """parameter -> estimate of the table printed in ``text`` (its rows after the header)."""
    header = text.index("parameter unit")
    rows = re.findall(r"^(Rs|Ls|Le|Rr|J|fv|fc)\s+.+?\s+([-+0-9.e]+)\s+\S+\s+\S+\s+\S+$", text[header:], flags=re.M)
    return {name: float(value) for name, value in rows}


def run_file(path: Path, seen: set[str], log=print, outputs: dict | None = None) -> list[str]:
    """Run the quick commands and API snippets of one file in a fresh temporary folder; returns
    the failures (file, command, exit status, end of stderr). ``outputs``: command -> its
    standard output, filled in."""
    env = dict(os.environ, PYTHONPATH=str(REPO), MPLBACKEND="Agg", NUMBA_NUM_THREADS="1")
    failures = []
    with tempfile.TemporaryDirectory(prefix="imbench-docs-") as tmp:
        for item in SHIPPED:
            shutil.copytree(REPO / item, Path(tmp) / item)
        jobs = [(bare(c), ["bash", "-c", c]) for c in commands(path) if quick(c) and bare(c) not in seen]
        for k, block in enumerate(python_blocks(path)):
            script = Path(tmp) / f"snippet_{k}.py"
            script.write_text(block, encoding="utf-8")
            jobs.append((f"python snippet {k + 1}", [sys.executable, str(script)]))
        for label, argv in jobs:
            seen.add(label)
            proc = subprocess.run(argv, cwd=tmp, env=env, capture_output=True, text=True, timeout=1800)
            if outputs is not None:
                outputs[label] = proc.stdout
            log(f"{'ok   ' if proc.returncode == 0 else 'FAIL '} {path.relative_to(REPO)}: {label}")
            if proc.returncode != 0:
                failures.append(f"{path.relative_to(REPO)}: {label}\n  exit {proc.returncode}: "
                                f"{proc.stderr.strip()[-800:]}")
    return failures


def run_all(log=print, outputs: dict | None = None) -> list[str]:
    """Every file's quick commands, two files at a time (each command on one numba thread);
    ``outputs`` (command -> standard output) filled in."""
    seen: set[str] = set()
    files = documents()
    # the README first: the docs repeat some of its commands, which then run once
    first = run_file(files[0], seen, log, outputs)
    with ThreadPoolExecutor(max_workers=2) as pool:
        rest = pool.map(lambda f: run_file(f, seen, log, outputs), files[1:])
        return first + [f for failures in rest for f in failures]


if __name__ == "__main__":
    bad = run_all()
    print("\n".join(bad) if bad else "every quick fenced command ran")
    raise SystemExit(1 if bad else 0)
