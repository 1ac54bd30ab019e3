"""The machine's cycle in words: what one cycle of the machine is called and its rate's unit.

A sewing machine makes stitches (its rate in spm, stitches per minute), a loom picks (picks/min), a test
rig test cycles. ``[machine] cycle`` names it (default "stitch"); ``machine.spm`` and ``--spm`` keep their
names and mean cycles per minute of that cycle. Every text, report and figure label takes its words here.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

#: A cycle noun: one to three lower-case words (letters, hyphens), at most 24 characters.
CYCLE_NOUN = re.compile(r"[a-z][a-z-]*( [a-z][a-z-]*){0,2}")


@dataclass(frozen=True)
class MachineCycle:
    """The words of one cycle of the machine (``noun``: "stitch", "pick", "test cycle")."""

    noun: str = "stitch"

    @property
    def plural(self) -> str:
        return self.noun + ("es" if self.noun.endswith(("s", "sh", "ch", "x", "z")) else "s")

    @property
    def rate_unit(self) -> str:
        """The rate's unit: 'spm' for stitches (the trade's word), else '<plural>/min' ('picks/min')."""
        return "spm" if self.noun == "stitch" else f"{self.plural}/min"

    @property
    def rate_name(self) -> str:
        """'stitch rate', 'pick rate'."""
        return f"{self.noun} rate"

    def rate(self, value: float) -> str:
        """'600 spm', '200 picks/min'."""
        return f"{value:g} {self.rate_unit}"

    def count(self, n: str) -> str:
        """'1 stitch', '2 stitches' (``n``: the count as printed)."""
        return f"{n} {self.noun if n == '1' else self.plural}"


STITCH = MachineCycle()


def cycle_of(obj) -> MachineCycle:
    """The cycle of a problem, a design (its problem) or a summary dict ('cycle': the noun); else a stitch."""
    if isinstance(obj, MachineCycle):
        return obj
    if isinstance(obj, dict):
        return MachineCycle(obj["cycle"]) if obj.get("cycle") else STITCH
    cycle = getattr(obj, "cycle", None)
    if isinstance(cycle, MachineCycle):
        return cycle
    problem = getattr(obj, "problem", None)
    return cycle_of(problem) if problem is not None and problem is not obj else STITCH
