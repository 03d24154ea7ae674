"""The admittance problem: synthetic sweeps, the data format, the cost, compensation, identifiability.

Parameter recovery is checked with SciPy least squares on the problem's residuals (independent of the
lindsay_barton plugin, which has its own tests) against the motor preset's model-F values.
"""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy.optimize import least_squares

from benchmark.core.errors import ConfigError, DataError
from benchmark.core.harness import build_problem
from benchmark.problems.admittance.circuit import input_admittance, slip_from_speed
from benchmark.problems.admittance.data import load_admittance
from benchmark.problems.admittance.problem import bilinear_regression
from synthetic.admittance import generate, make_dataset
from tests.conftest import compose_config

MODEL_F = {
    "R1": 0.2045,
    "R1sigma": 0.0061,
    "X1": 0.5580,
    "R2": 0.2941,
    "R2sigma": 0.0340,
    "X2": 0.5579,
    "X3": 0.0093,
    "R0": 1.0592,
    "X0": 16.0998,
}
ROOT = Path(__file__).resolve().parents[3]
MODEL_D = {"R1": 0.2337, "X1": 0.5521, "R2": 0.2983, "X2": 0.5530, "R0": 1.051, "X0": 16.11}


def cfg_for(*overrides, noise="none"):
    return compose_config(["problem=admittance", f"noise={noise}", *overrides])


def fit(problem, x0):
    """Least squares in coordinates normalised to the bounds, to full convergence."""
    lo, hi = problem.lower, problem.upper
    sol = least_squares(
        lambda u: problem.residuals(lo + u * (hi - lo)),
        np.clip((x0 - lo) / (hi - lo), 0, 1),
        bounds=(0, 1),
        xtol=1e-15,
        ftol=1e-15,
        gtol=1e-15,
        x_scale="jac",
    )
    return lo + sol.x * (hi - lo)


def rel_errors(problem, x):
    est = problem.estimate(x)
    return {k: (est[k] - problem.truth[k]) / problem.truth[k] for k in est if problem.truth.get(k)}


def test_composed_config_and_paper_test_settings():
    cfg = cfg_for()
    # the model is chosen by the data, except for a preset's own synthetic data: the paper's 8
    assert cfg.problem.name == "admittance" and cfg.problem.model == "auto" and cfg.motor.model == 8
    assert cfg.motor.name == "lindsay_barton_7p5hp"
    p = build_problem(cfg)
    assert p.model_choice is None and p.normalisation == "full_scale"
    assert p.parameter_names == ("R1_total", "X1", "R2", "X2", "R0", "X0", "R2sigma", "X3")
    speeds = p.data.speed_rpm
    np.testing.assert_allclose(speeds, np.arange(-1800, 2401, 100), atol=1e-9)
    np.testing.assert_allclose(p.data.slip[[0, -1]], [2.0, -1 / 3])
    assert np.all(p.data.voltage == 30.2)
    assert p.truth["R1_total"] == pytest.approx(0.2106) and p.truth["R1sigma"] == pytest.approx(0.0061)
    # the bounds are wide and do not centre on the truth
    t = np.array([p.truth[n] for n in p.parameter_names])
    frac = (t - p.lower) / (p.upper - p.lower)
    assert np.all(frac > 0.05) and np.all(frac < 0.5)


def test_generator_writes_section7_folder_that_loads_back(tmp_path):
    cfg = cfg_for("noise.seed=3", noise="noisy")
    folder = generate(cfg, tmp_path / "d")
    names = sorted(p.name for p in folder.iterdir())
    assert names == ["meta.yaml", "sweep01.csv", "truth.yaml"]
    meta = yaml.safe_load((folder / "meta.yaml").read_text())
    assert meta["kind"] == "admittance" and meta["frequency"] == 60.0 and meta["pole_pairs"] == 2
    assert meta["voltage"] == 30.2 and meta["full_scale_admittance"] == 1.0
    assert (
        len(meta["stator_dc_resistance"]) == 2
        and meta["stator_dc_resistance"][1] > meta["stator_dc_resistance"][0]
    )
    truth = yaml.safe_load((folder / "truth.yaml").read_text())
    assert truth["parameters"]["R2sigma"] == 0.034 and truth["noise"]["admittance_fraction"] == 0.003
    mem, _ = make_dataset(cfg)
    disk = load_admittance(folder)
    np.testing.assert_allclose(disk.G, mem.G, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(disk.B, mem.B, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(disk.slip, mem.slip, atol=1e-12)
    # the noise is 0.3 % of full scale (1 S) on G and B
    clean, _ = make_dataset(cfg_for())
    resid = np.concatenate([(mem.Y - clean.Y).real, (mem.Y - clean.Y).imag])
    assert 0.0022 < resid.std() < 0.0038 and abs(resid.mean()) < 0.001
    # the problem built from the folder is the in-memory one, and scores against truth.yaml
    cfg_disk = cfg_for(f"data.path={folder}", "problem.model=8", noise="noisy")
    p_disk, p_mem = build_problem(cfg_disk), build_problem(cfg)
    x = np.array([p_mem.truth[n] for n in p_mem.parameter_names])
    assert p_disk.evaluate(x[None])[0] == pytest.approx(p_mem.evaluate(x[None])[0], rel=1e-7)
    assert p_disk.truth == pytest.approx(p_mem.truth)


def test_python_m_synthetic_writes_the_folder(tmp_path):
    out = tmp_path / "cli"
    proc = subprocess.run(
        [sys.executable, "-m", "synthetic", "problem=admittance", "noise=noisy", f"out={out}"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    assert (
        (out / "meta.yaml").is_file() and (out / "sweep01.csv").is_file() and (out / "truth.yaml").is_file()
    )
    assert load_admittance(out).n == 43


def test_extra_voltage_levels_and_down_sweep(tmp_path):
    cfg = cfg_for("motor.test.voltages=[30.2,45.0]", "motor.test.down_sweep=true")
    folder = generate(cfg, tmp_path / "two")
    files = sorted(p.name for p in folder.glob("sweep*.csv"))
    assert files == ["sweep01.csv", "sweep02.csv", "sweep03.csv", "sweep04.csv"]
    d = load_admittance(folder)
    assert set(np.round(d.voltage, 6)) == {30.2, 45.0}
    assert d.n == 4 * 43 - 2 and np.all(np.diff(d.time) > 0)
    # the down-sweep is read later, warmer: its standstill conductance is higher than the up-sweep's
    up = (d.sweep == 0) & (np.abs(d.slip - 1) < 1e-9)
    down = (d.sweep == 1) & (np.abs(d.slip - 1) < 1e-9)
    assert d.G[down][0] > d.G[up][0]
    p = build_problem(cfg_for(f"data.path={folder}", "problem.model=8"))
    x = np.array([p.truth[n] for n in p.parameter_names])
    # compensated, the truth fits to ~1e-5 of full scale (what remains is the heat interpolated
    # between readings 4 s apart); uncompensated the warming leaves a misfit 50 times larger
    assert p.rms_error_percent(x) < 3e-3
    off = build_problem(cfg_for(f"data.path={folder}", "problem.model=8", "problem.temperature_compensation=false"))
    assert off.rms_error_percent(x) > 0.05


def write_folder(tmp_path, meta: dict, table: str, name="sweep01.csv"):
    tmp_path.mkdir(parents=True, exist_ok=True)
    (tmp_path / "meta.yaml").write_text(yaml.safe_dump(meta))
    (tmp_path / name).write_text(table)
    return tmp_path


GOOD_META = {"kind": "admittance", "frequency": 60, "pole_pairs": 2, "voltage": 30.2}
GOOD_TABLE = "speed_rpm,G,B\n" + "".join(f"{n},0.1,-0.2\n" for n in range(-1800, 2401, 600))


@pytest.mark.parametrize(
    "meta, table, words",
    [
        (GOOD_META | {"kind": "startup"}, GOOD_TABLE, ["meta.yaml", "'kind'", "admittance"]),
        ({k: v for k, v in GOOD_META.items() if k != "frequency"}, GOOD_TABLE, ["meta.yaml", "'frequency'"]),
        (GOOD_META | {"stator_dc_resistance": 0.2}, GOOD_TABLE, ["stator_dc_resistance", "[before, after]"]),
        (GOOD_META | {"stator_dc_resistance": [0.2, -1]}, GOOD_TABLE, ["stator_dc_resistance", "positive"]),
        (GOOD_META, GOOD_TABLE.replace("G,B", "G,X"), ["sweep01.csv", "column 'B'", "missing"]),
        (GOOD_META, GOOD_TABLE.replace("2400,0.1", "2400,abc"), ["sweep01.csv", "column 'G'", "row 8"]),
        ({k: v for k, v in GOOD_META.items() if k != "voltage"}, GOOD_TABLE, ["voltage"]),
        (
            GOOD_META,
            "speed_rpm,G,B,time\n0,0.1,-0.2,5\n100,0.1,-0.2,4\n200,0.1,-0.2,6\n",
            ["column 'time'", "row 2"],
        ),
        (GOOD_META, "speed_rpm,G,B\n0,0.1,-0.2\n", ["only 1 readings"]),
    ],
)
def test_loader_names_file_column_row(tmp_path, meta, table, words):
    folder = write_folder(tmp_path / "bad", meta, table)
    with pytest.raises(DataError) as exc:
        load_admittance(folder)
    for w in words:
        assert w in str(exc.value)


def test_config_errors_name_the_key(tmp_path):
    with pytest.raises(ConfigError, match=r"problem\.model"):
        build_problem(cfg_for("problem.model=7"))
    # the user's bounds replace the preset's parameter by parameter (X3 from the preset here)
    p = build_problem(cfg_for("+bounds={R1_total:[0.1,1],X1:[0.1,1],R2:[0.1,1],X2:[0.1,1],R0:[0,2],X0:[5,30],"
                              "R2sigma:[0,0.1]}"))
    assert p.upper[p.parameter_names.index("X3")] == 0.05 and p.upper[p.parameter_names.index("X0")] == 30
    with pytest.raises(ConfigError, match=r"bounds\.X3: low 0\.1 >= high 0\.01"):
        build_problem(cfg_for("+bounds={X3:[0.1,0.01]}"))
    with pytest.raises(ConfigError, match=r"bounds: \['Rs'\] not searched"):
        build_problem(cfg_for("+bounds={Rs:[1,2]}"))
    with pytest.raises(ConfigError, match=r"bounds\.R2: low 0\.6 >= high 0\.1"):
        build_problem(cfg_for("motor.bounds.R2=[0.6,0.1]"))
    folder = write_folder(tmp_path / "nodc", GOOD_META, GOOD_TABLE)
    with pytest.raises(ConfigError, match=r"problem\.temperature_compensation.*stator_dc_resistance"):
        build_problem(cfg_for(f"data.path={folder}", "problem.temperature_compensation=true"))
    with pytest.raises(ConfigError, match=r"problem\.stalled_torque_weight.*torque"):
        build_problem(cfg_for(f"data.path={folder}", "problem.stalled_torque_weight=1"))


def test_without_dc_resistance_only_r1_total_is_reported(tmp_path):
    folder = write_folder(tmp_path / "nodc", GOOD_META, GOOD_TABLE)
    p = build_problem(cfg_for(f"data.path={folder}"))
    assert p.truth is None and not p.compensated
    est = p.estimate(p.crude_start())
    assert "R1_total" in est and "R1" not in est and "R1sigma" not in est
    assert any("R1_total = R1 + R1sigma" in n for n in p.describe()["identifiability"])


def test_evaluate_is_vectorised_and_counts_invalid_as_inf():
    """(Its speed is measured in ``python -m benchmark.studies.perf``, not in a timed test.)"""
    p = build_problem(cfg_for(f"motor.test.speed_step_rpm={4200 / 99!r}", noise="noisy"))  # 100 readings
    assert p.data.n == 100
    rng = np.random.default_rng(1)
    X = p.lower + rng.uniform(0, 1, (100, p.n_var)) * (p.upper - p.lower)
    X[3, 2] = -0.1  # negative R2
    X[7, 5] = np.nan
    c = p.evaluate(X)
    assert c.shape == (100,) and np.isinf(c[3]) and np.isinf(c[7])
    row = np.array([p.evaluate(x[None])[0] for x in X])
    np.testing.assert_allclose(c, row, rtol=1e-12)
    r = p.residuals(X[0])
    assert r @ r == pytest.approx(c[0], rel=1e-12) and len(r) == 200


def test_noise_free_eight_parameter_fit_recovers_every_identifiable_parameter():
    """Model-F data at constant temperature: the minimum of the cost is the truth, reached from the
    crude start; R1 and R1sigma are separated through the DC stator resistance."""
    p = build_problem(cfg_for("motor.test.warming=false"))
    x = fit(p, p.crude_start())
    err = rel_errors(p, x)
    assert set(err) == {"R1_total", "X1", "R2", "X2", "R0", "X0", "R2sigma", "X3", "X1+X2", "R1", "R1sigma"}
    for k, e in err.items():
        assert abs(e) < 1e-3, (k, e)
    assert p.rms_error_percent(x) < 1e-8


def test_regression_route_recovers_a_six_parameter_truth_to_five_significant_figures():
    six = MODEL_D | {"R1sigma": 0.0, "R2sigma": 0.0, "X3": 0.0}  # (the override merges into model F)
    overrides = [
        f"motor.parameters={{{','.join(f'{k}:{v}' for k, v in six.items())}}}",
        "motor.test.warming=false",
        "problem.model=6",
    ]
    p = build_problem(cfg_for(*overrides))
    assert p.parameter_names == ("R1_total", "X1", "R2", "X2", "R0", "X0")
    x = p.initial_guess("E")
    assert p.last_mapping == "free"
    truth = {"R1_total": 0.2337} | {k: MODEL_D[k] for k in ("X1", "R2", "X2", "R0", "X0")}
    for name, v in zip(p.parameter_names, x, strict=True):
        assert f"{v:.5g}" == f"{truth[name]:.5g}", name
        assert v == pytest.approx(truth[name], rel=1e-9)
    # the bare regression (no problem object) does the same on the exact curve
    s = slip_from_speed(np.arange(-1800, 2401, 100), 60.0, 2)
    Y = input_admittance(s, 0.2337, 0.5521, 0.2983, 0.5530, 1.051, 16.11)
    reg = bilinear_regression(s, Y)["free"]
    assert reg["R2"] == pytest.approx(0.2983, rel=1e-9) and reg["X2"] == pytest.approx(0.5530, rel=1e-9)


def test_five_degree_rise_biases_resistances_and_compensation_removes_it():
    cfg = cfg_for()
    data, truth = make_dataset(cfg)
    rise = truth["temperature"]["last_reading"] - truth["temperature"]["first_reading"]
    assert 4.5 < rise < 5.5  # the paper's 5 C example
    on = build_problem(cfg)
    off = build_problem(cfg_for("problem.temperature_compensation=false"))
    x_true = np.array([on.truth[n] for n in on.parameter_names])
    e_off = rel_errors(off, fit(off, x_true))
    e_on = rel_errors(on, fit(on, x_true))
    # uncompensated: the fit sees the sweep-average temperature, about 1 % warm
    assert e_off["R1_total"] > 0.005 and e_off["R2"] > 0.005
    for k in ("R1_total", "R2", "X1", "X2", "X0", "R2sigma", "X3"):
        assert abs(e_on[k]) < 5e-4, (k, e_on[k])
    assert abs(e_on["R0"]) < 1e-3
    # the estimated temperature profile ends where the DC readings say, and follows the truth
    prof = on.profile
    assert prof.theta[-1] == pytest.approx(truth["temperature"]["last_reading"], abs=0.02)
    assert prof.theta[0] == pytest.approx(truth["temperature"]["first_reading"], abs=0.02)
    # the paper's I^2 heat model is cruder but still removes most of the bias
    i2 = build_problem(cfg_for("problem.heat_model=current_squared"))
    e_i2 = rel_errors(i2, fit(i2, x_true))
    assert abs(e_i2["R2"]) < 0.2 * abs(e_off["R2"])


def test_stalled_torque_term_and_measured_normalisation():
    base = ["motor.test.warming=false"]
    p = build_problem(cfg_for(*base, "problem.stalled_torque_weight=1.0", "problem.normalisation=measured"))
    x = np.array([p.truth[n] for n in p.parameter_names])
    r = p.residuals(x)
    assert len(r) == 2 * 43 + 1 and np.max(np.abs(r)) < 1e-8
    T_stalled = p.data.torque[np.argmin(np.abs(p.data.slip - 1))]
    assert p.stalled_torque(x[None])[0] == pytest.approx(T_stalled, rel=1e-9)
    # a 10 % too large R2sigma raises the stalled torque (it pins R2sigma)
    x2 = x.copy()
    x2[p.parameter_names.index("R2sigma")] *= 1.1
    assert p.stalled_torque(x2[None])[0] > T_stalled


def test_r0_is_weakly_determined_and_the_spread_shows_it():
    """Over noise realisations at 0.3 % of full scale, R0 scatters by tens of per cent while X0 and
    the tied leakage reactance stay within a few per cent (Lindsay and Barton (1972))."""
    errs = []
    for seed in range(5):
        p = build_problem(
            cfg_for(f"noise.seed={seed}", "motor.test.warming=false", "problem.tie_x1_x2=true", noise="noisy")
        )
        x = fit(p, p.initial_guess("E"))
        errs.append(rel_errors(p, x))
    spread = {k: np.std([e[k] for e in errs]) for k in errs[0]}
    assert spread["R0"] > 0.05
    assert spread["X0"] < 0.03 and spread["X1"] < 0.01 and spread["R2"] < 0.02
    assert spread["R0"] > 5 * spread["X0"]
