"""`strokeopt size` as a user and a script see it."""

from __future__ import annotations

import json

import pytest

from strokeopt.cli.main import main


def _json(capsys, argv):
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 0, err
    return json.loads(out), err


def test_size_json_full_catalogue(capsys, reference_path, tmp_path):
    fig = tmp_path / "s.png"
    data, err = _json(capsys, ["size", str(reference_path), "--spm", "600", "--json", "--plot", str(fig)])
    assert data["spm"] == 600
    cands = data["candidates"]
    assert len(cands) == 140
    for key in ("motor", "pulley_teeth", "peak_torque_N_m", "rms_torque_N_m", "overload_pct", "peak_speed_rpm",
                "inertia_ratio", "feasible", "binding"):
        assert all(key in c for c in cands), key
    assert "max_spm" not in cands[0]
    assert cands[0]["feasible"] and cands[0]["overload_pct"] <= cands[1]["overload_pct"]
    assert data["inputs"]["moving_mass_kg"] == 0.191 and data["inputs"]["belt"] == "GT3-3MR-09"
    assert fig.stat().st_size > 10_000 and str(fig) in err


def test_size_restricted_with_max_spm_and_explain(capsys, reference_path):
    data, _ = _json(capsys, ["size", str(reference_path), "--spm", "600", "--json", "--plot", "none", "--motor",
                             "055U2B30", "--pulley-teeth", "28", "--pulley-teeth", "36", "--max-spm", "--explain"])
    cands = data["candidates"]
    assert [(c["motor"], c["pulley_teeth"]) for c in cands] == [("055U2B30", 28), ("055U2B30", 36)]
    assert data["max_spm_resolution"] == 1.0
    for c in cands:
        assert c["max_spm"] > 600 and c["max_spm_binding"]
        terms = c["torque_at_peak_N_m"]
        assert sum(v for k, v in terms.items() if k != "total") == pytest.approx(terms["total"])
        assert {ch["name"] for ch in c["checks"]} >= {"peak_torque", "overload", "rms_torque", "peak_speed",
                                                      "inertia_ratio", "belt_width", "belt_breaking"}


def test_size_text_table(capsys, reference_path):
    assert main(["size", str(reference_path), "--plot", "none", "--motor", "055U2B30", "--explain",
                 "--continuous-radius"]) == 0
    out = capsys.readouterr().out
    assert "500 spm" in out and "055U2B30" in out and "binding" in out
    assert "moving mass 0.191 kg" in out  # the inputs are printed beside the numbers
    assert "rotor_inertia" in out and "continuous pulley radius" in out


def test_continuous_radius_json(capsys, reference_path):
    data, _ = _json(capsys, ["size", str(reference_path), "--json", "--plot", "none", "--motor", "055U2B30",
                             "--motor", "CMP50M3000", "--continuous-radius"])
    rows = {r["motor"]: r for r in data["continuous_radius"]}
    assert set(rows) == {"055U2B30", "CMP50M3000"}
    # a heavier rotor wants a larger pulley (inertia matching)
    assert rows["CMP50M3000"]["pitch_radius_mm"] > rows["055U2B30"]["pitch_radius_mm"]
    # and the optimum beats every catalogue pulley for that motor
    sized, _ = _json(capsys, ["size", str(reference_path), "--json", "--plot", "none", "--motor", "055U2B30"])
    assert rows["055U2B30"]["peak_torque_N_m"] <= min(c["peak_torque_N_m"] for c in sized["candidates"]) + 1e-9


def _one_line_error(capsys, argv, *words):
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "Traceback" not in err
    for w in words:
        assert w in err, (w, err)
    return err


def test_unknown_motor_exit_2(capsys, reference_path):
    _one_line_error(capsys, ["size", str(reference_path), "--motor", "055U2B31", "--plot", "none"],
                    "--motor", "unknown motor '055U2B31'", "055U2B30")


def test_pulley_with_zero_teeth_exit_2(capsys, reference_path):
    _one_line_error(capsys, ["size", str(reference_path), "--pulley-teeth", "0", "--plot", "none"],
                    "--pulley-teeth", "0 teeth")


def test_bad_catalogue_files_exit_2(capsys, reference_path, tmp_path):
    dup = tmp_path / "dup.toml"
    dup.write_text('[[belt]]\nname = "GT3-3MR-09"\nprofile = "GT3"\nwidth_mm = 9\nwidth_factor = 1.66\n'
                   'breaking_tension_glass_N = 1990\n', encoding="utf-8")
    _one_line_error(capsys, ["size", str(reference_path), "--catalogue", str(dup), "--plot", "none"],
                    str(dup), "belt[1].name", "duplicate", "gt3_belts.toml")
    nomotor = tmp_path / "m.toml"
    nomotor.write_text('[[motor]]\nname = "X"\nrated_speed_rpm = 3000\nrated_torque_N_m = 1\nstall_torque_N_m = 1\n'
                       'peak_torque_N_m = 3\n', encoding="utf-8")
    _one_line_error(capsys, ["size", str(reference_path), "--catalogue", str(nomotor), "--plot", "none"],
                    str(nomotor), "motor[1].rotor_inertia_kg_cm2", "missing")
    zero = tmp_path / "z.toml"
    zero.write_text('[[pulley]]\nname = "GT3-0"\nprofile = "GT3"\nteeth = 0\n', encoding="utf-8")
    _one_line_error(capsys, ["size", str(reference_path), "--catalogue", str(zero), "--plot", "none"],
                    str(zero), "pulley[1].teeth")


def test_problem_without_drive_section_exit_2(capsys, write_problem):
    cut = write_problem(lambda t: t[: t.index("# ----", t.index("[transmission]"))]
                        + t[t.index("# ----", t.index("[drive]")):])
    _one_line_error(capsys, ["size", str(cut), "--plot", "none"], "drive", "no [drive] section")


def test_set_override_reaches_the_drive(capsys, reference_path):
    code = main(["size", str(reference_path), "--json", "--plot", "none", "--motor", "055U2B30",
                 "--pulley-teeth", "28", "--spm", "600", "--set", "drive.peak_limit_pct=100"])
    data = json.loads(capsys.readouterr().out)
    c = data["candidates"][0]
    # the torque limit min(motor peak 5.5, 100 % x rated 1.2) = 1.2 N m binds, named once (not as 'overload')
    assert code == 1 and data["status"] == "infeasible"
    assert data["inputs"]["peak_limit_pct"] == 100 and not c["feasible"] and c["binding"] == "peak_torque"
    assert c["torque_limit_N_m"] == pytest.approx(1.2)


def test_problem_motor_and_belt_must_be_in_the_catalogue(capsys, reference_path):
    _one_line_error(capsys, ["size", str(reference_path), "--plot", "none", "--set", "drive.motor=055U2B99"],
                    str(reference_path), "drive.motor", "unknown motor '055U2B99'")
    _one_line_error(capsys, ["size", str(reference_path), "--plot", "none", "--set", "drive.belt=GT3-3MR-12"],
                    str(reference_path), "drive.belt", "unknown belt 'GT3-3MR-12'")
