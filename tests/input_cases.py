"""What the tests of strokeopt's inputs share: an input mutated field by field, for the property tests of what
strokeopt reads (problem, linkage and design files: a number scaled by 10^k or its sign flipped, a value of another
type swapped in, a key deleted, misspelt or an array cut short; one generator, each test choosing the operations,
the scales and the swapped-in values), and the check that a JSON answer holds only finite numbers."""

from __future__ import annotations

import json
import math

from hypothesis import strategies as st

#: every operation :func:`mutated` knows
OPERATIONS = ("scale", "sign", "swap", "delete", "misspell", "truncate")


def field_paths(node, prefix=(), depth=0, *, skip=lambda key, depth: False, max_depth=None):
    """Every key and array element under ``node`` as a path of keys and indices (``skip(key, depth)``: leave that
    key and what is under it out; ``max_depth``: do not go below it)."""
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for key, value in items:
        if skip(key, depth):
            continue
        yield prefix + (key,)
        if max_depth is None or depth < max_depth:
            yield from field_paths(value, prefix + (key,), depth + 1, skip=skip, max_depth=max_depth)


@st.composite
def mutated(draw, base, paths, *, count=(1, 3), operations=OPERATIONS, scales=(-30, -3, -1, 1, 3, 30), swaps,
            whole_numbers: bool = False):
    """A copy of ``base`` with ``count`` (a range) mutations at fields drawn from ``paths``; a path an earlier
    mutation removed is passed over. ``whole_numbers``: an integer scaled up stays an integer."""
    data = json.loads(json.dumps(base))
    for _ in range(draw(st.integers(*count))):
        path = draw(st.sampled_from(paths))
        parent = data
        try:
            for key in path[:-1]:
                parent = parent[key]
            value = parent[path[-1]]
        except (KeyError, IndexError, TypeError):
            continue  # an earlier mutation removed or replaced it
        op = draw(st.sampled_from(list(operations)))
        number = isinstance(value, (int, float)) and not isinstance(value, bool)
        if op == "scale" and number:
            k = draw(st.sampled_from(list(scales)))
            scaled = value * 10.0**k
            keep = whole_numbers and isinstance(value, int) and abs(scaled) < 2**63 and k > 0
            parent[path[-1]] = int(scaled) if keep else scaled
        elif op == "sign" and number:
            parent[path[-1]] = -value
        elif op == "swap":
            parent[path[-1]] = draw(st.sampled_from(list(swaps)))
        elif op == "delete":
            del parent[path[-1]]
        elif op == "misspell" and isinstance(parent, dict):
            parent[path[-1] + draw(st.sampled_from(["x", "_", "s"]))] = parent.pop(path[-1])
        elif op == "truncate" and isinstance(value, list):
            parent[path[-1]] = value[: draw(st.integers(0, max(len(value) - 1, 0)))]
    return data


def finite_json(value, nullable, key=None) -> bool:
    """No NaN or infinity anywhere, and no null number (a null under a key outside ``nullable``)."""
    if isinstance(value, dict):
        return all(finite_json(v, nullable, k) for k, v in value.items())
    if isinstance(value, list):
        return all(finite_json(v, nullable, key) for v in value)
    if value is None:
        return key in nullable
    return not isinstance(value, float) or math.isfinite(value)
