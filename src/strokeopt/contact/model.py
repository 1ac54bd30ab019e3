"""A one-dimensional multibody contact model, declared as data in the problem file.

The model is what a mechanism *is*: bodies on one axis, the springs and
contacts between them, the force laws of the nonlinear elements and the one
body that is driven by the stroke. Nothing of a particular mechanism is
written in Python: the six-body needle bar (thesis ch. 5, eqs. 5.30-5.35,
sources A.6) lives in ``problems/deco2000_needle_bar.toml`` as ``[model]``.

Coordinates are positive in the direction of the handover move (for the needle
bar: downward, the direction of move 1) and measured from the position every
body has at the start of the cycle.

Every element acts between two bodies ``bodies = [a, b]`` (``"frame"`` is the
fixed ground). Its *compression* is

    c = x_a - x_b + offset

with ``offset = free_length - installed_length`` for a spring (its preload)
and ``offset = -gap`` for a contact, so an element pushes ``a`` back and ``b``
forward with ``F = law(c) + damping * c'`` while it acts; ``law(c)`` is
``stiffness * c`` or a polynomial force law. Springs and contacts act only
while ``c >= 0`` (compression only). A *grip* (the balls of the needle-bar cage
holding the needle) is bilateral, ``F = k (x_a - x_b) + b (x_a' - x_b')``, and
acts while a condition between two other bodies holds:
``x_p - x_q + acts_while_offset >= 0``. A *link* (``[model.links.*]``: the elastic
chain of the knitting machine) is bilateral with a dead zone, a total play V:
``F = k (c -+ V/2) + b c'`` once ``|c| > V/2``; its damping may come from a
logarithmic decrement (``b = delta/pi sqrt(k m*)``).

Bodies may move on the members of the problem's transmission (``stage``: the nut,
the lever, the sleeve of a screw lever; an angular member takes ``inertia_kg_cm2``):
the driven body then follows the stroke through the transmission, and a body that
``rides_on`` another is carried by it through the transmission's maps (no state of
its own; its inertia enters its host's equation, scene.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from .events import ROLE_KINDS, EventRoles

if TYPE_CHECKING:  # type only: io/problem_file.py passes the Fields reader of [model] in
    from ..io.fields import Fields

FRAME = "frame"
ELEMENT_KINDS = ("spring", "contact", "grip", "link")


@dataclass(frozen=True)
class Body:
    """A rigid body on the axis. ``mass`` in kg (its moment of inertia in kg m^2 on an angular stage).

    ``stage``: the member of the problem's transmission whose coordinate the body moves on (None: the
    model's own axis); a driven body on a stage follows the stroke through the transmission.
    ``rides_on``: a body this one is rigidly coupled to through the transmission (its coordinate is
    the chain's map from the host's stage to its own: a lever tilted by a nut); it has no state, its
    inertia is carried by the host's equation."""

    name: str
    mass: float
    driven: bool = False
    label: str = ""
    stage: str | None = None
    rides_on: str | None = None
    angular: bool = False  # on an angular coordinate (a lever): mass is a moment of inertia, positions in rad


@dataclass(frozen=True)
class ForceLaw:
    """A polynomial force law ``F = sum_i c_i x^i`` (F in N, compression x in m; SI coefficients)."""

    name: str
    coefficients: tuple[float, ...]

    def __call__(self, x):
        out = 0.0 * x
        for c in reversed(self.coefficients):
            out = out * x + c
        return out


@dataclass(frozen=True)
class Element:
    """A spring, contact or grip between ``bodies[0]`` and ``bodies[1]`` (``"frame"`` allowed).

    ``offset`` (m) enters the compression ``c = x_a - x_b + offset``. ``force_law``
    replaces ``stiffness * c`` when given. ``acts_while = (p, q, offset)``: a grip acts
    while ``x_p - x_q + offset >= 0``.
    """

    name: str
    kind: str
    bodies: tuple[str, str]
    stiffness: float
    damping: float
    offset: float = 0.0
    force_law: ForceLaw | None = None
    acts_while: tuple[str, str, float] | None = None
    label: str = ""
    clearance: float = 0.0  # a link's total play (m or rad): it acts once |x_a - x_b| passes clearance / 2
    log_decrement: float | None = None  # a link's damping came from this logarithmic decrement

    @property
    def gap(self) -> float:
        """The gap of a contact (m): how far ``a`` moves relative to ``b`` before it closes."""
        return -self.offset if self.kind == "contact" else 0.0

    @property
    def preload(self) -> float:
        """Initial compression of a spring (free minus installed length, m)."""
        return self.offset if self.kind == "spring" else 0.0

    @property
    def body_names(self) -> set[str]:
        """Bodies this element needs (the frame excluded), including those of its acts_while condition."""
        names = set(self.bodies)
        if self.acts_while is not None:
            names |= {self.acts_while[0], self.acts_while[1]}
        return names - {FRAME}

    def elastic_force(self, c):
        """Force of the elastic part at compression ``c`` (numbers or CasADi expressions)."""
        return self.force_law(c) if self.force_law is not None else self.stiffness * c


@dataclass(frozen=True)
class Model:
    """Bodies, springs, contacts (grips included), force laws and the driven body."""

    bodies: dict[str, Body]
    springs: dict[str, Element]
    contacts: dict[str, Element]
    force_laws: dict[str, ForceLaw] = field(default_factory=dict)
    events: EventRoles = field(default_factory=EventRoles)
    description: str = ""

    @property
    def driven(self) -> str:
        return next(b.name for b in self.bodies.values() if b.driven)

    links: dict[str, Element] = field(default_factory=dict)
    transmission: object = None  # the problem's transmission, when a body moves on one of its stages

    @property
    def elements(self) -> dict[str, Element]:
        return {**self.springs, **self.contacts, **self.links}

    def riders(self, host: str) -> list[Body]:
        return [b for b in self.bodies.values() if b.rides_on == host]

    def rider_map(self, body: Body, q):
        """The coordinate of the rider ``body`` from its host's coordinate ``q`` (CasADi-friendly)."""
        host = self.bodies[body.rides_on]
        return self.transmission.stage_map(host.stage, body.stage, q)

    def reduced_inertia(self, name: str) -> float:
        """A body's inertia with its riders' at rest (x = 0): m + sum I_r (dq_r/dx)^2 (kg or kg m^2)."""
        import casadi as ca

        q = ca.SX.sym("q")
        total = self.bodies[name].mass
        for r in self.riders(name):
            d = ca.Function("d", [q], [ca.jacobian(self.rider_map(r, q), q)])
            total += r.mass * float(d(0.0)) ** 2
        return total


# --------------------------------------------------------------------------- parsing


def _name_list(f: "Fields", key: str, known, what: str, length: int | None = None) -> list[str]:
    value = f.raw(key)
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise f.error(key, f"must be an array of {what} names, got {value!r}")
    if length is not None and len(value) != length:
        raise f.error(key, f"must name exactly {length} {what}s, got {len(value)}")
    for v in value:
        if v not in known:
            raise f.error(key, f"unknown {what} {v!r}; known: {', '.join(sorted(known))}")
    return list(value)


def _parse_link(f: "Fields", name: str, bodies: dict, model_inertia) -> Element:
    """A bilateral elastic link with a dead zone (a clearance) between two bodies on the same kind of
    coordinate: ``F = k (c -+ V/2) + b c'`` once ``|c| > V/2`` (c = x_a - x_b, V the total play), 0 inside.
    Damping ``damping_*`` or ``log_decrement`` delta: ``b = delta/pi sqrt(k m*)`` with ``m*`` the
    reduced inertia at rest of the second body (the first when the second is the frame)."""
    pair = _name_list(f, "bodies", set(bodies) | {FRAME}, "body", length=2)
    if pair[0] == pair[1]:
        raise f.error("bodies", f"an element needs two different bodies, got {pair[0]!r} twice")
    angular = {bodies[b].angular for b in pair if b != FRAME}
    if len(angular) > 1:
        raise f.error("bodies", "links one body on a linear and one on an angular coordinate: put both on the "
                                "same kind (a rider carries a body across the transmission)")
    unit = ("N_m_rad", "N_m_s_rad", "rad", 1.0) if angular == {True} else ("N_m", "N_s_m", "mm", 1e-3)
    # as springs (up to 1e12 N/m); torsion up to 1e9 N m/rad (a 100 mm steel shaft is ~1e6)
    stiffness = f.number(f"stiffness_{unit[0]}", min=0.0, max=1e12 if unit[2] == "mm" else 1e9)
    # clearances: up to 10 mm (0.01 mm is the knitting machine's V2) or 0.2 rad (11 deg)
    clearance = f.number(f"clearance_{unit[2]}", 0.0, min=0.0, max=10.0 if unit[2] == "mm" else 0.2) * unit[3]
    decrement = f.number("log_decrement", None, min=0.0, max=10.0)  # ln 2 = 0.693: amplitude halves per period
    if decrement is not None and f.has(f"damping_{unit[1]}"):
        raise f.error("log_decrement", f"give either log_decrement or damping_{unit[1]}, not both")
    damping = f.number(f"damping_{unit[1]}", 0.0, min=0.0, max=1e7)
    label = f.string("label", "")
    f.finish()
    if decrement is not None:
        other = pair[1] if pair[1] != FRAME else pair[0]
        damping = decrement / math.pi * math.sqrt(stiffness * model_inertia(other))
    return Element(name, "link", (pair[0], pair[1]), stiffness, damping, 0.0, None, None, label, clearance, decrement)


def _parse_element(f: "Fields", name: str, kind_default: str, bodies: dict, laws: dict) -> Element:
    kind = f.string("kind", kind_default, choices=("contact", "grip") if kind_default != "spring" else ("spring",))
    pair = _name_list(f, "bodies", set(bodies) | {FRAME}, "body", length=2)
    if pair[0] == pair[1]:
        raise f.error("bodies", f"an element needs two different bodies, got {pair[0]!r} twice")
    law_name = f.string("force_law", None)
    if law_name is not None and law_name not in laws:
        raise f.error("force_law", f"unknown force law {law_name!r}; known: {', '.join(sorted(laws)) or 'none'}")
    if law_name is None:
        # up to 1e12 N/m: penalty contacts are 1e9 (needle bar), elastic links 1e7 (knitting machine); stiffer
        # only shortens the integrator's steps to nothing
        stiffness = f.number("stiffness_N_m", min=0.0, max=1e12)
    else:
        if f.has("stiffness_N_m"):
            raise f.error("stiffness_N_m", "give either stiffness_N_m or force_law, not both")
        stiffness = 0.0
    damping = f.number("damping_N_s_m", 0.0, min=0.0, max=1e7)  # contact damping is 100 N s/m
    label = f.string("label", "")
    acts_while = None
    if kind == "spring":
        # lengths and gaps within 10 m (clearances of 1e-5 m = 0.01 mm are the knitting machine's)
        free = f.number("free_length_mm", None, min=0.0, max=1e4)
        installed = f.number("installed_length_mm", None, min=0.0, max=1e4)
        if (free is None) != (installed is None):
            missing = "installed_length_mm" if installed is None else "free_length_mm"
            raise f.error(missing, "give free_length_mm and installed_length_mm together (or neither: no preload)")
        offset = 0.0 if free is None else (free - installed) * 1e-3
        if offset < 0:
            raise f.error("installed_length_mm", f"is longer than the free length ({installed:g} > {free:g} mm): "
                                                 "a compression spring cannot be installed stretched")
    elif kind == "contact":
        offset = -f.number("gap_mm", min=0.0, max=1e4) * 1e-3
    else:  # grip
        offset = 0.0
        cond = _name_list(f, "acts_while", set(bodies), "body", length=2)
        acts_while = (cond[0], cond[1], f.number("acts_while_offset_mm", 0.0, min=-1e4, max=1e4) * 1e-3)
    f.finish()
    return Element(name, kind, (pair[0], pair[1]), stiffness, damping, offset,
                   laws.get(law_name) if law_name else None, acts_while, label)


def _parse_body(bf: "Fields", name: str, transmission) -> Body:
    stage = bf.string("stage", None)
    angular = False
    if stage is not None:
        stages = transmission.stage_names() if transmission is not None else []
        if stage not in stages:
            raise bf.error("stage", f"{stage!r} is no member of the problem's transmission"
                                    + (f" ({transmission.name}: {', '.join(stages)})" if stages else ""))
        angular = transmission.stage_unit(stage) == "rad"
    if angular:
        if bf.has("mass_g"):
            raise bf.error("mass_g", f"the {stage} turns: give its moment of inertia inertia_kg_cm2, not mass_g")
        # a lever of 1e-4 kg cm^2 (the knitting machine's is 0.028) to a loom sley (13 000 kg cm^2)
        mass = bf.number("inertia_kg_cm2", min=1e-5, max=1e6) * 1e-4
    else:
        # 1 mg (a needle is 200 mg) to 10 t (a loom sley is 25 kg); a lighter body on a 1e9 N/m contact
        # vibrates beyond any integrator step
        mass = bf.number("mass_g", min=1e-3, max=1e7) * 1e-3
    body = Body(name, mass, bf.boolean("driven", False), bf.string("label", ""), stage, bf.string("rides_on", None),
                angular)
    return body


def _check_rider(tb: "Fields", body: Body, bodies: dict, transmission) -> None:
    host = bodies.get(body.rides_on)
    where = f"{body.name}.rides_on"
    if host is None:
        raise tb.error(where, f"unknown body {body.rides_on!r}; known: {', '.join(sorted(bodies))}")
    if body.driven or host.driven or host.rides_on is not None:
        raise tb.error(where, "a rider rides on a free body that rides on nothing (and is not driven itself)")
    if body.stage is None or host.stage is None:
        raise tb.error(where, "a rider and its host need a stage each (the transmission couples them)")
    order = transmission.stage_names()
    if order.index(body.stage) <= order.index(host.stage):
        raise tb.error(where, f"the rider's stage {body.stage!r} must come after its host's {host.stage!r} "
                              f"in the {transmission.name} ({' -> '.join(order)})")


def parse_model(f: "Fields | None", transmission=None) -> Model | None:
    """Read ``[model]``: bodies, force laws, springs, contacts, links and event roles. None if absent.
    ``transmission``: the problem's, for bodies on its stages."""
    if f is None:
        return None
    description = f.string("description", "")

    bodies: dict[str, Body] = {}
    tb = f.table("bodies")
    for name in list(tb.data):
        if name == FRAME:
            raise tb.error(name, f"{FRAME!r} is the fixed ground, not a body name")
        bf = tb.table(name)
        bodies[name] = _parse_body(bf, name, transmission)
        bf.finish()
    for body in bodies.values():
        if body.rides_on is not None:
            _check_rider(tb, body, bodies, transmission)
    tb.finish()
    driven = [b.name for b in bodies.values() if b.driven]
    if len(driven) != 1:
        what = "none is" if not driven else f"{len(driven)} are ({', '.join(driven)})"
        raise f.error("bodies", f"exactly one body must be driven = true (the one that follows the stroke); {what}")

    laws: dict[str, ForceLaw] = {}
    tl = f.table("force_laws", required=False)
    if tl is not None:
        for name in list(tl.data):
            lf = tl.table(name)
            coeffs = lf.raw("coefficients_SI")
            if (not isinstance(coeffs, list) or not coeffs
                    or not all(isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c) for c in coeffs)):
                raise lf.error("coefficients_SI", f"must be a non-empty array of finite numbers c_i of F = sum c_i x^i "
                                                  f"(N, x in m), got {coeffs!r}")
            if any(abs(c) > 1e30 for c in coeffs):  # the pad's cubic term is 1.6e12 N/m^3
                raise lf.error("coefficients_SI", f"has a coefficient beyond 1e30 (SI), got {coeffs!r}")
            if coeffs[0] != 0:
                raise lf.error("coefficients_SI", f"c_0 must be 0 (no force at zero compression), got {coeffs[0]!r}")
            laws[name] = ForceLaw(name, tuple(float(c) for c in coeffs))
            lf.finish()
        tl.finish()

    springs: dict[str, Element] = {}
    ts = f.table("springs", required=False)
    if ts is not None:
        for name in list(ts.data):
            springs[name] = _parse_element(ts.table(name), name, "spring", bodies, laws)
        ts.finish()
    contacts: dict[str, Element] = {}
    tc = f.table("contacts", required=False)
    if tc is not None:
        for name in list(tc.data):
            if name in springs:
                raise tc.error(name, "a spring has the same name; element names must be unique")
            contacts[name] = _parse_element(tc.table(name), name, "contact", bodies, laws)
        tc.finish()

    staged = any(b.stage is not None for b in bodies.values())
    links: dict[str, Element] = {}
    tk = f.table("links", required=False)
    if tk is not None:
        partial = Model(bodies, springs, contacts, laws, transmission=transmission if staged else None)
        for name in list(tk.data):
            if name in springs or name in contacts:
                raise tk.error(name, "another element has the same name; element names must be unique")
            links[name] = _parse_link(tk.table(name), name, bodies, partial.reduced_inertia)
        tk.finish()

    elements = {**springs, **contacts, **links}
    te = f.table("events", required=False)
    roles = EventRoles()
    if te is not None:
        def role(key, kinds, pool):
            value = te.string(key, None)
            if value is None:
                return None
            if value not in pool:
                raise te.error(key, f"unknown {' or '.join(kinds)} {value!r}; known: {', '.join(sorted(pool)) or 'none'}")
            if kinds != ("body",) and pool[value].kind not in kinds:
                raise te.error(key, f"{value!r} is a {pool[value].kind}, expected a {' or '.join(kinds)}")
            return value

        roles = EventRoles(**{key: role(key, kinds, bodies if kinds == ("body",) else elements)
                              for key, kinds in ROLE_KINDS.items()})
        te.finish()
    f.finish()
    return Model(bodies, springs, contacts, laws, roles, description, links, transmission if staged else None)
