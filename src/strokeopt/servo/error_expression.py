"""The form in which a handover error term enters the design's NLP: :class:`ErrorExpression`.

It lives here, on the servo's floor, because the servo's term (:mod:`.kernel`) returns one and the
servo package does not import the design package above it; the design names it
:class:`strokeopt.design.transcription.request.ErrorExpression` (the same class) and sums the terms it is given.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class ErrorExpression:
    """A handover error term in the NLP: ``signed``, the error [m] at each instant the term checks
    (a CasADi column; the terms of one design check the same instants, or a scalar for all of
    them), and ``bound``, a magnitude [m] added at every instant (an encoder count). The design
    holds ``-accuracy <= signed_total -/+ bound_total <= accuracy`` row by row: constraints
    linear in the signed error, where a maximum of absolute values would be neither smooth nor
    sparse."""

    signed: Any
    bound: Any = 0.0
