"""Transmissions: motor angle -> load position. A transmission is its position function ``x = f(phi)`` (metres
from radians), written once with CasADi operations; its transfer functions ``mu = dx/dphi`` and ``nu = d2x/dphi2``
come from algorithmic differentiation, so a position-dependent transmission (crank, screw and lever) needs nothing
but its position function.

Where it sits: first in the drive package. The toothed-pulley geometry (:data:`PROFILE_PITCH`,
:func:`pitch_diameter`) is here, once: the problem's ``[transmission]``, the catalogue's pulleys (catalogue.py) and
the design's pulley search all use it. load.py turns a load motion into motor torque through a transmission.
"""

from __future__ import annotations

import copy
import math

import casadi as ca
import numpy as np

from .._casadi import evaluate
from ..errors import ProblemError
from .load import read_efficiency


class Transmission:
    """Base: subclasses define :meth:`position` (CasADi-friendly) and, to be driven from a prescribed load motion,
    :meth:`inverse_position`. ``inertia`` [kg m^2]: what the transmission adds on the motor shaft (a pulley)."""

    name = "transmission"
    #: the transmission in words, for reports ("belt pulley")
    label = "transmission"
    #: the SI unit of the load it drives: "m" (a translating load, [timing] in mm) or "rad" (a rotary load,
    #: [timing] in deg)
    load_unit = "m"
    inertia = 0.0
    efficiency = 1.0  # [transmission] efficiency (read_efficiency): the load model's losses through it
    #: whether the transmission's own bodies carry the load's masses (a linkage's links): the ``[drive]`` moving
    #: mass or inertia is then only what is added to its output, zero by default
    carries_load = False
    #: the tables a file of this transmission means where it states no ``[timing]`` (a linkage: its crank turning
    #: at constant speed), merged under the file's own; None: it must state one
    implied = None

    @classmethod
    def read(cls, fields, timing) -> "Transmission":
        """The transmission of a problem file's ``[transmission]`` table (``fields``: its
        :class:`~strokeopt.io.fields.Fields`, ``type`` already read; ``timing``: the problem's
        :class:`~strokeopt.motion.timing.TimingDiagram`), every field read with its range and the table
        finished (unknown keys refused). Each registered type (transmissions.py) defines it."""
        raise NotImplementedError(f"{cls.__name__} cannot be read from a problem file")

    def position(self, phi):
        raise NotImplementedError

    def inverse_position(self, x):
        """Motor angle [rad] for the load position ``x`` [m], with CasADi operations."""
        raise NotImplementedError(f"{type(self).__name__} has no inverse")

    #: the ``[transmission]`` fields a design may free (``[design.free.transmission]``, design/free.py): file field ->
    #: (attribute, factor from the file's unit to SI); a constant-ratio belt's radius is ``design.pulley``'s
    free_fields: dict = {}

    def free_error(self, key: str, lower: float, upper: float, positions: tuple[float, float]) -> str | None:
        """Why the bounds ``lower..upper`` (the file's unit) of the free field ``key`` do not fit the load positions
        ``positions`` (the least and largest of [timing], m), or None."""
        return None

    def with_free(self, values: dict) -> "Transmission":
        """The same transmission with the fields of ``values`` (file field -> value in the file's unit: a number, or a
        CasADi expression for a design variable) in place of its own; its functions of the motor angle built again."""
        return self.replaced(**{self.free_fields[key][0]: value * self.free_fields[key][1] for key, value in values.items()})

    def replaced(self, **attributes) -> "Transmission":
        """A copy with ``attributes`` set, its functions of the motor angle built again for them."""
        tr = copy.copy(self)
        for cached in ("_fns", "_inv", "_stage_fns"):
            tr.__dict__.pop(cached, None)
        tr.__dict__.update(attributes)
        return tr

    def reach_rows(self, x_min, x_max) -> list:
        """Rows that must be >= 0 (CasADi alike) for the load positions ``x_min..x_max`` [m] to lie in the range of a
        transmission with free fields (:meth:`range_error` says it of a fixed one when the file is read)."""
        return []

    def _compiled(self, cache: str, name: str, inputs: int, outputs):
        """The CasADi function ``outputs(tr, *x)`` of ``inputs`` scalar symbols ``x``, built once (``cache``). Where an
        attribute is a CasADi expression (a free field, :meth:`with_free`) the function is built over a symbol
        standing for it and called with the expression."""
        if cache not in self.__dict__:
            free = {k: v for k, v in vars(self).items() if isinstance(v, (ca.SX, ca.MX))}
            proto = copy.copy(self)
            stand = {k: ca.SX.sym(k) for k in free}
            for k, sym in stand.items():
                setattr(proto, k, sym)
            args = [ca.SX.sym(f"x{i}") for i in range(inputs)]
            fn = ca.Function(name, args + list(stand.values()), outputs(proto, *args))
            values = tuple(free.values())
            self.__dict__[cache] = fn if not free else (lambda *a: fn(*a, *values))
        return self.__dict__[cache]

    def _functions(self):
        def transfer(tr, phi):
            x = tr.position(phi)
            mu = ca.jacobian(x, phi)
            return [x, mu, ca.jacobian(mu, phi)]
        return self._compiled("_fns", f"{self.name}_transfer", 1, transfer)

    def _inverse_function(self):
        return self._compiled("_inv", f"{self.name}_inverse", 1, lambda tr, x: [tr.inverse_position(x)])

    def transfer(self, phi):
        """Numeric ``(x, mu, nu)`` at motor angles ``phi`` [rad]."""
        return tuple(evaluate(self._functions(), phi))

    def symbolic_transfer(self, phi):
        return tuple(self._functions()(phi))

    def motor_angle(self, x):
        """Motor angle [rad] for the load position ``x`` [m] (inverse of :meth:`position`)."""
        (phi,) = evaluate(self._inverse_function(), x)
        return phi

    def chain(self) -> list[tuple[str, object, str]]:
        """The members the transmission moves, motor side first, as ``(name, map, unit)``: ``map`` takes
        the previous member's coordinate (the motor angle for the first) to this one's, with CasADi
        operations; the last member is the load; ``unit`` is "m" or "rad". A constant-ratio drive has
        one member, the load; a chain (screw, lever) lists each."""
        return [("load", self.position, "m")]

    def stages(self, phi) -> list[tuple[str, object, str]]:
        """Every member's coordinate as a CasADi expression of the motor angle ``phi``: ``(name, q, unit)``."""
        out, q = [], phi
        for name, step, unit in self.chain():
            q = step(q)
            out.append((name, q, unit))
        return out

    def stage_map(self, start: str, end: str, q):
        """The coordinate of member ``end`` from that of member ``start`` (``"motor"``: the motor angle),
        composing the chain's maps between them; ``end`` must come after ``start``."""
        names = ["motor"] + [name for name, _, _ in self.chain()]
        i, j = names.index(start), names.index(end)
        if j <= i:
            raise ValueError(f"{end!r} does not follow {start!r} in the {self.name} ({' -> '.join(names)})")
        for _, step, _ in self.chain()[i:j]:
            q = step(q)
        return q

    def stage_unit(self, name: str) -> str:
        return "rad" if name == "motor" else next(u for n, _, u in self.chain() if n == name)

    def stage_names(self) -> list[str]:
        return [name for name, _, _ in self.stages(ca.SX.sym("phi"))]

    def _stage_functions(self):
        """``phi -> [q, dq/dphi, d2q/dphi2, d3q/dphi3]`` of every stage (AD), and of the load last."""
        def stages(tr, phi):
            outs = []
            for _, q, _ in tr.stages(phi) + [("", tr.position(phi), "")]:
                d1 = ca.jacobian(q, phi)
                d2 = ca.jacobian(d1, phi)
                outs += [q, d1, d2, ca.jacobian(d2, phi)]
            return outs
        return self._compiled("_stage_fns", f"{self.name}_stages", 1, stages)

    def stage_transfer(self, phi) -> dict:
        """``{stage: (dq/dphi, d2q/dphi2)}`` at motor angles ``phi``: numpy for numbers, CasADi for symbols."""
        if isinstance(phi, (ca.SX, ca.MX)):
            vals = self._stage_functions()(phi)
        else:
            vals = evaluate(self._stage_functions(), phi)
        return {name: (vals[4 * k + 1], vals[4 * k + 2]) for k, name in enumerate(self.stage_names())}

    def stage_kinematics(self, x, v, a, j) -> dict:
        """Position, speed, acceleration and jerk of the motor and of every stage for a sampled load
        motion ``x, v, a, j`` (numpy): ``{"motor": (phi, omega, eps, jerk), name: (q, dq, ddq, dddq), ...}``,
        time derivatives by the chain rule with AD derivatives of the position functions (the motor's
        jerk from ``j = mu jerk + 3 nu omega eps + x3 omega^3``, x3 the third derivative of x(phi))."""
        x, v, a, j = (np.asarray(y, dtype=float) for y in (x, v, a, j))
        phi = self.motor_angle(x)
        vals = [np.asarray(o).reshape(phi.shape) for o in evaluate(self._stage_functions(), phi)]
        _, mu, nu, x3 = vals[-4:]
        omega = v / mu
        eps = (a - nu * omega**2) / mu
        with np.errstate(invalid="ignore"):  # an unbounded jerk (a jump of acceleration) stays unbounded
            jerk = (j - 3 * nu * omega * eps - x3 * omega**3) / mu
        out = {"motor": (phi, omega, eps, jerk)}
        for k, name in enumerate(self.stage_names()):
            q, d1, d2, d3 = vals[4 * k: 4 * k + 4]
            with np.errstate(invalid="ignore"):
                out[name] = (q, d1 * omega, d1 * eps + d2 * omega**2,
                             d1 * jerk + 3 * d2 * omega * eps + d3 * omega**3)
        return out

    def range_error(self, x_min: float, x_max: float) -> str | None:
        """Why the load positions ``x_min..x_max`` [m] are outside what this transmission can reach, or None."""
        return None

    def ratio_range(self, x_min: float, x_max: float, samples: int = 201) -> tuple[float, float]:
        """The smallest and largest ratio ``|dx/dphi|`` [m or rad per rad] over the load positions ``x_min..x_max``
        (sampled between them, not only at the ends: a linkage's ratio may be equal at both and not between)."""
        x = np.linspace(x_min, x_max, samples)
        mu = np.abs(np.ravel(self.transfer(np.ravel(self.motor_angle(x)))[1]))
        return float(mu.min()), float(mu.max())

    def facts(self) -> list[tuple[str, object]]:
        """What a report states of the transmission: ``(label with its unit, value)`` rows."""
        return []

    def analysis(self, problem, with_dynamics: bool = False) -> dict | None:
        """What ``kinematics``, ``size``, ``report`` add of its own (a linkage's outputs, index, crank torque)."""
        return None

    def load_switches(self) -> tuple[float, ...]:
        """The load positions where a torque of :meth:`own_terms` jumps (a linkage's process load switched on or
        off): the design holds the torque on both sides of each (pins inside a move, rows at a move's ends)."""
        return ()

    def same_position(self, x: float, switch: float) -> bool:
        """Whether the load position ``x`` is the switch position ``switch`` (a turning crank: modulo a turn)."""
        return abs(x - switch) <= 1e-12 * max(1.0, abs(x))

    def inertia_at(self, phi):
        """The transmission's own inertia on the motor shaft [kg m^2] at motor angles ``phi``: ``inertia`` for a
        transmission of constant inertia; a linkage's varies with the crank's pose."""
        return self.inertia + 0 * phi

    def own_terms(self, phi, omega, eps) -> dict:
        """The motor torques [N m] of the transmission's own bodies and of the forces on them, numbers or CasADi
        alike: ``{"inertia": ..., name: ...}`` (``inertia``: ``J(phi) eps + 1/2 J'(phi) omega^2``; a constant
        inertia's is ``inertia * eps``; a linkage adds its links' gravity and process loads by name)."""
        return {"inertia": self.inertia * eps}

    def motor_kinematics(self, x, v, a):
        """Motor angle, speed and acceleration [rad, rad/s, rad/s^2] for a load motion.

        From ``v = mu*omega`` and ``a = mu*eps + nu*omega^2``. Numeric
        (numpy) for numeric input, CasADi expressions for CasADi symbols.
        """
        if isinstance(x, (ca.SX, ca.MX)) or isinstance(v, (ca.SX, ca.MX)) or isinstance(a, (ca.SX, ca.MX)):
            phi = self._inverse_function()(x)
            _, mu, nu = self.symbolic_transfer(phi)
            omega = v / mu
            return phi, omega, (a - nu * omega**2) / mu
        phi = self.motor_angle(np.asarray(x, dtype=float))
        _, mu, nu = self.transfer(phi)
        omega = np.asarray(v) / mu
        eps = (np.asarray(a) - nu * omega**2) / mu
        return phi, omega, eps


#: Tooth pitch [m] of each toothed-belt profile strokeopt knows.
PROFILE_PITCH = {"GT3": 3e-3}

#: Plausible pulley tooth counts (``transmission.pulley_teeth``, the pulley ranges of [drive] and [design],
#: catalogue pulleys): below 8 teeth a toothed belt does not wrap a pulley (catalogues start at 10-14),
#: above 250 a pulley is a flywheel (catalogues end near 150-216).
TEETH_RANGE = (8, 250)


def pitch_diameter(profile: str, teeth) -> float:
    """Pitch diameter [m] of a pulley: ``z * pitch / pi`` (GT3: 3 mm pitch, thesis 4.2)."""
    return teeth * PROFILE_PITCH[profile] / math.pi


def gt3_pitch_diameter(teeth: int) -> float:
    """Pitch diameter [m] of a GT3 (3 mm pitch) pulley: PD = z * 3 mm / pi (thesis 4.2)."""
    return pitch_diameter("GT3", teeth)


class BeltPulley(Transmission):
    """A toothed belt on a pulley of pitch radius ``r``: ``x = r*phi``; ``inertia`` of the pulley [kg m^2].

    ``pitch_diameter`` and ``inertia`` may be CasADi expressions (a pulley radius that is a
    decision variable of the design NLP); numbers are checked. ``teeth`` and ``profile``
    say which toothed pulley it is (:meth:`toothed`), or are None for a pulley of any radius.
    """

    name = "belt_pulley"
    label = "belt pulley"

    @classmethod
    def read(cls, fields, timing) -> "BeltPulley":
        """``[transmission]`` of a belt drive: the toothed pulley's ``profile`` and ``pulley_teeth``."""
        profile = fields.string("profile", "GT3", choices=tuple(PROFILE_PITCH))
        teeth = fields.number("pulley_teeth", integer=True, min=TEETH_RANGE[0], max=TEETH_RANGE[1])
        efficiency = read_efficiency(fields)
        fields.finish()
        tr = cls.toothed(teeth, profile)
        tr.efficiency = efficiency
        return tr

    @classmethod
    def toothed(cls, teeth: int, profile: str = "GT3", inertia=0.0) -> "BeltPulley":
        """The pulley of ``teeth`` grooves of ``profile``: its pitch diameter from :func:`pitch_diameter`."""
        return cls(pitch_diameter(profile, teeth), inertia, teeth, profile)

    def __init__(self, pitch_diameter, inertia=0.0, teeth: int | None = None, profile: str | None = None):
        symbolic = isinstance(pitch_diameter, (ca.SX, ca.MX)) or isinstance(inertia, (ca.SX, ca.MX))
        if not symbolic:
            if not (pitch_diameter > 0 and math.isfinite(pitch_diameter)):
                raise ValueError("pitch diameter must be positive")
            if not (inertia >= 0 and math.isfinite(inertia)):
                raise ValueError("pulley inertia must be zero or positive")
            pitch_diameter, inertia = float(pitch_diameter), float(inertia)
        self.pitch_diameter = pitch_diameter
        self.inertia = inertia
        self.teeth = teeth
        self.profile = profile

    @property
    def radius(self):
        return self.pitch_diameter / 2

    def position(self, phi):
        return self.radius * phi

    def inverse_position(self, x):
        return x / self.radius

    # constant ratio: the same numbers as the AD transfer functions, without a CasADi call per sample
    def transfer(self, phi):
        phi = np.asarray(phi, dtype=float)
        return self.radius * phi, np.full_like(phi, self.radius), np.zeros_like(phi)

    def symbolic_transfer(self, phi):
        return self.radius * phi, self.radius + 0 * phi, 0 * phi

    def motor_angle(self, x):
        return np.asarray(x) / self.radius

    def motor_kinematics(self, x, v, a):
        return x / self.radius, v / self.radius, a / self.radius

    def __repr__(self) -> str:
        if isinstance(self.pitch_diameter, (ca.SX, ca.MX)):
            return "BeltPulley(pitch_diameter=<symbolic>)"
        return f"BeltPulley(pitch_diameter={self.pitch_diameter * 1e3:.3f} mm)"


class Gearbox(Transmission):
    """A gearbox of ``ratio`` motor turns per output turn driving a rotary load: ``x = phi / ratio`` (the
    load's angle [rad] from the motor's); ``inertia`` [kg m^2] is the gearbox's own, reduced to the motor
    shaft (catalogues give it so). ``ratio = 1`` is a direct drive. Its transfer functions come from AD
    like every transmission's; the load positions of such a problem are angles ([timing] in deg)."""

    name = "gearbox"
    label = "gearbox"
    load_unit = "rad"

    @classmethod
    def read(cls, trans, timing) -> "Gearbox":
        """``[transmission]`` of a gearbox: ``ratio``, ``inertia_kg_cm2`` and the ``gearbox``'s name (a label)."""
        # motor turns per output turn: 1 (a direct drive) to 1000 (a two-stage worm); a gearbox's own inertia on
        # the motor shaft as a rotor's (catalogue.py: to 1e6 kg cm^2). The ratio is the problem's design choice:
        # a design uses it as stated (a study compares ratios by --set transmission.ratio=...)
        name = trans.string("gearbox", None)
        entry = None
        if name is not None:  # the shipped catalogue's entry: it supplies the ratio and inertia, or must agree
            from .gearboxes import load_gearboxes

            known = {g.name: g for g in load_gearboxes()}
            if name not in known:
                raise trans.error("gearbox", f"{name!r} is not in the gearbox catalogue (drive/data/gearboxes.toml: "
                                             f"{', '.join(known)}); for a gearbox of your own, state its ratio and "
                                             "inertia_kg_cm2 without a gearbox name")
            entry = known[name]
        ratio = trans.number("ratio", entry.ratio, min=1.0, max=1000.0) if entry else \
            trans.number("ratio", min=1.0, max=1000.0)
        inertia = trans.number("inertia_kg_cm2", entry.inertia * 1e4 if entry else 0.0, min=0.0, max=1e6) * 1e-4
        if entry is not None:
            for key, value, own in (("ratio", ratio, entry.ratio), ("inertia_kg_cm2", inertia, entry.inertia)):
                if not math.isclose(value, own, rel_tol=1e-9, abs_tol=1e-15):
                    shown = (value, own) if key == "ratio" else (value * 1e4, own * 1e4)
                    blame = "gearbox" if trans.where("gearbox") in trans.overridden else key  # what the user set
                    raise trans.error(blame, f"{name}: the catalogue's has {key} = {shown[1]:g}, the file {shown[0]:g}: "
                                             "a named gearbox supplies its values (omit them), or name none")
        efficiency = read_efficiency(trans)
        trans.finish()
        tr = cls(ratio, inertia, name)
        tr.efficiency = efficiency
        return tr

    def __init__(self, ratio: float, inertia: float = 0.0, entry: str | None = None):
        if not (ratio > 0 and math.isfinite(ratio)):
            raise ValueError("gear ratio must be positive")
        if not (inertia >= 0 and math.isfinite(inertia)):
            raise ValueError("gearbox inertia must be zero or positive")
        self.ratio, self.inertia, self.entry = float(ratio), float(inertia), entry

    def facts(self):
        return [("gear ratio [motor turns per output turn]", self.ratio)]

    def with_gearbox(self, entry) -> "Gearbox":
        """The same drive through the catalogue's gearbox ``entry`` (drive/gearboxes.py): its ratio and inertia."""
        tr = Gearbox(entry.ratio, entry.inertia, entry.name)
        tr.efficiency = self.efficiency
        return tr

    def position(self, phi):
        return phi / self.ratio

    def inverse_position(self, x):
        return x * self.ratio

    def chain(self):
        return [("load", self.position, "rad")]

    def __repr__(self) -> str:
        return f"Gearbox(ratio={self.ratio:g}, inertia={self.inertia:g} kg m^2)"


def check_reach(tr: Transmission, fields, key: str, timing, remedy: str) -> None:
    """Refuse (naming ``key`` of ``fields``) a transmission ``tr`` whose range the positions of ``timing``
    leave (:meth:`Transmission.range_error`); ``remedy`` says what to change."""
    why = tr.range_error(*timing.position_range)
    if why is not None:
        message = f"the strokes of [timing] reach beyond the {tr.label}'s range: {why}; {remedy}"
        # the --set that moved the positions, unless the transmission's own field was set too
        moved = sorted(f for f in fields.overridden if f.startswith("timing."))
        if moved and fields.where(key) not in fields.overridden:
            raise ProblemError(fields.file, moved[0], f"{message} (value from --set)")
        raise fields.error(key, message)
