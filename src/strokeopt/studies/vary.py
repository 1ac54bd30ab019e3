"""A scene's results over numbers of the problem: ``strokeopt simulate --vary``.

:func:`vary_scene` simulates a scene at one rate with one or more fields of the problem (``--set`` paths: a
contact's gap, a body's mass, a spring's stiffness, a pad law's coefficient) stepped together, on the study
runner (runner.py): a sweep of one number, or a coupled move of several (the impact point of the needle bar:
gap N smaller and the pad's gap H larger by the same amount, ``--vary model.contacts.c32.gap_mm-=0:5:1 --vary
model.contacts.pad.gap_mm+=0:5:1``). Each step's problem is the file's with that step's ``--set`` texts, checked
as the file is (every step before any is simulated); report/contact.py prints and draws the rows.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ..contact.simulate import SimulationOptions, simulate_scene
from ..errors import ProblemError
from ..io.fields import number_in
from ..io.ranges import parse_range
from .runner import run_study

#: ``FIELD=A:B:STEP`` (the values), ``FIELD+=A:B:STEP`` / ``FIELD-=A:B:STEP`` (added to / taken from the file's value)
_VARY = re.compile(r"^\s*(?P<field>[A-Za-z_][\w.\[\]\-]*?)\s*(?P<op>\+=|-=|=)\s*(?P<values>\S.*?)\s*$")
#: Fields a step cannot take: the rate is the run's (``--spm``; a sweep of rates is ``--spm START:STOP:STEP``)
_NOT_VARIED = {"machine.spm": "the rate is the run's: sweep it with --spm START:STOP:STEP (or give one --spm)"}


@dataclass(frozen=True)
class Vary:
    """One ``--vary``: the problem field (a ``--set`` path) and its values in the field's unit, absolute or as a
    shift of the file's ``nominal`` (``sign`` +1 or -1; 0: absolute)."""

    field: str
    values: tuple
    nominal: float
    sign: int = 0

    def value(self, k: int) -> float:
        v = self.values[k]
        return v if self.sign == 0 else self.nominal + self.sign * v


def parse_vary(texts, problem, option: str = "--vary") -> list[Vary]:
    """The ``--vary`` options: each ``FIELD=A:B:STEP`` (or one value), ``FIELD+=...`` or ``FIELD-=...`` (a shift of
    the file's value); several move together, step by step (a coupled move: ``--vary model.contacts.c32.gap_mm-=0:5:1
    --vary model.contacts.pad.gap_mm+=0:5:1`` moves the impact point), so they must have as many values each. The
    field must be a number of the problem and every value one the problem file accepts (ProblemError naming it)."""
    out = []
    for text in texts:
        m = _VARY.match(str(text))
        if m is None:
            raise ProblemError(option, str(text), "expected FIELD=START:STOP:STEP or FIELD=VALUE (FIELD+=..., FIELD-=... "
                                                  "shift the file's value; no other operator), e.g. "
                                                  "'model.contacts.c32.gap_mm=5:7.4:0.2'")
        field = m["field"]
        if field in _NOT_VARIED:
            raise ProblemError(option, field, _NOT_VARIED[field])
        nominal = number_in(problem.data, field, problem.file, option)
        values = parse_range(m["values"], f"{option} {field}", "VALUE")
        out.append(Vary(field, tuple(values), nominal, {"=": 0, "+=": 1, "-=": -1}[m["op"]]))
    if len({v.field for v in out}) != len(out):
        raise ProblemError(option, "", "names a field twice")
    counts = {len(v.values) for v in out}
    if len(counts) > 1:
        raise ProblemError(option, "", "fields varied together need as many values each, got "
                                       + ", ".join(f"{v.field}: {len(v.values)}" for v in out))
    for k in range(len(out[0].values) if out else 0):
        try:
            problem.with_overrides(vary_overrides(out, k))
        except ProblemError as exc:
            raise ProblemError(option, exc.field, f"at step {k + 1} ("
                               + ", ".join(f"{v.field} = {v.value(k):g}" for v in out)
                               + f") the problem refuses it: {exc.message}") from None
    return out


def vary_overrides(varies: list[Vary], k: int) -> list[str]:
    """The ``--set`` texts of step ``k`` of ``varies``."""
    return [f"{v.field}={v.value(k)!r}" for v in varies]


def vary_scene(problem, scene: str, spm: float, varies: list[Vary], options: SimulationOptions | None = None,
               runner=None, progress: bool = False, stroke=None) -> list[dict]:
    """Summaries of :func:`simulate_scene` at ``spm`` with the fields of ``varies`` stepped together (one row per
    step: the fields' values under ``"varied"``, then the scene's results; a step that fails has ``"failed"``), on
    the study runner (studies/runner.py; None: in this process); ``stroke``: a design's stroke (default: the
    problem's law at each step)."""
    bar = None
    if progress:
        from tqdm import tqdm

        def bar(items):
            return tqdm(items, desc=f"simulating {scene}", unit="step", leave=False)

    steps = list(range(len(varies[0].values))) if varies else []
    outcomes = run_study(_vary_step, steps, (problem, scene, spm, tuple(varies), options, stroke), runner=runner,
                         progress=bar, chained=False)
    rows = []
    for k, out in zip(steps, outcomes):
        varied = {v.field: v.value(k) for v in varies}
        rows.append({"varied": varied, **(out.row if out.error is None else {"failed": out.error})})
    return rows


def _vary_step(shared, k, warm):
    problem, scene, spm, varies, options, stroke = shared
    sampled = problem.with_overrides(vary_overrides(list(varies), k))
    return simulate_scene(sampled, scene, spm, stroke=stroke, options=options).summary(), None
