"""``strokeopt kinematics`` and ``strokeopt size`` on a linkage problem file without [timing]: read as a problem
whose crank turns at constant speed, through the general commands; the transmission's own analysis (its outputs,
transmission index, crank torque) is the linkage package's (summary.summarize, dynamics.analyse_dynamics), the
motor and gearbox are `size`'s general choice, options that do not apply are refused with exit 2, a failed limit
is exit 1."""

from __future__ import annotations

import json

import numpy as np
import pytest

from strokeopt.cli.main import main
from strokeopt.linkage.dynamics import analyse_dynamics
from strokeopt.files.problem_file import load_problem
from strokeopt.linkage.files import load_linkage_file
from strokeopt.linkage.kinematics import kinematics_of
from strokeopt.linkage.summary import summarize

from conftest import ROOT

LOOM = ROOT / "problems" / "loom_beatup_sixbar.toml"
BLIND = ROOT / "problems" / "blind_stitch_needle.toml"


def _json(capsys, argv, code=0) -> dict:
    assert main(argv) == code
    return json.loads(capsys.readouterr().out)


def test_kinematics_of_a_linkage_is_the_library_s(capsys, tmp_path):
    # before: "machine.spm: is required but missing"
    fig = tmp_path / "k.png"
    top = _json(capsys, ["kinematics", str(LOOM), "--json", "--plot", str(fig)])
    lib = summarize(load_linkage_file(LOOM), with_dynamics=False)
    out = top["transmission_analysis"]
    assert top["status"] == out["status"] == "ok" and "dynamics" not in out
    # the crank turns once a pick at the constant 200 rpm: the general summary's turn
    (turn,) = top["intervals"]
    assert (turn["name"], turn["stroke_deg"], turn["time_s"]) == ("turn", 360.0, pytest.approx(0.3))
    crank = next(m for m in turn["members"] if m["member"] == "crank")
    assert crank["v_max"] == pytest.approx(200 * 2 * np.pi / 60) and crank["a_max"] == pytest.approx(0, abs=1e-9)
    assert fig.stat().st_size > 10_000
    sley = next(o for o in out["outputs"] if o["name"] == "sley_angle")
    assert sley == next(o for o in lib["outputs"] if o["name"] == "sley_angle")
    # the file's linkage (docs/linkages.md): swing 19.40 deg, front extreme 351 deg, rear near-dwell 64.5 deg,
    # rise 168.5 / fall 191.5 deg, least transmission index 0.162
    assert sley["swing_deg"] == pytest.approx(19.40, abs=0.005) and sley["minimum_at_deg"] == 351.0
    rear = next(d for d in sley["near_dwells"] if d["at"] == "maximum")
    assert (rear["from_deg"], rear["to_deg"], rear["length_deg"]) == (128.5, 193.0, 64.5)
    assert sley["asymmetry_rise_over_fall"] == pytest.approx(168.5 / 191.5)
    assert {"speed", "acceleration", "jerk"} <= set(sley["peaks"]) and sley["acceleration_unit"] == "rad/s^2"
    assert out["transmission"][0]["min_index"] == pytest.approx(0.162, abs=5e-4)


def test_kinematics_text_and_the_machine_s_rate(capsys):
    # --spm is the crank's rate (one turn per machine cycle): the blind-stitch needle at 2000 instead of 2500 rpm
    assert main(["kinematics", str(BLIND), "--spm", "2000", "--plot", "none"]) == 0
    text = capsys.readouterr().out
    assert "crank 2000 rpm = 209.4395 rad/s" in text and "near-dwell" in text and "transmission angle of the dyad" in text


def test_kinematics_below_the_transmission_limit_is_exit_1(capsys):
    assert main(["kinematics", str(LOOM), "--set", "transmission.min_transmission_index=0.2", "--plot", "none"]) == 1
    assert "below the limit 0.2" in capsys.readouterr().err


def test_size_of_a_linkage_is_the_library_s(capsys, tmp_path):
    fig = tmp_path / "s.png"
    top = _json(capsys, ["size", str(LOOM), "--json", "--explain", "--plot", str(fig)])
    out = top["transmission_analysis"]
    assert top["status"] == "ok" and fig.stat().st_size > 10_000
    problem = load_linkage_file(LOOM)
    kin = kinematics_of(problem.linkage)
    dyn = analyse_dynamics(kin, kin.solve(problem.angles), problem.omega)
    t = out["dynamics"]["torque_N_m"]
    assert (t["max"], t["min"], t["rms"]) == (float(dyn.torque.max()), float(dyn.torque.min()),
                                              float(np.sqrt(np.mean(dyn.torque ** 2))))
    # docs/linkages.md: the crank torque runs from -19.3 to 10.7 N m (RMS 8.4 N m); Newton-Euler agrees
    assert t["min"] == pytest.approx(-19.31, abs=0.01) and t["max"] == pytest.approx(10.70, abs=0.01)
    assert out["dynamics"]["newton_euler_max_relative_difference"] <= 1e-6
    for row in out["terms"]:   # the terms add up to the crank torque, Newton-Euler's equal at every row
        assert row["inertia_torque_N_m"] + row["gravity_torque_N_m"] + row["process_torque_N_m"] == \
            pytest.approx(row["torque_N_m"], abs=1e-9)
        assert row["torque_newton_euler_N_m"] == pytest.approx(row["torque_N_m"], abs=1e-6 * 19.31)
    beat = out["process_loads"][0]
    assert (beat["name"], beat["from_deg"], beat["to_deg"], beat["force_end_N"]) == ("beat-up", 352.0, 360.0, 1961.3)
    # the motor and gearbox: every catalogue motor through every gearbox of the file's [drive] gearboxes, ranked as
    # the file's [drive] choose says (the smallest motor that carries the crank, then the least RMS torque)
    fits = [c for c in top["candidates"] if c["feasible"]]
    first = top["candidates"][0]
    assert first == fits[0] and len(top["candidates"]) == 11 * 5   # 11 motors, 5 gearboxes
    # the sizing samples the cycle at 3601 points, the analysis at the file's 720 poses
    assert first["peak_torque_N_m"] == pytest.approx(-t["min"] / first["ratio"], rel=1e-4)
    assert first["peak_speed_rpm"] == pytest.approx(200.0 * first["ratio"])
    rated = {m.name: m.rated_torque for m in load_problem(LOOM).drive.catalogue().motors.values()}
    assert rated[first["motor"]] == min(rated[c["motor"]] for c in fits)
    assert all(c["ok"] for c in first["checks"]) and {"gearbox_peak_output_torque", "gearbox_rated_output_torque"} <= \
        {c["name"] for c in first["checks"]}
    # the gearbox's output torque is the crank's: 19.31 N m at the beat-up, whatever the ratio
    out_peak = next(c for c in first["checks"] if c["name"] == "gearbox_peak_output_torque")
    assert out_peak["value"] == pytest.approx(-t["min"], rel=1e-4)


def test_size_of_a_linkage_without_masses_says_so(capsys):
    # the blind-stitch file states no masses: no torque to size for, and the analysis says what is left
    problem = load_problem(BLIND)
    out = problem.transmission.analysis(problem, with_dynamics=True)
    assert "no masses" in out["note"] and out["dynamics"]["torque_N_m"]["rms"] == 0.0
    assert main(["size", str(BLIND), "--plot", "none"]) == 2   # nor a [drive] to size
    assert "drive: the problem has no [drive] section" in capsys.readouterr().err
    assert _json(capsys, ["size", str(LOOM), "--json"])["transmission_analysis"]["note"] is None


def test_size_text_and_an_infeasible_rate(capsys):
    assert main(["size", str(LOOM), "--plot", "none"]) == 0
    text = capsys.readouterr().out
    assert "Newton-Euler" in text and "through every gearbox of" in text and "smallest motor" in text
    # at 2000 rpm the crank's inertia torque is 100 times larger: no pair carries it
    out = _json(capsys, ["size", str(LOOM), "--spm", "2000", "--json"], code=1)
    assert out["status"] == "infeasible" and not any(c["feasible"] for c in out["candidates"])


@pytest.mark.parametrize("argv, option", [
    (["kinematics", str(LOOM), "--law", "poly5"], "--law"),
    (["size", str(LOOM), "--pulley-teeth", "24"], "--pulley-teeth"),
    (["size", str(LOOM), "--motor", "nope"], "--motor"),
])
def test_options_that_do_not_apply_are_refused(capsys, argv, option):
    assert main(argv + ["--plot", "none"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"strokeopt: error: {option}")


def test_a_bad_drive_section_names_the_field(capsys, tmp_path):
    path = tmp_path / "loom.toml"
    path.write_text(LOOM.read_text().replace('catalogues = ["loom_servos.toml"]', 'catalogues = ["no_such.toml"]'))
    assert main(["size", str(path), "--plot", "none"]) == 2
    err = capsys.readouterr().err
    assert "drive.catalogues" in err and "no_such.toml" in err and "loom_servos.toml" in err
