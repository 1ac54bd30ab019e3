"""Solving a prepared NLP with CasADi's nlpsol (IPOPT, or Bonmin for a motor choice).

Fourth step of the design's flow (:mod:`.nlp` -> solver -> :mod:`.refine`). Options are plain
dicts passed to CasADi over :data:`DEFAULT_SOLVER_OPTIONS`; a solver is built once per NLP
structure and options (:attr:`.nlp.Graph.solvers`) and nothing is printed unless asked.
"""

from __future__ import annotations

import re
import tempfile
from functools import cache

import numpy as np

import casadi as ca

from ..._stdout import stdout_to
from ...io.fields import did_you_mean

#: Default IPOPT options (plain dict, passed through to CasADi's nlpsol).
DEFAULT_SOLVER_OPTIONS = {
    # Not expanded to SX: the servo term's dense rows (kernel weights x accelerations at every
    # instant of the handover window) took 6 s per solver build expanded, 0.25 s as MX; the
    # reference solve 3.0 s instead of 3.5 s, the catalogue min_time 4.4 s instead of 5.9 s.
    "expand": False,
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


#: The solvers a ``[design.solver]`` ``plugin`` may name: IPOPT (the default) and Bonmin (what
#: ``motor_choice = "bonmin"`` uses); others are not built with strokeopt's CasADi or not handled here.
PLUGINS = ("ipopt", "bonmin")


def check_solver_options(options: dict) -> tuple[str, str] | None:
    """The first option of ``options`` (``[design.solver]``) the solver refuses, as ``(key, why)``; None if all
    are good. Asks CasADi and IPOPT themselves, before any design is built: a one-variable NLP is built and
    solved (a few ms) with each option over :data:`DEFAULT_SOLVER_OPTIONS`."""
    opts = dict(options)
    plugin = opts.pop("plugin", "ipopt")
    if plugin not in PLUGINS or not ca.has_nlpsol(plugin):
        return "plugin", (f"{plugin!r} is not a solver strokeopt can use here; use 'ipopt' (the default) or "
                          "'bonmin' (motor_choice = \"bonmin\" chooses it)")
    for key, value in opts.items():
        trial = {**DEFAULT_SOLVER_OPTIONS, key: value}
        if plugin == "bonmin":
            trial = {k: v for k, v in trial.items() if not k.startswith("ipopt.")}
        reason = _refusal(plugin, trial)
        if reason is None:
            continue
        message, log = reason
        name = key.split(".", 1)[1] if key.startswith("ipopt.") else key
        if "Unknown option" in message or "No such IPOPT option" in message:
            return key, (f"unknown solver option{did_you_mean(key, _option_names(plugin))} (CasADi's nlpsol "
                         f"options, or 'ipopt.NAME' for an IPOPT option)")
        illegal = re.search(r"Illegal type for \w+: (.*)", message)
        if illegal:
            return key, f"wrong type, got {value!r} ({illegal.group(1).strip()})"
        doc = _ipopt_doc(name) if key.startswith("ipopt.") else ""
        doc = f" (IPOPT: {doc}, default in parentheses)" if doc else ""
        if "type mismatch" in message:
            return key, f"wrong type, got {value!r}{doc}"
        if "Invalid options were detected" in message:
            return key, f"{value!r} is not a valid setting{doc}"
        if message == "Invalid_Option":
            return key, f"IPOPT refuses {value!r} (Invalid_Option: not available in this IPOPT build?){doc}"
        found = re.search(r"Exception message: (.*)", log)
        return key, f"the solver refuses {value!r}: " + (found.group(1).strip() if found else message.splitlines()[-1])
    return None


def _refusal(plugin: str, opts: dict) -> tuple[str, str] | None:
    """Build and solve ``min x^2`` with ``opts``: None if the solver takes them, else (error, solver output)."""
    x = ca.SX.sym("x")
    message = None
    with tempfile.TemporaryFile(mode="w+") as log:
        with stdout_to(log.fileno()):
            try:
                solver = ca.nlpsol("check_options", plugin, {"x": x, "f": x**2}, opts)
                solver(x0=1.0)
                if solver.stats()["return_status"] == "Invalid_Option":
                    message = "Invalid_Option"
            except RuntimeError as exc:
                message = str(exc)
        log.seek(0)
        text = log.read()
    return None if message is None else (message, text)


@cache
def _ipopt_documentation() -> dict[str, str]:
    """IPOPT's own option list: name -> its range or default as IPOPT prints it (``0 <= (3000) < +inf``)."""
    x = ca.SX.sym("x")
    with tempfile.TemporaryFile(mode="w+") as log:
        with stdout_to(log.fileno()):
            ca.nlpsol("options", "ipopt", {"x": x, "f": x**2},
                      {"print_time": False, "ipopt.sb": "yes", "ipopt.print_options_documentation": "yes",
                       "ipopt.max_iter": 0})(x0=1.0)
        log.seek(0)
        text = log.read()
    lines = re.finditer(r"^([a-z][a-z0-9_]*) +(\S.*?)\s*$", text, flags=re.M)
    return {m.group(1): re.sub(r"\(\s+", "(", " ".join(m.group(2).split())) for m in lines}


def _ipopt_doc(name: str) -> str:
    return _ipopt_documentation().get(name, "")


def _option_names(plugin: str) -> list[str]:
    names = list(ca.nlpsol_options(plugin))
    if plugin == "ipopt":
        names += [f"ipopt.{n}" for n in _ipopt_documentation()]
    return names


#: Iterations of a continued solve: IPOPT stopped at its iteration limit on a feasible iterate, still on its way
#: (the contact design's min_time without a jerk bound, 420 -> 483.7 spm: more than 200 iterations, converged
#: within this). An infeasible iterate at the limit is not continued: the diagnosis names the limit.
CONTINUE_MAX_ITER = 1500
#: The largest constraint violation of an iterate that counts as feasible for a continued solve.
CONTINUE_INF_PR = 1e-6


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
    structure and options. A solve that stops at IPOPT's iteration limit on a feasible iterate is continued
    from there once, with :data:`CONTINUE_MAX_ITER` iterations."""
    sol, stats, solver = _solve(nlp, options)
    if options.get("plugin", "ipopt") == "ipopt" and stats.get("return_status") == "Maximum_Iterations_Exceeded":
        inf_pr = (stats.get("iterations") or {}).get("inf_pr") or [np.inf]
        if inf_pr[-1] <= CONTINUE_INF_PR and options.get("ipopt.max_iter", 0) < CONTINUE_MAX_ITER:
            more = {**options, "ipopt.max_iter": CONTINUE_MAX_ITER}
            sol, stats2, solver = _solve(nlp, more, x0=np.asarray(sol["x"]).ravel())
            stats = {**stats2, "iter_count": int(stats.get("iter_count", 0)) + int(stats2.get("iter_count", 0))}
    return sol, stats, solver


#: A constraint row with more nonzeros than this in its Jacobian is dense (the servo term's handover rows: every
#: node acceleration of the moves), and its group of rows gets a Jacobian of its own (:func:`constraint_jacobian`).
DENSE_ROW = 64


def constraint_jacobian(groups: list, w, p) -> ca.Function:
    """IPOPT's constraint Jacobian (CasADi's ``nlp_jac_g``: ``(x, p) -> (g, jac_g_x)``) of the rows ``groups`` (the
    :class:`~.nlp.Built`'s ``g``, in order), differentiated group by group where a group has a dense row.
    CasADi's Jacobian of all rows at once colours them together, and the dense rows then need one sweep through
    every row's graph each: the handover accuracy's 200 rows took 5-8 ms of every IPOPT iteration (a third of a
    held solve), apart 1 ms. The same numbers, the same sparsity."""
    blocks, run = [], []
    for rows in groups:
        sparsity = ca.jacobian_sparsity(rows, w)
        dense = sparsity.nnz() > 0 and int(np.max(np.diff(np.asarray(sparsity.T.colind())))) > DENSE_ROW
        if dense:
            blocks += [ca.vertcat(*run)] if run else []
            blocks.append(rows)
            run = []
        else:
            run.append(rows)
    blocks += [ca.vertcat(*run)] if run else []
    jac = ca.vertcat(*[ca.jacobian(rows, w) for rows in blocks]) if blocks else ca.MX(0, w.shape[0])
    return ca.Function("nlp_jac_g", [w, p], [ca.vertcat(*groups), jac], ["x", "p"], ["g", "jac_g_x"])


def _solve(nlp, options: dict, x0=None):
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
            found = None if g.drive_model is None else g.drive_model.discrete
            if found is not None:
                discrete = np.zeros(w.shape[0], dtype=bool)
                offset, count = b.offsets[found[0]]
                discrete[offset:offset + count] = True
                opts["discrete"] = discrete.tolist()
        if "jac_g" not in opts:
            opts["jac_g"] = constraint_jacobian(b.g, w, p)
        solver = ca.nlpsol("design", plugin, {"x": w, "f": g.f, "g": gs, "p": p}, opts)
        g.solvers[key] = solver
    nums = nlp.numbers
    args = dict(x0=nums.x0 if x0 is None else x0, lbx=nums.lbx, ubx=nums.ubx, lbg=nums.lbg, ubg=nums.ubg, p=nums.p)
    if plugin == "bonmin" and not options.get("ipopt.print_level", 0):
        with stdout_to(None):  # Bonmin's branch-and-bound log ignores its log-level options
            sol = solver(**args)
    else:
        sol = solver(**args)
    return sol, solver.stats(), solver
