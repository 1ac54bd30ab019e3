"""The command line does what it says: --set KEY=null removes a key, solve takes --law and --strict, figures of
runs with different --set texts get different names, no handover note on a machine without a handover."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from strokeopt import load_problem
from strokeopt.cli.main import main

PROBLEMS = Path(__file__).resolve().parents[2] / "problems"
REFERENCE = PROBLEMS / "deco2000_needle_bar.toml"


def test_set_null_removes_a_key(capsys):
    # before: --set 'motion.law="poly5"' was refused ("law 'poly5' takes no parameter chi") with no way to
    # remove the file's chi
    assert main(["kinematics", str(REFERENCE), "--set", 'motion.law="poly5"', "--plot", "none"]) == 2
    assert "chi" in capsys.readouterr().err
    assert main(["kinematics", str(REFERENCE), "--set", 'motion.law="poly5"', "--set", "motion.chi=null",
                 "--json", "--plot", "none"]) == 0
    assert json.loads(capsys.readouterr().out)["law"].startswith("poly5")
    p = load_problem(REFERENCE, ['motion.law="poly5"', "motion.chi=null"])
    assert p.default_law.name == "poly5" and "chi" not in p.data["motion"]
    assert main(["kinematics", str(REFERENCE), "--set", "motion.nochi=null", "--plot", "none"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "motion.nochi" in err[0] and "no such field to remove" in err[0] and "'chi'" in err[0]


def test_figure_names_follow_the_overrides(tmp_path, monkeypatch):
    from strokeopt.cli import common
    from strokeopt.cli.parser import build_parser

    parser = build_parser()

    def path(argv):
        args = parser.parse_args(argv)
        args.typed_overrides = tuple(args.overrides)  # as main() records them
        return common._plot_path(args, "simulate", "release")

    plain = path(["simulate", str(REFERENCE)])
    k2 = path(["simulate", str(REFERENCE), "--set", "model.springs.k2.stiffness_N_m=1240"])
    k2b = path(["simulate", str(REFERENCE), "--set", "model.springs.k2.stiffness_N_m=1500"])
    assert len({plain, k2, k2b}) == 3 and k2.name.startswith(plain.stem + "_set-")


def test_no_handover_note_without_a_handover():
    # the knitting drive has no handover: its solve says nothing about a handover accuracy (before: "handover
    # accuracy 0.5 mm NOT checked")
    from strokeopt import solve_design

    problem = load_problem(PROBLEMS / "knitting_stitch_density.toml")
    design = solve_design(problem, objective="min_time")
    assert not any("handover" in n for n in design.notes)


@pytest.mark.slow  # two reference solves
def test_solve_law_and_strict(capsys):
    # --strict: a criterion without a limit (the reference's lag and impact velocity) fails the design, exit 1
    assert main(["solve", str(REFERENCE), "--plot", "none", "--json"]) == 0
    default = json.loads(capsys.readouterr().out)
    assert [r["criterion"] for r in default["not_judged"]] == ["lag", "impact velocity"]
    assert main(["solve", str(REFERENCE), "--plot", "none", "--strict", "--law", "poly5", "--json"]) == 1
    out, err = capsys.readouterr()
    data = json.loads(out)
    assert err.strip().startswith("strokeopt: --strict: solved, 2 criteria not judged")
    # --law sets every move's law, so the jerk bound taken from the law is poly5's
    assert data["status"] == "optimal" and data["verdict"] != default["verdict"]


def test_set_reaches_ipopt_options(capsys):
    # before: IPOPT options could be set in the file only ("ipopt.max_iter" = 500 in [design.solver])
    from strokeopt import load_problem

    known = PROBLEMS / "known_optima" / "min_jerk.toml"
    p = load_problem(known, ["design.solver.ipopt.tol=1e-10"])
    assert p.design.solver_options == {"ipopt.tol": 1e-10}
    assert main(["kinematics", str(known), "--set", "design.solver.ipopt.nope=1", "--plot", "none"]) == 2
    err = capsys.readouterr().err
    assert "design.solver.ipopt.nope: unknown solver option" in err
