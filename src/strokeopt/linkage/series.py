"""A periodic function of the crank angle as a truncated Fourier series: what a linkage's output, reduced
inertia and load torques become so that a transmission can evaluate them on numbers and on CasADi symbols.

A closed linkage's pose is an analytic, periodic function of its crank angle, so its Fourier coefficients
fall off geometrically: the loom's six-bar needs 31 harmonics for its sley angle and 40 for its reduced
inertia to reach 1e-13 of their largest coefficient (720 samples a turn). :meth:`Series.fit` keeps the
harmonics above that level and refuses a function that needs more than a quarter of the samples (a linkage
near a dead centre: sample it finer); the caller checks the series against the exact closure between the
samples (linkage/transmission.py). A function that gains a turn per turn (a crank's own angle) is fitted
as a slope plus its periodic rest.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

#: Harmonics whose amplitude is below this share of the largest are dropped.
KEEP_RELATIVE = 1e-11


@dataclass(frozen=True)
class Series:
    """``f(theta) = a0 + slope u + sum_k (a_k cos k u + b_k sin k u)``, ``u = theta - theta0``."""

    theta0: float
    a0: float
    slope: float
    a: tuple
    b: tuple

    @classmethod
    def fit(cls, theta0: float, values, slope: float = 0.0) -> "Series":
        """The series through ``values`` sampled at ``theta0 + 2 pi j / n`` (j = 0..n-1), less ``slope`` times
        the angle; ValueError when the samples do not resolve it (harmonics beyond a quarter of them)."""
        values = np.asarray(values, dtype=float)
        n = len(values)
        periodic = values - slope * (2 * math.pi * np.arange(n) / n)
        c = np.fft.rfft(periodic) / n
        amp = np.abs(c[1:])
        top = max(float(amp.max()) if amp.size else 0.0, abs(float(c[0].real)), 1e-300)
        kept = np.nonzero(amp > KEEP_RELATIVE * top)[0]
        harmonics = int(kept[-1]) + 1 if kept.size else 0
        if harmonics > n // 4:
            raise ValueError(f"needs {harmonics} harmonics of {n} samples a turn")
        a = tuple(2 * c[1:harmonics + 1].real)
        b = tuple(-2 * c[1:harmonics + 1].imag)
        return cls(float(theta0), float(c[0].real), float(slope), a, b)

    @property
    def harmonics(self) -> int:
        return len(self.a)

    def derivative(self) -> "Series":
        """d/dtheta, exactly (term by term)."""
        k = np.arange(1, self.harmonics + 1)
        return Series(self.theta0, self.slope, 0.0, tuple(k * np.asarray(self.b)), tuple(-k * np.asarray(self.a)))

    def __call__(self, theta):
        """The value at ``theta``: numpy for numbers and arrays, CasADi for symbols (cos k u by the angle-sum
        recurrence: two trigonometric calls whatever the harmonics)."""
        symbolic = isinstance(theta, (ca.SX, ca.MX))
        cos, sin = (ca.cos, ca.sin) if symbolic else (np.cos, np.sin)
        u = theta - self.theta0
        out = self.a0 + self.slope * u
        if not self.harmonics:
            return out + 0 * u
        if symbolic:  # each harmonic its own cos and sin: a shallow expression, cheap to differentiate twice
            for k, (ak, bk) in enumerate(zip(self.a, self.b), start=1):
                out = out + ak * cos(k * u) + bk * sin(k * u)
            return out
        c1, s1 = cos(u), sin(u)
        ck, sk = c1, s1
        for ak, bk in zip(self.a, self.b):
            out = out + ak * ck + bk * sk
            ck, sk = ck * c1 - sk * s1, sk * c1 + ck * s1
        return out
