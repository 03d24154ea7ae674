"""Every entry point's --help is its own and short: it names its own keys with their defaults, lists
only the groups a user can select (no effect group that would then be rejected), hides the internal
hooks; a misspelt key, with or without +, is one line with the nearest key and exit status 2."""

from __future__ import annotations

import runpy
import sys

import pytest

from benchmark.core.config_files import config_groups

ENTRY_POINTS = {  # module: keys its help must name
    "benchmark": ["seed=0", "budget=null", "data.path=null", "progress=auto", "problem.stator_resistance=auto",
                  "optimizer.plugin.{global_fraction=0.3"],
    "benchmark.diagnose": ["candidates=null", "effects=[]", "diagnosis.{selection_share=0.5", "base_case=2",
                           "budget=8000"],
    "synthetic": ["out=", "effects=[]", "effect_size=null"],
    "benchmark.blind": ["source=own", "n=30", "free_share=0.34", "workdir=outputs/blind"],
    "benchmark.blind_admittance": ["n=60", "seed=2024", "free_share=null"],
}


def _run_module(module: str, argv: list[str], capsys) -> tuple[int, str, str]:
    old = sys.argv
    sys.argv = [module, *argv]
    try:
        runpy.run_module(module, run_name="__main__", alter_sys=False)
        code = 0
    except SystemExit as exc:
        code = exc.code or 0
    finally:
        sys.argv = old
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.parametrize("module", list(ENTRY_POINTS))
def test_help_names_its_own_keys(module, capsys):
    code, out, _ = _run_module(module, ["--help"], capsys)
    assert code == 0
    for key in ENTRY_POINTS[module]:
        assert key in out, (module, key)
    assert "_target_" not in out and "$CONFIG" not in out
    assert "effect " not in out.split("Config groups")[-1]  # the catalogue is no group
    assert len(out.splitlines()) <= 60, len(out.splitlines())
    assert max(len(line) for line in out.splitlines()) <= 125


def test_the_help_follows_the_choices_on_the_command_line(capsys):
    _, out, _ = _run_module("benchmark", ["problem=admittance", "optimizer=genesis", "--help"], capsys)
    assert "problem.{model=auto" in out and "optimizer.plugin.{population_size=100" in out
    assert "optimizer  cmaes" in out and "genesis*" in out
    assert "problem.stator_resistance=auto" not in out
    assert set(config_groups()) == {"experiment", "motor", "noise", "optimizer", "problem"}


@pytest.mark.parametrize(("argv", "message"), [
    (["seeed=1"], "error: seeed: unknown key (did you mean seed?)"),
    (["+seeed=1"], "error: seeed: unknown key (did you mean seed?)"),
    (["problem.stator_resistanse=prior"], "error: problem.stator_resistanse: unknown key (did you mean "
                                          "problem.stator_resistance?)"),
    (["+problem.stator_resistanse=prior"], "did you mean problem.stator_resistance?"),
    (["optimizer=deep"], "error: optimizer=deep: no such option (did you mean deap?)"),
    (["-m", "optimizer=deap,cmaes", "seed=0,1", "bugdet=5"], "error: bugdet: unknown key (did you mean budget?)"),
])
def test_a_misspelt_key_is_one_line(argv, message, capsys):
    code, out, err = _run_module("benchmark", argv, capsys)
    assert code == 2
    assert message in err and len(err.strip().splitlines()) == 1, err
    assert out == ""
