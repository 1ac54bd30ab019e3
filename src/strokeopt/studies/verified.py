"""One verified pipeline: :func:`solve_verified` and :func:`verify_design`.

A design is solved on a rigid model of the drive (:func:`strokeopt.design.solve.solve_design`); what an
engineer builds from is that design *judged*: its stroke run through the full servo simulation (the
handover error of the real loop, belt and encoder: :func:`strokeopt.servo.accuracy.design_accuracy`) and
through the contact model's scenes (:func:`strokeopt.contact.verify.design_verification`), with one status
and one verdict. Every caller -- ``strokeopt solve`` and ``report``, the studies, the notebooks, the
README's Python example -- calls these two functions, so the answer does not depend on where it is asked.

The verdict has three states per criterion: met, failed, not judged (a criterion the problem sets no limit
for, with its value). A design with a failed criterion is ``limits exceeded`` or ``verification failed``;
one with unjudged criteria is "solved, N criteria not judged", never "verified".
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

from ..contact.verify import LIMIT_FIELDS, design_verification, verify
from ..design.compare import compare_with_laws
from ..design.result import design_summary
from ..design.solve import limit_of, solve_design, verified_handover
from ..io.plain import counted


@dataclass(frozen=True)
class VerifiedDesign:
    """A design with the simulations that judge it, one status and one verdict.

    ``design``: the :class:`~strokeopt.design.result.Design`; ``accuracy``: the full servo simulation
    (:class:`~strokeopt.servo.accuracy.AccuracyResult`; None without a ``[servo]`` section or a motor);
    ``verification``: the contact verification block of the design's scene (None without scenes);
    ``scenes``: every scene simulated, by name (:class:`~strokeopt.contact.simulate.SceneResult`);
    ``comparison``: the classic laws on the same drive (empty when not asked);
    ``status``: ``optimal`` (or the solver's word), ``limits exceeded`` or ``verification failed``;
    ``verdict``: one line saying what was judged and how; ``unjudged``: the criteria with a value and no limit.
    """

    design: Any
    accuracy: Any = None
    verification: dict | None = None
    scenes: dict = field(default_factory=dict)
    comparison: list = field(default_factory=list)
    status: str = ""
    verdict: str = ""
    unjudged: tuple = ()

    @property
    def problem(self):
        return self.design.problem

    @property
    def ok(self) -> bool:
        """Every judged criterion met (unjudged ones do not fail a design unless asked: ``strict``)."""
        return self.status not in FAILED_STATES

    def strict_ok(self) -> bool:
        """Every criterion judged and met (``--strict``: an unjudged criterion fails the design)."""
        return self.ok and not self.unjudged

    def summary(self) -> dict:
        """The JSON of ``strokeopt solve --json`` (without the drive's provenance, which the caller adds)."""
        out = design_summary(self.design)
        out["status"] = self.status
        out["verdict"] = self.verdict
        out["not_judged"] = [dict(r) for r in self.unjudged]
        if self.comparison:
            out["comparison"] = self.comparison
        return out

    def __repr__(self) -> str:
        d = self.design
        parts = [f"{d.objective} {d.objective_value:.6g} {d.objective_unit}", f"{d.spm:g} spm"]
        if d.motor:
            parts.append(f"motor {d.motor}")
        if d.pulley_teeth:
            parts.append(f"pulley {d.pulley_teeth} teeth")
        return f"VerifiedDesign({self.status}: {', '.join(parts)}; {self.verdict})"


#: The statuses of a design that must not be built (exit 1 on the command line).
FAILED_STATES = ("limits exceeded", "verification failed")


def solve_verified(problem, *, objective: str | None = None, spm: float | None = None, settings=None,
                   warm_start=None, compare: bool = True, scenes=None, options=None,
                   progress=None, verbose: bool = False) -> VerifiedDesign:
    """Solve the design problem of ``problem`` and judge the design: the one pipeline.

    The handover accuracy row of the design's checks is the full servo simulation's (the design's own
    error term beside it as ``design_term``); the design is re-simulated in its contact scene
    (``[design.contact] scene``, else ``release``, else the first) and in ``scenes`` (more scene names);
    ``compare``: the classic laws on the same drive beside it. ``objective``, ``spm``, ``settings``,
    ``warm_start``, ``progress`` (wraps the motors of a catalogue search) and ``verbose`` are
    :func:`~strokeopt.design.solve.solve_design`'s. Raises :class:`~strokeopt.errors.SolverError` when no
    design exists (naming the constraint).
    """
    chosen = settings or getattr(problem, "design", None)
    if chosen is not None and chosen.outer:  # a number the collocation does not carry: searched around this solve
        from .outer import solve_outer

        def solve(point, inner, warm):
            return solve_verified(point, objective=objective, spm=spm, settings=inner, warm_start=warm or warm_start,
                                  compare=False, scenes=scenes, options=options, verbose=verbose)

        found = solve_outer(problem, chosen, solve, progress=_bar(progress, "design.free." + chosen.outer[0].name))
        if not compare:
            return found
        return replace(found, comparison=compare_with_laws(found.design))
    design, accuracy = solve_checked(problem, objective=objective, spm=spm, settings=settings,
                                     warm_start=warm_start, progress=progress, verbose=verbose)
    return verify_design(design, accuracy=accuracy, compare=compare, scenes=scenes, options=options)


def _bar(progress, what: str):
    """A progress bar over the points of an outer search where the caller shows progress (tqdm on stderr)."""
    if progress is None:
        return None
    from tqdm import tqdm

    return lambda it: tqdm(it, desc=f"searching {what}", unit="point", leave=False)


def solve_checked(problem, *, objective: str | None = None, spm: float | None = None, settings=None,
                  warm_start=None, progress=None, verbose: bool = False):
    """The first half of :func:`solve_verified`: the design with its handover row from the full servo simulation
    (and that simulation's result, None without a servo), not yet re-simulated in its contact scenes
    (:func:`verify_design` is the second half; a study runs the two as separate tasks)."""
    held: dict = {}

    def full_simulation(design):
        from ..servo.accuracy import design_accuracy

        held["accuracy"] = design_accuracy(design)
        return held["accuracy"].handover_error, "full servo simulation"

    checked = getattr(problem, "servo", None) is not None and getattr(problem, "drive", None) is not None
    design = solve_design(problem, objective=objective, spm=spm, settings=settings,
                          warm_start=warm_start, verbose=verbose, progress=progress,
                          handover_check=full_simulation if checked else None)
    return design, held.get("accuracy")


def verify_design(design, *, accuracy=None, compare: bool = False, scenes=None, options=None,
                  scene: str | None = None) -> VerifiedDesign:
    """Judge a solved :class:`~strokeopt.design.result.Design` (a design.json is read back into one by
    ``design_from_data``): its full servo simulation (``accuracy`` if already made; a simulation made here
    replaces the handover row the design carries, so a design judged on a changed problem -- ``--set`` -- is
    judged by its own numbers), its contact verification in ``scene`` (default: the design's), the scenes
    ``scenes`` beside it, one status, one verdict."""
    problem = design.problem
    if accuracy is None and getattr(problem, "servo", None) is not None and design.motor_spec is not None:
        from ..servo.accuracy import design_accuracy

        accuracy = design_accuracy(design)
        design = _with_handover(design, accuracy.handover_error)
    results: dict = {}
    block = None
    if getattr(problem, "scenes", None):
        own = scene or _design_scene(design)
        results[own] = verify(design, own, options)
        block = design_verification(design, own, options, result=results[own])
        for name in scenes or ():
            if name not in results:
                results[name] = verify(design, name, options)
        failed = block["status"] != "ok" and design.status not in FAILED_STATES
        design = replace(design, verification=block, status="verification failed" if failed else design.status)
    unjudged = _unjudged(block)
    return VerifiedDesign(design, accuracy, block, results, compare_with_laws(design) if compare else [],
                          design.status, _verdict(design, block, unjudged), unjudged)


def _with_handover(design, error: float):
    """``design`` with its handover check row holding ``error`` [m] of a full simulation made now."""
    if design.settings is None or (design.drive is None and not any(c["name"].startswith("handover accuracy")
                                                                     for c in design.checks)):
        return design
    if not any(itv.handover for itv in design.problem.timing.intervals):
        return design
    rows = verified_handover(design.checks, error, "full servo simulation", design.settings.check_tolerance,
                             limit_of(design.settings, design.problem))
    return replace(design, checks=rows)


def _design_scene(design) -> str:
    """The scene a design is judged in: ``[design.contact] scene``, else ``release``, else the first."""
    from ..contact.scene import default_scene

    contact = getattr(getattr(design, "settings", None), "contact", None)
    return contact.scene if contact is not None and contact.scene else default_scene(design.problem.scenes)


def _unjudged(block: dict | None) -> tuple:
    """The criteria of a verification that have a value and no limit: ``{criterion, value, unit, field}``."""
    if block is None:
        return ()
    return tuple({"criterion": r["criterion"], "value": r["value"], "unit": r["unit"],
                  "field": f"design.contact.{LIMIT_FIELDS[r['criterion']]}"}
                 for r in block["criteria"] if r["ok"] is None and r["criterion"] in LIMIT_FIELDS)


def _verdict(design, block: dict | None, unjudged: tuple) -> str:
    """One line: what failed, or what was judged and met and what was not judged (with its value)."""
    if design.status == "limits exceeded":
        first = design.notes[0] if design.notes else ""
        return first if first.startswith("limits exceeded") else f"limits exceeded: {first}".rstrip(": ")
    if block is not None and block["status"] != "ok":
        return block["verdict"]
    judged = [c["name"] for c in design.checks if c.get("ok")]
    handover = next((c for c in design.checks if c["name"].startswith("handover accuracy")), None)
    met = []
    if handover is not None:
        unit = handover.get("unit", "mm")
        met.append(f"handover error {handover['value']:.4g} {unit} <= {handover['limit']:g} {unit}")
    if block is not None:
        met += [r["criterion"] for r in block["criteria"] if r["ok"] is True and r["criterion"] != "handover accuracy"]
    where = f" (scene {block['scene']!r})" if block is not None else ""
    # values reported beside the criteria (an elastic chain's link forces): no limit exists for them, so they
    # are named as reported, never counted as met
    reported = [r for r in (block or {}).get("criteria", []) if r["ok"] is None and r["criterion"] not in LIMIT_FIELDS]
    also = ("; reported, no limit: " + ", ".join(f"{r['criterion']} {r['value']:.4g} {r['unit']}" for r in reported)
            if reported else "")
    if unjudged:
        values = ", ".join(f"{r['criterion']} {r['value']:.4g} {r['unit']}" for r in unjudged)
        fields = ", ".join(r["field"] for r in unjudged)
        return (f"solved, {counted(len(unjudged), 'criterion', 'criteria')} not judged{where}: {values} (no limit: set {fields}); "
                f"met: {', '.join(met) or 'the design limits'}{also}")
    if block is None and handover is None:
        limits = f"{counted(len(judged), 'design limit')} met on the rigid model" if judged else "no limit to check"
        return f"solved: {limits}; nothing re-simulated (no [servo] section, no scenes)"
    return f"verified{where}: " + ", ".join(met + [f"{counted(len(judged), 'design limit')} met"]) + also
