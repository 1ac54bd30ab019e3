"""A planar linkage as data: joints at a reference pose, links as sets of joints, the driven crank,
named outputs, masses and process loads.

Lengths and the shapes of ternary links are not stated: they follow from the joint coordinates of
the reference pose, which also picks the assembly branch the kinematics keeps. Everything is in SI
(metres, radians, kilograms); the file reader (files.py) converts at the boundary.

A *joint* is a point named in the data: a revolute pair where it belongs to two or more bodies
(a ground joint belongs to the ground), or a tracer point (a needle point) where it belongs to one
moving link only. Ground is not listed among the links: it is the set of ground joints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Joint:
    name: str
    x: float          # reference pose [m]
    y: float
    ground: bool = False

    @property
    def xy(self) -> np.ndarray:
        return np.array([self.x, self.y])


@dataclass(frozen=True)
class Link:
    """A rigid body through its joints; ``mass_kg`` with its centre of gravity at the reference pose
    ``cg`` [m] and its moment of inertia about the centre of gravity ``inertia_cg`` [kg m^2]."""

    name: str
    joints: tuple[str, ...]
    mass: float = 0.0
    cg: tuple[float, float] | None = None
    inertia_cg: float = 0.0


@dataclass(frozen=True)
class Crank:
    """The driven input: ``link`` turns about its ground joint ``pivot``; the input angle is
    ``reference_angle`` [rad] at the reference pose and grows counter-clockwise."""

    link: str
    pivot: str
    reference_angle: float = 0.0


@dataclass(frozen=True)
class Output:
    """A named output of the linkage.

    kind ``angle``: the direction of the line ``start`` -> ``end`` (two joints of one link) [rad];
    kind ``arc``: the arc length [m] of joint ``end`` about the ground joint ``start``, from the
    reference pose; kind ``x`` / ``y``: a coordinate of joint ``end`` [m]. ``sign`` is +1 when the
    output counts counter-clockwise (or along +x, +y), -1 when clockwise.
    """

    name: str
    kind: str
    end: str
    start: str | None = None
    sign: float = 1.0


@dataclass(frozen=True)
class Load:
    """A process force on joint ``joint`` of link ``link``: magnitude ramped linearly from ``force_start``
    to ``force_end`` [N] while the input angle runs from ``start`` to ``end`` [rad] (mod one turn), zero
    elsewhere; its direction is ``direction`` [rad] counter-clockwise from the link's line (its first joint
    to its second), so it turns with the link (pi/2: perpendicular, counter-clockwise about the first)."""

    name: str
    link: str
    joint: str
    start: float
    end: float
    force_start: float
    force_end: float
    direction: float


@dataclass(frozen=True)
class Linkage:
    """The linkage's data; ``file`` names where it came from (for messages)."""

    joints: tuple[Joint, ...]
    links: tuple[Link, ...]
    crank: Crank
    outputs: tuple[Output, ...] = ()
    loads: tuple[Load, ...] = ()
    gravity: float = 0.0            # m/s^2 along -y; 0: none
    file: str = "<linkage>"
    name: str = "linkage"
    fields: dict = field(default_factory=dict, compare=False)   # data item -> file field (messages)

    def joint(self, name: str) -> Joint:
        return self.joints[self.joint_index(name)]

    def joint_index(self, name: str) -> int:
        for i, j in enumerate(self.joints):
            if j.name == name:
                return i
        raise KeyError(name)

    def link(self, name: str) -> Link:
        for link in self.links:
            if link.name == name:
                return link
        raise KeyError(name)

    def reference(self) -> np.ndarray:
        """All joint coordinates of the reference pose, flat ``[x0, y0, x1, y1, ...]`` [m]."""
        return np.array([c for j in self.joints for c in (j.x, j.y)], dtype=float)

    def with_reference(self, coords) -> "Linkage":
        """The same linkage with other reference coordinates (flat, as :meth:`reference`)."""
        coords = np.asarray(coords, dtype=float).reshape(-1, 2)
        joints = tuple(Joint(j.name, float(c[0]), float(c[1]), j.ground) for j, c in zip(self.joints, coords))
        index = {j.name: i for i, j in enumerate(self.joints)}
        links = []
        for link in self.links:   # a centre of gravity keeps its place in its link's frame (metres)
            if link.cg is not None:
                old = [self.joints[index[n]].xy for n in link.joints[:2]]
                new = [coords[index[n]] for n in link.joints[:2]]
                u, w = _frame(*old) @ (np.asarray(link.cg) - old[0])
                ex, ey = _frame(*new)
                link = Link(link.name, link.joints, link.mass, tuple(new[0] + u * ex + w * ey), link.inertia_cg)
            links.append(link)
        return Linkage(joints, tuple(links), self.crank, self.outputs, self.loads, self.gravity, self.file,
                       self.name, self.fields)

    def field_of(self, key: str, default: str = "") -> str:
        return self.fields.get(key, default)

    def length(self, a: str, b: str) -> float:
        """Distance of two joints at the reference pose [m]."""
        return float(math.dist(self.joint(a).xy, self.joint(b).xy))


def _frame(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rows: the unit vector from a to b and its counter-clockwise normal."""
    e = (b - a) / np.linalg.norm(b - a)
    return np.array([e, [-e[1], e[0]]])
