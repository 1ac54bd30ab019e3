"""The kinematics and laws commands, as a user and a script see them."""

from __future__ import annotations

import json

import pytest

from strokeopt.cli.main import main


def test_kinematics_json(capsys, reference_path, tmp_path):
    fig = tmp_path / "k.png"
    assert main(["kinematics", str(reference_path), "--json", "--plot", str(fig)]) == 0
    out, err = capsys.readouterr()
    data = json.loads(out)  # stdout is only JSON
    assert data["spm"] == 500 and data["law"] == "modified_sine"
    assert [m["index"] for m in data["moves"]] == [1, 2, 3]
    assert [m["stroke_mm"] for m in data["moves"]] == pytest.approx([32, 35, 3])
    for key in ("v_max_m_s", "a_max_m_s2", "jerk_max_m_s3", "pulley_speed_max_deg_s", "pulley_accel_max_deg_s2"):
        assert all(m[key] > 0 for m in data["moves"]), key
    assert fig.stat().st_size > 10_000 and str(fig) in err


def test_kinematics_table_and_options(capsys, reference_path, tmp_path):
    assert main(["kinematics", str(reference_path), "--spm", "600", "--law", "modified_sine", "--chi", "0.125",
                 "--plot", "none"]) == 0
    out = capsys.readouterr().out
    assert "600 spm" in out and "chi = 0.125" in out and "move 3" in out


def test_unbounded_jerk_is_null_in_json(capsys, reference_path):
    assert main(["kinematics", str(reference_path), "--law", "parabolic", "--json", "--plot", "none"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert all(m["jerk_max_m_s3"] is None for m in data["moves"])


def test_laws_json(capsys):
    assert main(["laws", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["laws"]
    names = [r["law"] for r in rows]
    # the thesis's seven first, in its order, then the cam handbooks' laws: at least 15 in all
    assert names[:7] == ["parabolic", "cubic", "cosine", "modified_sine", "sine", "poly5", "poly7"]
    assert len(names) >= 15 and len(set(names)) == len(names)
    assert all(r["C_v"] > 1 and r["C_a"] > 3 and r["continuity"].startswith("C") for r in rows)


def test_laws_plot_draws_every_law(tmp_path, capsys):
    import matplotlib.image

    path = tmp_path / "laws.png"
    assert main(["laws", "--plot", str(path)]) == 0
    assert "figure written to" in capsys.readouterr().out
    assert matplotlib.image.imread(path).shape[0] > 1000  # four panels and a legend of 15 lines


def test_law_option_takes_parameters(capsys, reference_path):
    argv = ["kinematics", str(reference_path), "--json", "--plot", "none"]
    assert main([*argv, "--law", "trapezoidal_velocity:constant_speed_share=0.5"]) == 0
    half = json.loads(capsys.readouterr().out)
    assert main([*argv, "--law", "trapezoidal_velocity"]) == 0
    third = json.loads(capsys.readouterr().out)
    # C_v = 2/(1 + c): 4/3 at c = 1/2 against 3/2 at c = 1/3, on the same move time
    ratio = half["moves"][0]["v_max_m_s"] / third["moves"][0]["v_max_m_s"]
    assert ratio == pytest.approx((4 / 3) / 1.5, rel=1e-6)
    assert main([*argv, "--law", "trapezoidal_velocity:constant_speed_share"]) == 2
    assert "PARAM=NUMBER" in capsys.readouterr().err


def test_help_teaches(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["kinematics", "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert "--set" in out and "Example" in out


def test_solve_help_names_every_objective(capsys):
    from strokeopt.design.transcription.objectives import OBJECTIVES

    with pytest.raises(SystemExit):
        main(["solve", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    missing = [name for name in OBJECTIVES if name not in out]
    assert not missing, f"solve --help does not name {missing}"


def test_unwritable_figure_format_is_bad_input(capsys, reference_path, tmp_path):
    assert main(["kinematics", str(reference_path), "--plot", str(tmp_path / "k.txt")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--plot" in err and "'txt'" in err and ".png" in err


def test_json_stays_json_with_verbose_solver_logs(tmp_path):
    import subprocess
    import sys

    from conftest import ROOT

    run = subprocess.run([sys.executable, "-m", "strokeopt", "solve", str(ROOT / "problems/known_optima/min_jerk.toml"),
                          "--json", "--verbose", "--plot", "none"], capture_output=True, text=True, cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert json.loads(run.stdout)["status"] == "optimal"  # only JSON on stdout
    assert "Ipopt" in run.stderr  # the solver log went to stderr


@pytest.mark.parametrize("argv", [["solve", "{p}", "600"], ["verify", "out/design.json", "--spm", "700"]])
def test_an_option_in_the_wrong_place_gets_the_commands_usage(capsys, reference_path, argv):
    # before: the top level's usage ("strokeopt [-h] [--version] COMMAND ..."), which names no command
    argv = [a.replace("{p}", str(reference_path)) for a in argv]
    with pytest.raises(SystemExit) as exc:
        main(argv)
    err = capsys.readouterr().err
    assert exc.value.code == 2 and f"strokeopt {argv[0]}: error: unrecognized arguments" in err
    assert f"(see strokeopt {argv[0]} --help)" in err and len(err.strip().splitlines()) == 1  # one line, exit 2


def test_laws_at_parameters_of_ones_own(capsys):
    # the trapezoidal velocity with half the move at constant speed: C_v = 2/(1 + c) = 4/3, C_a = C_v/((1 - c)/2)
    assert main(["laws", "--json", "--law", "trapezoidal_velocity:constant_speed_share=0.5",
                 "--law", "modified_sine:chi=0.095"]) == 0
    rows = json.loads(capsys.readouterr().out)["laws"]
    assert [r["law"] for r in rows] == ["trapezoidal_velocity", "modified_sine"]
    assert (rows[0]["C_v"], rows[0]["C_a"]) == pytest.approx((4 / 3, 16 / 3), rel=1e-9)
    assert rows[1]["C_a"] == pytest.approx(5.373, abs=5e-4)  # thesis 4.4, chi = 0.095
    assert main(["laws", "--law", "s_curve:ramp=1"]) == 2
    assert "takes no parameter ramp" in capsys.readouterr().err
