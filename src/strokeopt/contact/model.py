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
``x_p - x_q + acts_while_offset >= 0``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from .events import ROLE_KINDS, EventRoles

if TYPE_CHECKING:  # type only: io/problem_file.py passes the Fields reader of [model] in
    from ..io.fields import Fields

FRAME = "frame"
ELEMENT_KINDS = ("spring", "contact", "grip")


@dataclass(frozen=True)
class Body:
    """A rigid body on the axis. ``mass`` in kg."""

    name: str
    mass: float
    driven: bool = False
    label: str = ""


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

    @property
    def elements(self) -> dict[str, Element]:
        return {**self.springs, **self.contacts}


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


def parse_model(f: "Fields | None") -> Model | None:
    """Read ``[model]``: bodies, force laws, springs, contacts and event roles. None if absent."""
    if f is None:
        return None
    description = f.string("description", "")

    bodies: dict[str, Body] = {}
    tb = f.table("bodies")
    for name in list(tb.data):
        if name == FRAME:
            raise tb.error(name, f"{FRAME!r} is the fixed ground, not a body name")
        bf = tb.table(name)
        # 1 mg (a needle is 200 mg) to 10 t (a loom sley is 25 kg); a lighter body on a 1e9 N/m contact
        # vibrates beyond any integrator step
        mass = bf.number("mass_g", min=1e-3, max=1e7) * 1e-3
        bodies[name] = Body(name, mass, bf.boolean("driven", False), bf.string("label", ""))
        bf.finish()
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

    elements = {**springs, **contacts}
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
    return Model(bodies, springs, contacts, laws, roles, description)
