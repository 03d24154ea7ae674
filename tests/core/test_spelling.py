"""One matching rule for misspelt names, two phrasings: what a user typed gets "did you mean",
what a file holds gets "found ... instead" (benchmark/core/spelling.py), every caller through it."""

from __future__ import annotations

import pytest

from benchmark.core.errors import ConfigError
from benchmark.core.spelling import did_you_mean, found_instead
from benchmark.studies.suite.cli import parse


def test_a_typed_name_gets_the_nearest_known_one_and_an_unrelated_word_nothing():
    assert did_you_mean("seeed", ["seed", "budget"]) == " (did you mean seed?)"
    assert did_you_mean("stator_resistanse", ["stator_resistance"], "problem") == \
        " (did you mean problem.stator_resistance?)"
    assert did_you_mean("zzz", ["seed", "budget"]) == ""


def test_a_name_in_a_file_says_what_was_found_case_first():
    assert found_instead("speed", ["t", "Speed", "speeds"]) == " (found 'Speed': names are case-sensitive)"
    assert found_instead("sample_time", ["sampel_time", "pole_pairs"]) == " (found 'sampel_time': misspelt?)"
    assert found_instead("speed", ["t", "i_a"]) == ""


def test_the_suites_arguments_read_as_the_main_commands():
    with pytest.raises(ConfigError, match=r"^suit=small: unknown argument \(did you mean suite\?\); valid: suite"):
        parse(["suit=small"])


def test_a_run_configs_unknown_top_level_key_gets_the_nearest_key():
    from omegaconf import OmegaConf

    from benchmark.core.config_checks import check_top_level_keys

    with pytest.raises(ConfigError, match=r"^seeed: unknown key \(did you mean seed\?\); the keys of a run are \["):
        check_top_level_keys(OmegaConf.create({"seed": 0, "seeed": 1}))
