"""Small helpers for evaluating CasADi Functions on numpy arrays."""

from __future__ import annotations

import casadi as ca
import numpy as np


def evaluate(fn: ca.Function, *args) -> list[np.ndarray]:
    """Evaluate a Function of scalar inputs at many points; one array per output.

    The inputs are broadcast to one shape; the Function is mapped over the
    points (CasADi's implicit horizontal call is quadratic in the number of
    points, an explicit ``map`` is linear).
    """
    arrays = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in args))
    shape = arrays[0].shape
    n = max(int(np.prod(shape)), 1)
    flat = [a.reshape(1, -1) if a.size else np.zeros((1, 1)) for a in arrays]
    out = fn.map(n)(*flat) if n > 1 else fn(*flat)
    if not isinstance(out, (list, tuple)):
        out = [out]
    return [np.asarray(o).reshape(shape) for o in out]
