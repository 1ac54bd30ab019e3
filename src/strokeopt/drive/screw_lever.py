"""The screw and lever of the knitting machine's stitch-cam drive (sources B): a motor turns a screw, its nut tilts a
lever whose other arm moves the sleeve. Each stage is its own map (:meth:`ScrewLever.chain`), so the stages'
kinematics and the elastic model's couplings use the same functions as the position function.
"""

from __future__ import annotations

import math

import casadi as ca

from .load import read_efficiency
from .transmission import Transmission, check_reach

#: Lead angle plus the flanks' friction angle of a screw the motor turns [deg]: at 90 deg the torque
#: F d2/2 tan(lambda + rho') has no finite value (beyond it, it changes sign): no drive moves the nut.
SCREW_ANGLE_MAX_DEG = 90.0


#: The lever angle a screw-lever transmission may reach [deg] (both arms): tan() of the sleeve arm
#: grows without bound toward 90 deg; at 80 deg one step of the motor moves the sleeve 33 times as
#: far as at 0 deg -- a toggle, no longer a transmission.
LEVER_LIMIT_DEG = 80.0


class ScrewLever(Transmission):
    """Screw and lever of the knitting-machine stitch-cam drive (sources B).

    The motor turns a screw of lead ``s``; the nut moves ``x2 = s/(2 pi) phi``
    and tilts a lever, ``phi4 = atan(x2/R0)``; the lever's other arm, at
    ``offset`` [rad] to the first, moves the sleeve ``x6 = R0P tan(phi4 + offset)``
    (minus its value at phi = 0, so x6(0) = 0). Each stage is written once
    (:meth:`nut_position`, :meth:`lever_angle`, :meth:`sleeve_position`): the position function,
    the stages' kinematics and the elastic model's couplings all use them. ``inertia`` is the
    screw's [kg m^2].
    """

    name = "screw_lever"
    label = "screw and lever"

    @classmethod
    def read(cls, trans, timing) -> "ScrewLever":
        """``[transmission]`` of a screw and lever: ``lead_mm``, ``lever_arm_mm`` R0, ``sleeve_arm_mm`` R0P,
        ``lever_offset_deg``, ``screw_inertia_kg_cm2`` and the thread (``screw_diameter_mm``,
        ``thread_friction``, ``thread_angle_deg``); the strokes of ``timing`` must stay within the lever's
        range."""
        # leads of 0.1 mm (a fine adjusting screw) to 100 mm (a steep ball screw); lever arms of 1 mm to 1 m;
        # the arms' offset within the lever's own range (LEVER_LIMIT_DEG); a screw of up to 1e4 kg cm^2 (a
        # 100 mm steel shaft a metre long is 8e3 kg cm^2)
        diameter = trans.number("screw_diameter_mm", None, min=1.0, max=100.0)
        tr = cls(trans.number("lead_mm", min=0.1, max=100.0) * 1e-3,
                 trans.number("lever_arm_mm", min=1.0, max=1e3) * 1e-3,
                 trans.number("sleeve_arm_mm", min=1.0, max=1e3) * 1e-3,
                 math.radians(trans.number("lever_offset_deg", 0.0, min=-80.0, max=80.0)),
                 trans.number("screw_inertia_kg_cm2", 0.0, min=0.0, max=1e4) * 1e-4,
                 # the screw torque from the nut force (contact/chain.py): pitch diameters 1-100 mm, flank
                 # friction 0.01 (ball screw) to 1, flank angles 0 (square) to 90 deg (metric 60, Tr 30)
                 None if diameter is None else diameter * 1e-3,
                 trans.number("thread_friction", 0.15, min=0.01, max=1.0),
                 math.radians(trans.number("thread_angle_deg", 30.0, min=0.0, max=90.0)))
        if tr.screw_diameter is not None:  # a screw the motor cannot drive: F d2/2 tan(lambda + rho') turns over
            lam = math.degrees(math.atan(tr.lead / (math.pi * tr.screw_diameter)))
            rho = math.degrees(math.atan(tr.thread_friction / math.cos(tr.thread_angle / 2)))
            if lam + rho >= SCREW_ANGLE_MAX_DEG:
                raise trans.error("lead_mm", f"{tr.lead * 1e3:g} mm on a {tr.screw_diameter * 1e3:g} mm screw is a "
                                             f"lead angle of {lam:.1f} deg; with the flanks' friction angle {rho:.1f} "
                                             f"deg (thread_friction {tr.thread_friction:g}) they add to "
                                             f"{lam + rho:.1f} deg, at or above {SCREW_ANGLE_MAX_DEG:g} deg: no torque "
                                             "drives the nut (a shorter lead, a larger diameter or less friction)")
        check_reach(tr, trans, "sleeve_arm_mm", timing, "a longer arm or a shorter stroke")
        tr.efficiency = read_efficiency(trans)
        trans.finish()
        return tr

    def __init__(self, lead: float, R0: float, R0P: float, offset: float = 0.0, inertia: float = 0.0,
                 screw_diameter: float | None = None, thread_friction: float = 0.15, thread_angle: float = math.radians(30)):
        if not (lead > 0 and R0 > 0 and R0P > 0):
            raise ValueError("lead and lever arms must be positive")
        self.lead, self.R0, self.R0P, self.offset, self.inertia = (float(lead), float(R0), float(R0P),
                                                                   float(offset), float(inertia))
        self.screw_diameter, self.thread_friction, self.thread_angle = screw_diameter, thread_friction, thread_angle

    def screw_torque(self, force):
        """Torque [N m] that turns the screw against an axial nut force ``force`` [N] (raising the load,
        the worse sense): ``F d2/2 tan(lambda + rho')`` with the lead angle ``lambda = atan(s / (pi d2))``
        and the friction angle of the thread flanks ``rho' = atan(mu / cos(beta/2))`` (``screw_diameter``
        d2 = pitch diameter, ``thread_friction`` mu, ``thread_angle`` beta: 30 deg trapezoidal)."""
        lam = math.atan(self.lead / (math.pi * self.screw_diameter))
        rho = math.atan(self.thread_friction / math.cos(self.thread_angle / 2))
        return force * self.screw_diameter / 2 * math.tan(lam + rho)

    def facts(self):
        return [("screw lead [mm]", self.lead * 1e3), ("lever arm at the nut [mm]", self.R0 * 1e3),
                ("lever arm at the sleeve [mm]", self.R0P * 1e3)]

    def nut_position(self, phi):
        """x2 [m] of the nut for the screw angle ``phi`` [rad]."""
        return self.lead / (2 * math.pi) * phi

    def lever_angle(self, x2):
        """phi4 [rad] of the lever for the nut position ``x2`` [m] (phi4 = atan(x2/R0), sources B)."""
        return ca.atan(x2 / self.R0)

    def sleeve_position(self, phi4):
        """x6 [m] of the sleeve for the lever angle ``phi4`` [rad] (x6 = R0P tan(phi4P), phi4P = phi4 + offset)."""
        return self.R0P * (ca.tan(phi4 + self.offset) - math.tan(self.offset))

    def position(self, phi):
        return self.sleeve_position(self.lever_angle(self.nut_position(phi)))

    def chain(self):
        return [("nut", self.nut_position, "m"), ("lever", self.lever_angle, "rad"), ("sleeve", self.sleeve_position, "m")]

    def inverse_position(self, x):
        phi4 = ca.atan(x / self.R0P + math.tan(self.offset)) - self.offset
        return 2 * math.pi / self.lead * self.R0 * ca.tan(phi4)

    def range_error(self, x_min: float, x_max: float) -> str | None:
        """The lever (both arms) within +-:data:`LEVER_LIMIT_DEG`: beyond it tan() runs away and the
        nut no longer tilts the lever (the mechanism's own limit is far inside)."""
        for x in (x_min, x_max):
            phi4 = math.atan(x / self.R0P + math.tan(self.offset)) - self.offset
            for angle in (phi4, phi4 + self.offset):
                if abs(math.degrees(angle)) > LEVER_LIMIT_DEG:
                    return (f"the sleeve position {x * 1e3:g} mm turns the lever to {math.degrees(angle):.1f} deg, "
                            f"past +-{LEVER_LIMIT_DEG:g} deg")
        return None
