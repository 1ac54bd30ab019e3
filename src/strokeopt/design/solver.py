"""Solving a prepared NLP with CasADi's nlpsol (IPOPT, or Bonmin for a motor choice).

Fourth step of the design's flow (:mod:`.nlp` -> solver -> :mod:`.refine`). Options are plain
dicts passed to CasADi over :data:`DEFAULT_SOLVER_OPTIONS`; a solver is built once per NLP
structure and options (:attr:`.nlp.Graph.solvers`) and nothing is printed unless asked.
"""

from __future__ import annotations

import numpy as np

import casadi as ca

from .._stdout import stdout_to

#: Default IPOPT options (plain dict, passed through to CasADi's nlpsol).
DEFAULT_SOLVER_OPTIONS = {
    "expand": True,
    "print_time": False,
    "ipopt.print_level": 0,
    "ipopt.sb": "yes",
    "ipopt.tol": 1e-9,
    # Feasible designs converge in 20-40 iterations (every solve of the test suite and the reference
    # sweep: 36 at most); an infeasible motor of a catalogue search ran to any limit given (500:
    # 7 s) before the relaxed diagnosis names its limit. Raise it in [design.solver].
    "ipopt.max_iter": 200,
}

#: IPOPT's return statuses of a solution.
STATUS_OK = ("Solve_Succeeded", "Solved_To_Acceptable_Level")


def solver_options(settings, extra: dict | None, verbose: bool) -> dict:
    """The options of a solve: the defaults, ``--verbose``, ``[design.solver]``, then ``extra``."""
    opts = dict(DEFAULT_SOLVER_OPTIONS)
    if verbose:
        opts.update({"ipopt.print_level": 5, "print_time": True})
        opts.pop("ipopt.sb", None)
    opts.update(settings.solver_options)
    opts.update(extra or {})
    return opts


def solve_nlp(nlp, options: dict):
    """Solve ``nlp`` (:class:`~.nlp.Nlp`); the solver (CasADi's costly derivative generation) is built once per
    structure and options."""
    g = nlp.graph
    b = g.built
    opts = dict(options)
    plugin = opts.pop("plugin", "ipopt")
    key = repr(sorted(options.items()))
    solver = g.solvers.get(key)
    if solver is None:
        w, gs, p = ca.vertcat(*b.w), ca.vertcat(*b.g), ca.vertcat(*b.p)
        if plugin == "bonmin":
            opts = {k: v for k, v in opts.items() if not k.startswith("ipopt.")}
            opts.update({"bonmin.print_level": 0, "bonmin.bb_log_level": 0, "bonmin.nlp_log_level": 0,
                         "bonmin.fp_log_level": 0, "bonmin.lp_log_level": 0, "bonmin.milp_log_level": 0,
                         "bonmin.oa_log_level": 0})
            if g.discrete is not None:
                discrete = np.zeros(w.shape[0], dtype=bool)
                offset, count = b.offsets[g.discrete[0]]
                discrete[offset:offset + count] = True
                opts["discrete"] = discrete.tolist()
        solver = ca.nlpsol("design", plugin, {"x": w, "f": g.f, "g": gs, "p": p}, opts)
        g.solvers[key] = solver
    nums = nlp.numbers
    args = dict(x0=nums.x0, lbx=nums.lbx, ubx=nums.ubx, lbg=nums.lbg, ubg=nums.ubg, p=nums.p)
    if plugin == "bonmin" and not options.get("ipopt.print_level", 0):
        with stdout_to(None):  # Bonmin's branch-and-bound log ignores its log-level options
            sol = solver(**args)
    else:
        sol = solver(**args)
    return sol, solver.stats(), solver
