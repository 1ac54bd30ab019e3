"""Verifying a design by re-simulation: its optimised stroke through a scene of the contact model.

A design (design/) is solved on a rigid model of the drive; :func:`verify` runs its
stroke, at its stitch rate, through a scene of its problem's contact model
(simulate.py) and returns the :class:`~strokeopt.contact.simulate.SceneResult`, the
same results ``strokeopt simulate`` reports for a classic law. It takes the
``Design`` a solve returns, or a ``DesignStroke`` read back from a
``design.json`` by :func:`strokeopt.files.design_file.load_design` (what ``strokeopt verify`` does).
"""

from __future__ import annotations

from ..drive.checks import within_limit
from .simulate import SceneResult, SimulationOptions, simulate_scene


#: How far the simulated impact velocity may exceed its limit before verification fails: the design holds the
#: rigid cluster's velocity at the stop, the simulation adds the follower's motion on its contact and pad
#: (measured: 0.01-0.5 % above the designed value).
IMPACT_TOLERANCE = 0.02


def _row(criterion: str, value, limit, unit: str, ok) -> dict:
    return {"criterion": criterion, "value": value, "limit": limit, "unit": unit, "ok": ok}


def verification(result: SceneResult, lag_max: float | None = None, impact_velocity_max: float | None = None,
                 handover: dict | None = None, reported: tuple = (), implausible: list | tuple = ()) -> dict:
    """The verdict of a simulated cycle against the design's criteria, one row each (value, limit, pass/fail):

    * premature release: gap N closed (or the needle released) before the impact -- always judged;
    * lag: the largest lag before the impact against ``lag_max`` [m] (None: reported, not judged);
    * impact velocity against ``impact_velocity_max`` [m/s] (None: reported, not judged), within
      :data:`IMPACT_TOLERANCE`;
    * handover accuracy: ``handover``, a check row of the design (``value``, ``limit`` in mm, ``ok``), if given;
    * ``reported``: more rows (criterion, value, unit), reported and not judged (an elastic chain's link forces);
    * ``implausible``: peak forces beyond what the model can carry (plausible.py's rows): one failed row
      "plausible forces" naming them, so that a force of the model taken where it does not hold is never "ok".

    Returns ``{"scene", "status": "ok" | "verification failed", "criteria": [...], "failed": [names], "verdict"}``.
    """
    m = result.metrics
    rows = []
    if m["gap_N_mm"] is not None:
        premature = bool(m["premature_release"])
        rows.append(_row("premature release", premature, False, "", not premature))
    if m["max_lag_mm"] is not None:
        lag = m["max_lag_mm"]
        rows.append(_row("lag", lag, None if lag_max is None else lag_max * 1e3, "mm",
                         None if lag_max is None else bool(lag <= lag_max * 1e3)))
    if m["impact_velocity_m_s"] is not None:
        v = abs(m["impact_velocity_m_s"])
        rows.append(_row("impact velocity", v, impact_velocity_max, "m/s", None if impact_velocity_max is None
                         else within_limit(v, impact_velocity_max, IMPACT_TOLERANCE)))
    if handover is not None:
        rows.append(_row("handover accuracy", handover["value"], handover["limit"], handover.get("unit", "mm"),
                         bool(handover["ok"])))
    rows += [_row(criterion, value, None, unit, None) for criterion, value, unit in reported]
    if implausible:
        from .plausible import implausible_text

        worst = implausible[0]
        rows.append({**_row("plausible forces", worst["value"], worst["limit"], "N", False),
                     "detail": implausible_text(implausible) + " (more than the scene's bodies and springs can load "
                                                                "any element with: contact/plausible.py)",
                     "forces": [dict(r) for r in implausible]})
    failed = [r for r in rows if r["ok"] is False]
    if failed:
        verdict = "verification failed: " + "; ".join(
            r["criterion"] + (f": {r['detail']}" if "detail" in r else " (gap N closes before the impact)"
                              if r["unit"] == "" else
                              f" {r['value']:.4g} {r['unit']} > limit {r['limit']:.4g} {r['unit']}") for r in failed)
    else:
        judged = [r["criterion"] for r in rows if r["ok"]]
        # a criterion without a limit is named with its value, so that "verified" never hides it
        unjudged = [r for r in rows if r["ok"] is None and r["criterion"] not in {c for c, _, _ in reported}
                    and isinstance(r["value"], (int, float)) and not isinstance(r["value"], bool)]
        fields = ", ".join(LIMIT_FIELDS.get(r["criterion"], r["criterion"]) for r in unjudged)
        values = ", ".join(f"{r['criterion']} {r['value']:.4g} {r['unit']}" for r in unjudged)
        # "verified" only when every criterion was judged: unjudged ones are named with their values
        verdict = (("verified" if not unjudged else f"checked ({len(unjudged)} not judged)") +
                   f" in scene {result.scene!r} at {result.spm:g} spm: " +
                   (", ".join(judged) + " within limits" if judged else "no criterion to judge") +
                   (f"; not judged (no [design.contact] {fields}): {values}" if unjudged else "") +
                   ("; " + ", ".join(f"{c} {v:.4g} {u}" for c, v, u in reported) + " (reported)" if reported else ""))
    return {"scene": result.scene, "spm": result.spm, "status": "verification failed" if failed else "ok",
            "criteria": rows, "failed": [r["criterion"] for r in failed], "verdict": verdict}


#: The [design.contact] field that sets the limit of a criterion (named where a criterion is not judged).
LIMIT_FIELDS = {"lag": "lag_max_mm", "impact velocity": "impact_velocity_max_m_s"}


def design_verification(design, scene: str | None = None, options: SimulationOptions | None = None,
                        result: SceneResult | None = None) -> dict | None:
    """Re-simulate a solve's ``Design`` in ``scene`` (default: its ``[design.contact]`` scene, else ``release``
    or the first) and judge it (:func:`verification`) by its ``[design.contact]`` limits and its handover
    check row (``result``: the scene's simulation if already made). None when the problem has no scenes."""
    from .scene import default_scene

    problem = design.problem
    if not getattr(problem, "scenes", None):
        return None
    contact = getattr(getattr(design, "settings", None), "contact", None)
    scene = scene or (contact.scene if contact is not None and contact.scene else default_scene(problem.scenes))
    result = result if result is not None else verify(design, scene, options)
    handover = next((c for c in design.checks if c["name"].startswith("handover accuracy")), None)
    from .chain import chain_results  # a model on a transmission's members: its links' peak forces

    links = chain_results(problem, result, design.stroke).get("links", [])
    reported = tuple((f"peak force of link {k['link']}", k["peak_abs"], k["unit"]) for k in links)
    from .plausible import scene_implausible

    block = verification(result, None if contact is None else contact.lag_max,
                         None if contact is None else contact.impact_velocity_max, handover, reported,
                         scene_implausible(problem, result, design.stroke))
    block["cpu_time_s"] = result.cpu_time_s
    return block


def verify(design, scene: str, options: SimulationOptions | None = None) -> SceneResult:
    """Re-simulate ``design`` (a solve's ``Design``, or a ``DesignStroke`` read back from a design.json by
    :func:`strokeopt.files.design_file.load_design`): its stroke, at its stitch rate, through ``scene`` of
    its problem's contact model."""
    return simulate_scene(design.problem, scene, design.spm, stroke=design.stroke, options=options)
