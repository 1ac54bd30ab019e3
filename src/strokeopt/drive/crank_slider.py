"""The crank and connecting rod: a servo motor turns a crank of radius ``r``; a rod of length ``l`` drives the
load (a needle bar) along a straight line through the crank's centre (no offset).

The travel from the outer dead centre (the rod stretched, crank angle 0) towards the crank shaft is

    x(phi) = r + l - r cos(phi) - sqrt(l^2 - r^2 sin^2(phi)),   0 <= phi <= pi,

and the load's position is ``dead_centre + sense * x(phi)``: ``[transmission] dead_centre_mm`` is the load's
position at the outer dead centre, ``direction`` the sense in which it leaves it ("up": towards +x). Its
transfer functions come by AD like every transmission's. The motor oscillates within the half turn: every
position of ``[timing]`` must lie inside the travel with the crank at least :data:`DEAD_CENTRE_MARGIN_DEG`
from either dead centre, where the ratio dx/dphi vanishes and no motor angle follows a load speed.

A problem file: ``type = "crank_slider"``, ``crank_radius_mm``, ``rod_length_mm``, ``dead_centre_mm``,
``direction`` and the crank's own inertia on the motor shaft ``crank_inertia_kg_cm2``; the rod's and the
load's masses are the ``[drive]`` moving mass (a rod lumped on the load, a common first model).
"""

from __future__ import annotations

import math

import casadi as ca

from .transmission import Transmission, check_reach

#: The crank angle kept from either dead centre [deg]: at 5 deg the ratio dx/dphi is 9 % of the crank radius
#: (sin 5 deg); closer, the motor speed of a given load speed grows without bound.
DEAD_CENTRE_MARGIN_DEG = 5.0


class CrankSlider(Transmission):
    """A crank of radius ``crank_radius`` [m] and a rod of ``rod_length`` [m] driving a slider whose position is
    ``dead_centre + sense * x(phi)`` (module docstring); ``inertia`` [kg m^2]: the crank's, on the motor shaft.
    The inverse uses the half turn 0 <= phi <= pi."""

    name = "crank_slider"
    label = "crank and connecting rod"

    def __init__(self, crank_radius: float, rod_length: float, inertia: float = 0.0, dead_centre: float = 0.0,
                 sense: float = 1.0):
        if not (crank_radius > 0 and rod_length > crank_radius):
            raise ValueError("need 0 < crank radius < rod length")
        if sense not in (1.0, -1.0):
            raise ValueError("sense must be +1 or -1")
        self.r, self.l, self.inertia = float(crank_radius), float(rod_length), float(inertia)
        self.dead_centre, self.sense = float(dead_centre), float(sense)

    @classmethod
    def read(cls, fields, timing) -> "CrankSlider":
        # crank radii of 1 mm to 1 m; a rod longer than the crank (else it cannot turn) and at most 100 cranks
        # long; the dead centre anywhere a position of [timing] may be (problem.py: +-100 m); a crank of up to
        # 1e4 kg cm^2 on the motor shaft (as a screw's)
        r = fields.number("crank_radius_mm", min=1.0, max=1e3) * 1e-3
        rod = fields.number("rod_length_mm", min=1.0, max=1e5) * 1e-3
        if not r < rod <= 100 * r:
            raise fields.error("rod_length_mm", f"{rod * 1e3:g} mm: a rod must be longer than the crank radius "
                                                f"({r * 1e3:g} mm), and at most 100 times it")
        tr = cls(r, rod, fields.number("crank_inertia_kg_cm2", 0.0, min=0.0, max=1e4) * 1e-4,
                 fields.number("dead_centre_mm", min=-1e5, max=1e5) * 1e-3,
                 1.0 if fields.string("direction", choices=("up", "down")) == "up" else -1.0)
        # the field to name: one the user set (--set) among those that place the travel, else the dead centre
        placing = ("crank_radius_mm", "rod_length_mm", "direction", "dead_centre_mm")
        key = next((k for k in placing if fields.where(k) in fields.overridden), "dead_centre_mm")
        check_reach(tr, fields, key, timing, "move the dead centre or change the crank radius")
        fields.finish()
        return tr

    #: the crank radius a design may choose (``[design.free.transmission] crank_radius_mm = [lower, upper]``); the
    #: rod's length and the crank's inertia stay as stated
    free_fields = {"crank_radius_mm": ("r", 1e-3)}

    def free_error(self, key: str, lower: float, upper: float, positions: tuple[float, float]) -> str | None:
        """The radius within the plausible range and shorter than the rod, and every radius of the bounds able to
        carry the stroke (kept :data:`DEAD_CENTRE_MARGIN_DEG` from the dead centres): the NLP starts nowhere else."""
        if not (1.0 <= lower and upper * 1e-3 < self.l):
            return (f"bounds {lower:g}..{upper:g} mm: a crank radius of at least 1 mm and shorter than the rod "
                    f"({self.l * 1e3:g} mm)")

        def reach(r):
            return self.with_free({key: r}).range_error(*positions)

        for r in (lower, upper):
            why = reach(r)
            if why is not None:
                return f"bounds {lower:g}..{upper:g} mm: at {r:g} mm {why}" + _reaching(reach, lower, upper)
        return None

    def reach_rows(self, x_min, x_max) -> list:
        """The travel from the outer dead centre of ``x_min`` and ``x_max`` between the crank's travel at
        :data:`DEAD_CENTRE_MARGIN_DEG` and at 180 deg less it, in mm (what :meth:`range_error` checks of a
        fixed radius)."""
        margin = math.radians(DEAD_CENTRE_MARGIN_DEG)
        near, far = self.travel(margin), self.travel(math.pi - margin)
        rows = []
        for x in (x_min, x_max):
            u = self.sense * (x - self.dead_centre)
            rows += [(u - near) * 1e3, (far - u) * 1e3]
        return rows

    def facts(self):
        return [("crank radius [mm]", self.r * 1e3), ("connecting rod length [mm]", self.l * 1e3)]

    def travel(self, phi):
        """x [m] from the outer dead centre towards the crank shaft at the crank angle ``phi`` [rad]."""
        return self.r + self.l - self.r * ca.cos(phi) - ca.sqrt(self.l**2 - (self.r * ca.sin(phi)) ** 2)

    def position(self, phi):
        return self.dead_centre + self.sense * self.travel(phi)

    def inverse_position(self, x):
        d = self.r + self.l - self.sense * (x - self.dead_centre)  # crank centre to the rod's end on the slider
        # held inside [-1, 1]: a free radius may leave a position out of reach between iterates (reach_rows)
        return ca.acos(ca.fmin(ca.fmax((d**2 + self.r**2 - self.l**2) / (2 * d * self.r), -1.0), 1.0))

    def range_error(self, x_min: float, x_max: float) -> str | None:
        """Every load position inside the travel, the crank at least :data:`DEAD_CENTRE_MARGIN_DEG` from a dead
        centre."""
        margin = math.radians(DEAD_CENTRE_MARGIN_DEG)
        near, far = (float(self.position(a)) for a in (margin, math.pi - margin))
        lo, hi = min(near, far), max(near, far)
        for x in (x_min, x_max):
            if not lo - 1e-12 <= x <= hi + 1e-12:
                return (f"the position {x * 1e3:g} mm is outside {lo * 1e3:.4g}..{hi * 1e3:.4g} mm, the crank's travel "
                        f"kept {DEAD_CENTRE_MARGIN_DEG:g} deg from its dead centres (radius {self.r * 1e3:g} mm, dead "
                        f"centre at {self.dead_centre * 1e3:g} mm)")
        return None

    def __repr__(self) -> str:
        return (f"CrankSlider(crank_radius={self.r * 1e3:g} mm, rod_length={self.l * 1e3:g} mm, "
                f"dead_centre={self.dead_centre * 1e3:g} mm)")


def _reaching(reach, lower: float, upper: float) -> str:
    """Where within ``lower..upper`` [mm] the radii that carry the stroke lie (``reach(r)`` None), for a message."""
    grid = [lower + (upper - lower) * k / 200 for k in range(201)]
    ok = [r for r in grid if reach(r) is None]
    if not ok:
        return "; no radius of the bounds carries the stroke"
    return f"; the radii of the bounds that carry it: about {ok[0]:.4g}..{ok[-1]:.4g} mm"
