"""Where the driven body may go: the travel the model's gaps and stops leave it, against the stroke.

A contact ``bodies = [a, b]`` with gap ``g`` stays open while ``x_a - x_b <= g`` (model.py: its
compression ``x_a - x_b - g`` is negative). A chain of contacts from the driven body ``d`` to the frame,
``d -> b1 -> ... -> frame``, therefore lets ``d`` move forward by at most the sum of the chain's gaps
before every contact of it is closed and ``d`` presses the chain into the frame; a chain from the frame
to ``d`` bounds its travel backward. The shortest such chains (Dijkstra on the gaps, which are never
negative) are the travel the model leaves the driven body: on the reference needle bar the shell meets
the frame through c13 (gap P 3.6 mm), c32 (gap N 7.4 mm) and the pad (gap H 23 mm), 34 mm below the
upper dwell, and nothing stops it upward.

A stroke that takes the driven body beyond that travel does not fit the mechanism: the position the
stroke commands is then only reached by pushing the closed contacts and the pad into each other, and
the forces a simulation reports are those of the penetration, not of the motion (every stroke x1000 on
the reference: a 32 m move, 1.6e10 N through the pad). :func:`check_travel` refuses such a problem
when it is read, naming the interval whose end lies beyond and the chain that stops it. The positions
checked are the ends of the intervals (the dwells and the handover position): a classic law moves
monotonically between them. Springs, grips and links do not bound the travel (they stretch or act
both ways); only contacts are stops.
"""

from __future__ import annotations

import heapq
import math

from .model import FRAME, Model

#: How far past a chain's gaps a stroke may reach [m]: the rounding of positions stated in mm, nothing more
#: (a stroke that closes a chain exactly touches the frame with no force).
TRAVEL_TOLERANCE = 1e-9


def _coordinate(model: Model, name: str):
    """The coordinate a body moves on: its transmission stage (None: the model's own axis)."""
    return model.bodies[name].stage if name != FRAME else None


def _shortest(model: Model, start: str, end: str) -> tuple[float, list[str]]:
    """The smallest sum of contact gaps on a chain from ``start`` to ``end`` (each contact ``[a, b]`` an
    edge a -> b: ``x_a - x_b <= gap``), with the contacts on it in order; ``(inf, [])`` if none. Only
    bodies on the driven body's coordinate take part (a contact across a transmission's members compares
    coordinates of different members)."""
    own = _coordinate(model, model.driven)
    edges: dict[str, list[tuple[str, float, str]]] = {}
    for el in model.contacts.values():
        if el.kind != "contact" or any(b != FRAME and _coordinate(model, b) != own for b in el.bodies):
            continue
        edges.setdefault(el.bodies[0], []).append((el.bodies[1], el.gap, el.name))
    best = {start: 0.0}
    via: dict[str, tuple[str, str]] = {}
    queue = [(0.0, start)]
    while queue:
        d, node = heapq.heappop(queue)
        if node == end:
            chain = []
            while node != start:
                node, name = via[node]
                chain.append(name)
            return d, chain[::-1]
        if d > best.get(node, math.inf):
            continue
        for nxt, gap, name in edges.get(node, ()):
            if d + gap < best.get(nxt, math.inf):
                best[nxt], via[nxt] = d + gap, (node, name)
                heapq.heappush(queue, (d + gap, nxt))
    return math.inf, []


def travel_range(model: Model) -> tuple[tuple[float, list[str]], tuple[float, list[str]]]:
    """``((forward m, chain), (backward m, chain))``: how far the driven body may move in its positive and in
    its negative direction from where it starts before a chain of contacts (named in order) presses it into
    the frame; ``inf`` and ``[]`` where no chain stops it."""
    return _shortest(model, model.driven, FRAME), _shortest(model, FRAME, model.driven)


def driven_positions(model: Model, timing, reference) -> list[float]:
    """The driven body's coordinate at the end of every interval of ``timing`` [m or rad]: ``sign * (p -
    s_ref)`` with ``reference = (sign, s_ref)``, or, for a model on a transmission's members (``reference``
    None), the driven member's coordinate through the transmission."""
    ends = [i.end_position for i in timing.intervals]
    if reference is not None:
        sign, s_ref = reference
        return [sign * (p - s_ref) for p in ends]
    zero = [0.0] * len(ends)
    stage = model.bodies[model.driven].stage
    return [float(q) for q in model.transmission.stage_kinematics(ends, zero, zero, zero)[stage][0]]


def check_travel(model: Model | None, timing, reference, file: str, unit_key: str = "mm") -> None:
    """Refuse (ProblemError) a stroke that takes the driven body beyond the travel its contacts leave it
    (:func:`travel_range`), naming the first interval that ends beyond, the chain and its gaps.
    ``reference``: ``(sign, s_ref)`` of the driven coordinate (None: a model on a transmission's members)."""
    if model is None or not model.contacts:
        return
    (ahead, chain_ahead), (behind, chain_behind) = travel_range(model)
    if math.isinf(ahead) and math.isinf(behind):
        return
    from ..errors import ProblemError

    driven = model.driven
    scale, unit = (1e3, "mm") if unit_key == "mm" else (180.0 / math.pi, "deg")
    for interval, x in zip(timing.intervals, driven_positions(model, timing, reference)):
        if -behind - TRAVEL_TOLERANCE <= x <= ahead + TRAVEL_TOLERANCE:
            continue
        limit, chain = (ahead, chain_ahead) if x > 0 else (behind, chain_behind)
        gaps = " + ".join(f"{name} {model.contacts[name].gap * 1e3:g} mm" for name in chain)
        field = (f"timing.intervals[{interval.index}].stroke_{unit_key}" if interval.is_move
                 else f"timing.start_position_{unit_key}")
        raise ProblemError(file, field, (
            f"{interval.name!r} takes the driven {driven} {abs(x) * scale:g} {unit} from where the handover move "
            f"starts, beyond the {limit * scale:g} {unit} its contacts leave it ({gaps} of gap to the frame, "
            "[model.contacts]): the stroke would drive them into each other; a shorter stroke or wider gaps"))
