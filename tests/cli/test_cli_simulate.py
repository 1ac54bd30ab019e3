"""`strokeopt simulate` and `strokeopt verify` as a user and a script see them."""

from __future__ import annotations

import json

import pytest

from strokeopt.cli.main import main
from strokeopt.files.design_file import write_design


def test_simulate_json(capsys, reference_path, tmp_path):
    fig = tmp_path / "sim.png"
    assert main(["simulate", str(reference_path), "--scene", "release", "--spm", "600", "--json", "--plot", str(fig)]) == 0
    out, err = capsys.readouterr()
    data = json.loads(out)  # stdout is only JSON
    assert data["scene"] == "release" and data["spm"] == 600
    for key in ("impact_velocity_m_s", "impact_angle_deg", "lag_end_angle_deg", "min_gap_N_mm", "release_angle_deg",
                "peak_pad_force_N", "cpu_time_s", "gap_N_mm", "peak_drive_force_N"):
        assert isinstance(data[key], float), key
    assert data["premature_release"] is False
    assert 2.7 < data["impact_velocity_m_s"] < 3.0  # thesis ch. 6: 2.90 m/s at 600 spm
    assert fig.stat().st_size > 10_000 and str(fig) in err


def test_simulate_text_states_gap_N(capsys, reference_path):
    assert main(["simulate", str(reference_path), "--spm", "500", "--plot", "none"]) == 0
    out = capsys.readouterr().out
    assert "scene 'release'" in out and "gap N used by the model: 7.4 mm" in out
    assert "impact of control on the stop" in out and "not premature" in out and "CPU time" in out


def test_set_reaches_the_model(capsys, reference_path):
    args = ["simulate", str(reference_path), "--spm", "600", "--json", "--plot", "none"]
    assert main(args) == 0
    base = json.loads(capsys.readouterr().out)
    assert main(args + ["--set", "model.springs.k2.stiffness_N_m=1240", "--set", "model.contacts.c32.gap_mm=6.5"]) == 0
    stiff = json.loads(capsys.readouterr().out)
    assert stiff["gap_N_mm"] == pytest.approx(6.5)
    assert stiff["impact_velocity_m_s"] < base["impact_velocity_m_s"]


def test_sweep(capsys, reference_path, tmp_path):
    fig = tmp_path / "sweep.png"
    assert main(["simulate", str(reference_path), "--spm", "300:400:50", "--json", "--plot", str(fig)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [r["spm"] for r in data["rows"]] == [300, 350, 400]
    assert data["lag_onset_spm"] == 350
    assert fig.stat().st_size > 10_000
    assert main(["simulate", str(reference_path), "--spm", "300:400:50", "--plot", "none"]) == 0
    out = capsys.readouterr().out
    assert "impact speed m/s" in out and "lags from 350 spm" in out


@pytest.mark.slow
def test_tolerance_study(capsys, reference_path, tmp_path):
    fig = tmp_path / "tol.png"
    assert main(["simulate", str(reference_path), "--spm", "600", "--study", "tolerance", "--json", "--plot", str(fig)]) == 0
    data = json.loads(capsys.readouterr().out)
    methods = {(r["method"], r["switching"]) for r in data["rows"]}
    assert methods == {("cvodes", "hard"), ("idas", "hard"), ("cvodes", "smoothed"), ("cvodes", "restarts")}
    hard = [r for r in data["rows"] if r["method"] == "cvodes" and r["smoothing_mm"] == 0]
    assert hard[-1]["impact_velocity_error_m_s"] < hard[0]["impact_velocity_error_m_s"]
    assert fig.stat().st_size > 10_000


@pytest.mark.parametrize("args, words", [
    (["--scene", "relase"], "no scene 'relase'"),
    (["--spm", "300:200:10"], "STOP >= START"),
    (["--spm", "fast"], "expected SPM or START:STOP:STEP"),
    (["--set", "model.contacts.c32.gap_mm=-6.5"], "model.contacts.c32.gap_mm"),
    (["--set", "model.bodies.needle.mass_g=0"], "model.bodies.needle.mass_g: 0 is outside the plausible range [0.001, 1e+07]"),
    (["--rtol", "0"], "rtol"),
    (["--study", "tolerance", "--spm", "300:400:50"], "one speed"),
])
def test_bad_input_exit_2(capsys, reference_path, args, words):
    assert main(["simulate", str(reference_path), "--plot", "none"] + args) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1


@pytest.mark.parametrize("edit, words", [
    (('elements = ["k2", "k3", "pad", "c21", "c32", "c13", "c31"]', 'elements = ["k2", "k3", "pad", "c21", "c77"]'),
     "scenes.release.elements: unknown element 'c77'"),
    (('[model.springs.k3]\nbodies = ["control", "cage"]', '[model.springs.k3]\nbodies = ["control", "basket"]'),
     "model.springs.k3.bodies: unknown body 'basket'"),
    (('label = "3 clamp cage with the two balls"', 'label = "3 clamp cage"\ndriven = true'),
     "exactly one body must be driven"),
])
def test_bad_problem_file_exit_2(capsys, write_problem, edit, words):
    path = write_problem(lambda t: t.replace(*edit))
    assert main(["simulate", str(path), "--plot", "none"]) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err


@pytest.mark.slow  # solves a design first (collocation, seconds to tens of seconds)
def test_verify_design(capsys, reference_path, tmp_path, monkeypatch):
    from strokeopt import load_problem
    from strokeopt.design.solve import solve_design

    design = solve_design(load_problem(reference_path), objective="min_jerk", spm=600)
    path = write_design(design, tmp_path)[0]
    assert main(["verify", str(path), "--scene", "release", "--json", "--plot", "none"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["design"] == str(path) and data["spm"] == 600 and data["stroke"] == "optimal"
    assert data["impact_velocity_m_s"] > 0 and data["release_angle_deg"] > data["impact_angle_deg"]
    # --json alone writes no figure; the default figure is verify's own, named by scene, rate and objective
    monkeypatch.chdir(tmp_path)
    assert main(["verify", str(path), "--scene", "release", "--json"]) == 0
    assert not (tmp_path / "strokeopt-out").exists()
    assert main(["verify", str(path), "--scene", "release"]) == 0
    capsys.readouterr()
    assert [f.name for f in (tmp_path / "strokeopt-out").iterdir()] == [
        f"{reference_path.stem}_verify_release_600spm_min_jerk.png"]


def test_verify_bad_file(capsys, tmp_path):
    bad = tmp_path / "design.json"
    bad.write_text("{}")
    assert main(["verify", str(bad), "--plot", "none"]) == 2
    assert "design" in capsys.readouterr().err


def test_help_teaches(capsys):
    with pytest.raises(SystemExit):
        main(["simulate", "--help"])
    out = capsys.readouterr().out
    assert "Example" in out and "--spm" in out and "gap N" in out


def test_verify_help_example_writes_what_it_reads(capsys):
    with pytest.raises(SystemExit):
        main(["verify", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert ("strokeopt solve problems/deco2000_needle_bar.toml --out out && strokeopt verify "
            "problems/deco2000_needle_bar.toml --design out/design.json") in out
    assert "verify DESIGN.json" in out  # the older form, still accepted, is named
    assert "_verify_<scene>_<spm>spm_<objective>.png" in out


@pytest.mark.parametrize("command", ["simulate", "verify"])
def test_smoothing_is_not_a_command_line_option(capsys, reference_path, command):
    # smoothing the contact switches is a study device (--study tolerance), not a model option
    with pytest.raises(SystemExit) as exc:
        main([command, str(reference_path), "--smoothing-mm", "1", "--plot", "none"])
    assert exc.value.code == 2
    assert "--smoothing-mm" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main([command, "--help"])
    assert "--smoothing-mm" not in capsys.readouterr().out


def test_integrator_failure_is_one_line_of_strokeopt(capfd, reference_path):
    # the lightest body on the stiffest undamped contact of the plausible ranges makes CVODES fail; SUNDIALS'
    # own "At t = ..." must not reach the user (a budget of 1e8 steps lets it past the check of its contact period,
    # tests/contact/test_contact_peaks.py, to the integrator)
    assert main(["simulate", str(reference_path), "--set", "model.bodies.control.mass_g=1e-3", "--set",
                 "model.contacts.c21.stiffness_N_m=1e12", "--set", "model.contacts.c21.damping_N_s_m=0",
                 "--set", "scenes.release.max_steps=1e8", "--plot", "none"]) == 1
    out, err = capfd.readouterr()
    assert out == "" and "At t =" not in err
    assert err.count("\n") == 1 and err.startswith("strokeopt: failed: cvodes failed") and "error test" in err


def test_speed_sweep_names_the_onset_of_premature_release(capsys, reference_path):
    # at these rates the release scene closes gap N before the impact (min gap N < 0): the summary says from where
    assert main(["simulate", str(reference_path), "--scene", "release", "--spm", "1100:1160:20", "--json",
                 "--plot", "none"]) == 0
    data = json.loads(capsys.readouterr().out)
    first = next(r["spm"] for r in data["rows"] if r["premature_release"])
    assert data["premature_release_onset_spm"] == first
    assert main(["simulate", str(reference_path), "--scene", "release", "--spm", "1100:1160:20", "--plot", "none"]) == 0
    assert f"premature release from {first:g} spm" in capsys.readouterr().out


def test_a_misspelt_scene_gets_a_hint(reference_path, capsys):
    from strokeopt.cli.main import main as run

    assert run(["simulate", str(reference_path), "--scene", "relase", "--plot", "none"]) == 2
    err = capsys.readouterr().err
    assert "did you mean 'release'" in err and err.count("\n") == 1


@pytest.mark.parametrize("option, value", [("--rtol", "5"), ("--rtol", "0.1"), ("--rtol", "0"), ("--rtol", "1e-13"),
                                           ("--atol", "0.1"), ("--atol", "-1e-6"), ("--atol", "nan")])
def test_integrator_tolerances_out_of_range_are_refused(capsys, reference_path, option, value):
    """--rtol 5 was accepted (and ended in 'implausible forces', exit 1): the tolerances are ranged like a file's
    field (contact/scene.TOLERANCE_RANGES says why), refused in one line naming the option, before any run."""
    assert main(["simulate", str(reference_path), f"{option}={value}", "--plot", "none"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith(f"strokeopt: error: {option}: must be a positive number in [")


def test_integrator_tolerances_in_range_run(capsys, reference_path):
    assert main(["simulate", str(reference_path), "--rtol", "0.01", "--atol", "0.001", "--plot", "none"]) == 0
