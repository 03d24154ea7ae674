"""Tests of the GENESIS 5.0 clone (plugins/genesis/)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import plugins.genesis as G

REPO = Path(__file__).resolve().parents[2]
VECTORS = Path(__file__).resolve().parent / "genesis_vectors"
# The original program's worked example: its settings (in), genes (template) and the out and min
# files it wrote, for f = x1^2 + x2^2 + x3^2.
EX1 = VECTORS / "ex1"
# Settings that converge (Bias > 0.99) under rank selection: in and template only, the expected
# out lines are derived in test_converged_run_pads_out_with_advancing_generations.
RANK_CONVERGED = VECTORS / "rank_converged"
EXAMPLE = REPO / "plugins" / "genesis_example"


def _copy_inputs(dst: Path, src: Path = EX1) -> Path:
    dst.mkdir(parents=True, exist_ok=True)
    for name in ("in", "template"):
        shutil.copyfile(src / name, dst / name)
        os.chmod(dst / name, 0o644)
    return dst


def _run_cli(*args, cwd=REPO, env_extra=None):
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(REPO)] + ([env_extra] if env_extra else []))
    return subprocess.run(
        [sys.executable, "-m", "plugins.genesis", *map(str, args)],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )


# (1) the worked example, byte for byte ------------------------------------------------------


def test_ex1_api_reproduces_out_and_min(tmp_path):
    d = _copy_inputs(tmp_path / "ex1")
    result = G.run_dir(d)
    assert (d / "out").read_bytes() == (EX1 / "out").read_bytes()
    assert (d / "min").read_bytes() == (EX1 / "min").read_bytes()
    assert result.generations == 20 and result.trials == 1000


def test_ex1_cli_reproduces_out_and_min(tmp_path):
    d = _copy_inputs(tmp_path / "ex1")
    proc = _run_cli(d)
    assert proc.returncode == 0, proc.stderr
    assert (d / "out").read_bytes() == (EX1 / "out").read_bytes()
    assert (d / "min").read_bytes() == (EX1 / "min").read_bytes()


def test_cli_custom_objective(tmp_path):
    d = _copy_inputs(tmp_path / "ex1")
    mod = tmp_path / "objmod"
    mod.mkdir()
    (mod / "my_objective.py").write_text(
        "def sphere(x):\n    s = 0.0\n    for v in x:\n        s += v * v\n    return s\n"
        "def shifted(x):\n    return float(((x - 1.0) ** 2).sum())\n"
    )
    proc = _run_cli(d, "my_objective:sphere", env_extra=str(mod))
    assert proc.returncode == 0, proc.stderr
    assert (d / "out").read_bytes() == (EX1 / "out").read_bytes()
    assert (d / "min").read_bytes() == (EX1 / "min").read_bytes()
    proc = _run_cli(d, "my_objective:shifted", env_extra=str(mod))
    assert proc.returncode == 0, proc.stderr
    assert (d / "out").read_bytes() != (EX1 / "out").read_bytes()


def test_vectors_live_in_the_repository():
    for name in ("in", "template", "out", "min"):
        assert (EX1 / name).is_file()
    for name in ("in", "template"):
        assert (RANK_CONVERGED / name).is_file()
        assert (EXAMPLE / name).is_file()


@pytest.mark.parametrize("form", ["--out-dir", "-o", "--out-dir="])
def test_cli_out_dir_leaves_the_input_folder_alone(tmp_path, form):
    d = _copy_inputs(tmp_path / "ex1")
    dest = tmp_path / "results" / "run1"  # created by the runner
    args = [d, f"--out-dir={dest}"] if form.endswith("=") else [d, form, dest]
    proc = _run_cli(*args)
    assert proc.returncode == 0, proc.stderr
    assert sorted(p.name for p in d.iterdir()) == ["in", "template"]
    assert (dest / "out").read_bytes() == (EX1 / "out").read_bytes()
    assert (dest / "min").read_bytes() == (EX1 / "min").read_bytes()
    summary = proc.stdout.strip().splitlines()
    assert len(summary) == 1
    assert "20 generations, 1000 trials" in summary[0]
    assert str(dest / "out") in summary[0] and str(dest / "min") in summary[0]


def test_run_dir_out_dir_api(tmp_path):
    d = _copy_inputs(tmp_path / "ex1")
    res = G.run_dir(d, out_dir=tmp_path / "o")
    assert res.files == [tmp_path / "o" / "out", tmp_path / "o" / "min"]
    assert (tmp_path / "o" / "out").read_bytes() == (EX1 / "out").read_bytes()
    assert not (d / "out").exists() and not (d / "min").exists()
    res = G.run_dir(d)  # default: next to in, as the original
    assert res.files == [d / "out", d / "min"]
    assert (d / "min").read_bytes() == (EX1 / "min").read_bytes()


def test_cli_usage(tmp_path):
    d = _copy_inputs(tmp_path / "ex1")
    proc = _run_cli("--help")
    assert proc.returncode == 0 and "usage: python -m plugins.genesis DIR" in proc.stdout
    for args in ([d, "--out-dir"], [d, "--bogus"], [d, "a:b", "c:d"], [d, "-o", "x", "-o", "y"], []):
        proc = _run_cli(*args)
        assert proc.returncode == 2 and "Traceback" not in proc.stderr
        assert proc.stderr.startswith("usage:")
    assert sorted(p.name for p in d.iterdir()) == ["in", "template"]
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    proc = _run_cli(d, "-o", blocker / "sub")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert str(blocker / "sub") in proc.stderr and len(proc.stderr.strip().splitlines()) == 1


def test_example_folder_runs(tmp_path):
    """plugins/genesis_example: the README's small run (a fraction of a second)."""
    before = sorted(p.name for p in EXAMPLE.iterdir())
    proc = _run_cli(EXAMPLE, "--out-dir", tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert sorted(p.name for p in EXAMPLE.iterdir()) == before
    settings, _ = G.read_settings(EXAMPLE / "in")
    out = (tmp_path / "out").read_text().splitlines()
    assert out[0].split()[:2] == ["0", str(settings.population_size)]
    assert out[-1].split()[1] == str(settings.total_trials)
    assert len((tmp_path / "min").read_text().splitlines()) == settings.structures_saved
    assert "Total Trials" in proc.stdout


# (1b) termination on convergence: the padding of the out file ------------------------------


def _fields(line):
    gen, trials, *rest = line.split()
    return int(gen), int(trials), rest


def test_converged_run_pads_out_with_advancing_generations(tmp_path):
    """acefglR, Rank Min 0.75, N = 100, Report Interval 1000, 20000 trials (5 genes of 10 bits,
    sum of squares, the default seed) converges with Bias > 0.99 at generation 169.

    Expected out lines, from the original's rules: with option a every generation costs N = 100
    trials (generation g has 100 (g + 1)), so the report points are generation 0 (100 trials)
    and the generations whose trials reach 1000, 2000, ...: 9, 19, ..., 169 (17000 trials), where
    the run is declared converged. The original then pads out with copies of that line whose
    generation advances by Report Interval / N = 10 per line, one per Report Interval missing
    before Total Trials: 179, 189, 199 (the generation at which the run would have ended), all
    with 17000 trials -- the original's documented example of this padding."""
    d = _copy_inputs(tmp_path / "rank_converged", RANK_CONVERGED)
    res = G.run_dir(d)
    assert res.stop_reason == "converged (bias > 0.99) at generation 169"
    assert res.generations == 170 and res.trials == 17000

    lines = (d / "out").read_text().splitlines()
    assert lines == res.out_lines
    parsed = [_fields(line) for line in lines]
    gens = [g for g, _, _ in parsed]
    trials = [t for _, t, _ in parsed]
    assert gens == [0, *range(9, 170, 10), 179, 189, 199]
    assert trials == [100, *range(1000, 17001, 1000), 17000, 17000, 17000]

    converged = lines[-4]
    bias = [float(rest[2]) for _, _, rest in parsed]
    assert bias[-4] > 0.99 and all(b <= 0.99 for b in bias[:-4])  # no earlier stop
    for gen, pad in zip((179, 189, 199), lines[-3:], strict=True):
        assert pad == f"{gen:5d}" + converged[5:]  # only the generation field differs

    for line in (d / "min").read_text().splitlines():
        gen, trial = map(int, line.split()[-2:])
        assert gen <= 169 and trial <= 17000

    # the same through the command line
    proc = _run_cli(d, "-o", tmp_path / "cli")
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "cli" / "out").read_text() == (d / "out").read_text()


@pytest.mark.parametrize(
    "n, interval, total, gap, gen, trials, expected",
    [
        (100, 1000, 20000, 1.0, 169, 17000, [179, 189, 199]),  # the documented example
        (100, 1000, 20000, 1.0, 199, 20000, []),  # converged at the last report: no padding
        (100, 1000, 20500, 1.0, 169, 17000, [179, 189, 199, 209]),  # ceil(3500 / 1000) lines
        (30, 100, 1000, 1.0, 9, 300, [12, 15, 18, 21, 24, 27, 30]),  # step 100 // 30 = 3
        (20, 7, 400, 1.0, 16, 340, list(range(17, 26))),  # step at least 1; ceil(60 / 7) lines
        (100, 1000, 20000, 0.5, 169, 17000, [179, 189, 199]),  # step Interval // N at any gap
    ],
)
def test_padding_rule(n, interval, total, gap, gen, trials, expected):
    s = G.Settings(
        total_trials=total,
        population_size=n,
        structure_length=4,
        report_interval=interval,
        generation_gap=gap,
        options="acl",
    )
    eng = G.Genesis(s, None, G.sum_of_squares)
    eng.gen, eng.trials = gen, trials
    stats = (3, 4, 0.995, 1.5, 0.5, 0.25, 0.75)
    pad = eng._padding(stats)
    assert [_fields(line)[0] for line in pad] == expected
    assert all(line == G.format_out_line(g, trials, *stats) for g, line in zip(expected, pad, strict=True))


# bad input: one line naming the file (and line), status 2, no traceback


def test_cli_bad_input(tmp_path):
    proc = _run_cli(tmp_path / "nowhere")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1

    d = _copy_inputs(tmp_path / "missing_template")
    (d / "template").unlink()
    proc = _run_cli(d)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "template" in proc.stderr and len(proc.stderr.strip().splitlines()) == 1

    d = _copy_inputs(tmp_path / "bad_in")
    lines = (d / "in").read_text().splitlines()
    lines[2] = "   Population Size = fifty"
    (d / "in").write_text("\n".join(lines) + "\n")
    proc = _run_cli(d)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "line 3" in proc.stderr and str(d / "in") in proc.stderr

    d = _copy_inputs(tmp_path / "bad_template")
    text = (d / "template").read_text().replace("values: 1024", "values: 1000", 1)
    (d / "template").write_text(text)
    proc = _run_cli(d)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "line 6" in proc.stderr and "template" in proc.stderr

    d = _copy_inputs(tmp_path / "bad_objective")
    proc = _run_cli(d, "no_such_module_xyz:f")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "no_such_module_xyz" in proc.stderr


def test_unknown_and_irrelevant_options_are_ignored():
    s = G.Settings(total_trials=200, population_size=20, structure_length=8, options="acefgLlOoxyz")
    t = G.Template([G.Gene(-1.0, 1.0, 16), G.Gene(-1.0, 1.0, 16)])
    assert G.Genesis(s, t, G.sum_of_squares).run().trials == 200


# (2) RANDU -----------------------------------------------------------------------------------


def test_randu_first_values():
    r = G.Randu(123456789)
    assert [r.rand() for _ in range(3)] == [0.7746705113383283, 0.13062164053126013, 0.8116952440327436]


def test_randint_range():
    r = G.Randu(123456789)
    draws = [r.randint(3, 7) for _ in range(2000)]
    assert min(draws) == 3 and max(draws) == 7


def test_seed_mapping():
    assert G.seed_to_randu(0) == 123456789
    seeds = [G.seed_to_randu(s) for s in range(-50, 2000)]
    assert all(0 < v < 2**31 and v % 2 == 1 for v in seeds)
    assert len(set(seeds)) == len(seeds)


# (3) Gray decoding ---------------------------------------------------------------------------


def test_gray_decoding():
    n = 6
    for i in range(2**n):
        g = i ^ (i >> 1)
        gbits = np.array([(g >> (n - 1 - k)) & 1 for k in range(n)], dtype=np.uint8)
        b = G.gray_to_binary(gbits)
        assert int("".join(map(str, b))) == int(bin(i)[2:])
    # the original's rule: b0 = g0, b_i = b_(i-1) XOR g_i
    g = np.array([1, 1, 0, 1, 0], dtype=np.uint8)
    assert G.gray_to_binary(g).tolist() == [1, 0, 0, 1, 1]


def test_template_decode_gray_and_plain():
    t = G.Template([G.Gene(-5.12, 5.11, 1024), G.Gene(0.0, 7.0, 8)])
    bits = np.array([[1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 0]], dtype=np.uint8)
    plain = t.decode(bits, gray=False)[0]
    assert plain[0] == -5.12 + 512 * ((5.11 - -5.12) / 1023)
    assert plain[1] == 6.0
    gray = t.decode(bits, gray=True)[0]
    # Gray 1000000000 -> binary 1111111111 = 1023; Gray 110 -> binary 100 = 4
    assert gray[0] == -5.12 + 1023 * ((5.11 - -5.12) / 1023)
    assert gray[1] == 4.0
