"""What a wheel ships: every package of the tree (pyproject.toml lists them), the configuration as
package data, and the entry points find it there (benchmark.core.config_files). .ci/run builds the
wheel, installs it into a fresh venv and runs python -m benchmark outside the repository."""

from __future__ import annotations

import ast
import re
from pathlib import Path

from benchmark.core.config_files import CONFIG_DIR, _find_config_dir

REPO = Path(__file__).resolve().parents[2]


def test_every_package_is_listed_for_the_wheel():
    text = (REPO / "pyproject.toml").read_text()  # (tomllib is Python 3.11+; the project runs on 3.10)
    listed = ast.literal_eval(re.search(r"^packages = (\[.*?\])", text, flags=re.S | re.M).group(1))
    found = {str(p.parent.relative_to(REPO)).replace("/", ".") for top in ("benchmark", "plugins", "synthetic")
             for p in (REPO / top).rglob("__init__.py")}
    assert found | {"benchmark.conf"} == set(listed)
    assert '"benchmark.conf" = "conf"' in text


def test_the_configuration_is_found_in_a_source_checkout_and_in_an_installed_package(tmp_path, monkeypatch):
    assert CONFIG_DIR == REPO / "conf"
    import benchmark.core.config_files as cf

    package = tmp_path / "site" / "benchmark"
    (package / "conf" / "optimizer").mkdir(parents=True)
    (package / "conf" / "config.yaml").write_text("seed: 0\n")
    monkeypatch.setattr(cf, "_PACKAGE", package)
    assert _find_config_dir() == package / "conf"  # the wheel's copy (benchmark/conf) comes first
