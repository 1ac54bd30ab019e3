"""Motion laws built from acceleration pieces: the one mechanism behind the cam-handbook families.

Most cam laws of VDI 2143 and the cam-design handbooks are symmetric rises whose acceleration over the
first half is a chain of simple pieces -- a sine arc, a constant, a straight ramp -- and whose second
half mirrors the first (``y(1 - x) = 1 - y(x)``). A law is written here as that chain over the first
half, on ``[0, 1/2]``, with the acceleration's shape (its scale follows from ``y(1/2) = 1/2``):

- ``("sin", length, omega, phase)``: ``a = sin(omega*u + phase)`` for ``u`` in ``[0, length]``;
- ``("poly", length, (p0, p1, ...))``: ``a = p0 + p1*u + ...``.

A constant-speed section of a stated share ``c`` of the move (a "modified sine with constant velocity",
a trapezoidal velocity profile, an S-curve's cruise) is the same chain compressed to ``(1 - c)/2`` with a
zero-acceleration piece of ``c/2`` after it. Velocity and position are the chain's exact integrals, each
piece's start values carried as numbers, so a law is one CasADi expression that works on floats, numpy
arrays and SX/MX alike (motion/laws.py differentiates it).
"""

from __future__ import annotations

import math

import casadi as ca


def scca_half(sine_share: float, constant_accel_share: float) -> list[tuple]:
    """The first half of Norton's sine-constant-cosine acceleration (SCCA) family.

    ``b = sine_share``: the share of the move in the two quarter-sine flanks (``b/2`` at each end);
    ``c = constant_accel_share``: the share at constant acceleration; ``d = 1 - b - c``: the share of
    the cosine through zero in the middle. ``(b, c) = (0.25, 0.5)`` is the modified trapezoid,
    ``(0.25, 0)`` the modified sine, ``(0.5, 0)`` the cycloid, ``(0, 0)`` the simple harmonic law,
    ``(0, 1)`` constant acceleration.
    """
    b, c = sine_share, constant_accel_share
    d = 1.0 - b - c
    pieces = []
    if b > 0:
        pieces.append(("sin", b / 2, math.pi / b, 0.0))
    if c > 0:
        pieces.append(("poly", c / 2, (1.0,)))
    if d > 0:
        pieces.append(("sin", d / 2, math.pi / d, math.pi / 2))
    return pieces


def ramp_half(ramp_share: float) -> list[tuple]:
    """The first half of a trapezoidal acceleration: a straight ramp up, a constant and a straight ramp down
    to zero at the middle, the two ramps ``ramp_share`` of the half (``ramp_share = 1``: a triangle)."""
    r = ramp_share * 0.25
    flat = 0.5 - 2 * r
    pieces = [("poly", r, (0.0, 1.0 / r))]
    if flat > 0:
        pieces.append(("poly", flat, (1.0,)))
    pieces.append(("poly", r, (1.0, -1.0 / r)))
    return pieces


def with_constant_speed(half: list[tuple], share: float) -> list[tuple]:
    """The same half compressed to ``(1 - share)/2`` of the move, then a cruise at constant speed."""
    if share <= 0:
        return list(half)
    k = 1.0 - share
    out = []
    for piece in half:
        if piece[0] == "sin":
            _, length, omega, phase = piece
            out.append(("sin", length * k, omega / k, phase))
        else:
            _, length, coeffs = piece
            out.append(("poly", length * k, tuple(p / k**i for i, p in enumerate(coeffs))))
    out.append(("poly", share / 2, (0.0,)))
    return out


def joints(half: list[tuple]) -> tuple[float, ...]:
    """Where the pieces meet, over the whole move (the half's joints and their mirror images, and the middle)."""
    xs, x = [], 0.0
    for piece in half[:-1]:
        x += piece[1]
        xs.append(x)
    return tuple(sorted({*xs, 0.5, *(1.0 - v for v in xs)}))


def _piece_values(piece, u, v0, y0):
    """Velocity and position at ``u`` into a piece that starts at speed ``v0`` and position ``y0``
    (numbers or CasADi expressions alike)."""
    if piece[0] == "sin":
        _, _, w, ph = piece
        v = v0 + (math.cos(ph) - ca.cos(w * u + ph)) / w
        y = y0 + v0 * u + u * math.cos(ph) / w - (ca.sin(w * u + ph) - math.sin(ph)) / w**2
        return v, y
    _, _, coeffs = piece
    v = v0 + sum(p * u ** (i + 1) / (i + 1) for i, p in enumerate(coeffs))
    y = y0 + v0 * u + sum(p * u ** (i + 2) / ((i + 1) * (i + 2)) for i, p in enumerate(coeffs))
    return v, y


def _starts(half):
    """Each piece's start (x, v, y) for the unscaled acceleration, and the half's end position."""
    starts, x, v, y = [], 0.0, 0.0, 0.0
    for piece in half:
        starts.append((x, v, y))
        v, y = (float(val) for val in _piece_values(piece, piece[1], v, y))
        x += piece[1]
    if abs(x - 0.5) > 1e-12:
        raise ValueError(f"the pieces of a half-law span {x:g}, not 1/2")
    return starts, y


def mirrored_law(x, half: list[tuple]):
    """``y(x)`` of the symmetric rise whose first half's acceleration is ``half`` (scaled so y(1) = 1)."""
    starts, y_mid = _starts(half)
    scale = 0.5 / y_mid

    def first_half(z):
        expr = None
        for piece, (x0, v0, y0) in reversed(list(zip(half, starts))):
            _, y = _piece_values(piece, z - x0, v0, y0)
            expr = y if expr is None else ca.if_else(z < x0 + piece[1], y, expr)
        return scale * expr

    return ca.if_else(x <= 0.5, first_half(x), 1 - first_half(1 - x))
