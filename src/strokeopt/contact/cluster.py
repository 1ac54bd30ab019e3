"""The rigid cluster: the bodies that ride on the driven body, and the force each contact holds them with.

At rest (every body at x = 0, the model's start) some contacts are closed: a contact of gap 0
(the needle bar's control member on the shell, c21; the cage on the shell, c31) or a grip whose
condition holds. Bodies joined to the driven body through such contacts move with it as one rigid
*cluster* while the contacts stay closed. Each body then sits at a fixed offset from the driven
body, so the force on every joining contact is an algebraic function of the driven body's motion
``x_d, v_d, a_d`` and of the model's springs, preloads and masses -- no integration. For a
joining contact ``e`` whose far side is the subtree ``T`` of the cluster (the bodies reached
through ``e``), Newton's law for ``T``::

    M_T a_d = F_ext(T) + F_e(T)

where ``F_ext(T)`` sums every other element's force on ``T`` (elements inside ``T`` cancel) and
``F_e(T)`` is ``e``'s force on ``T``; ``e``'s compression force follows from it. It must stay
positive for the contact to stay closed (:meth:`Cluster.contact_force`). Bodies outside the
cluster are taken where they start (at rest, x = 0), like the frame.

The cluster holds only until a contact from ``T`` to the frame (or to a body outside the
cluster) closes: the needle bar's control member lands on its stop (the ``impact`` contact,
``pad``) and stays there while the shell goes on. :meth:`Cluster.holds` is that condition and
:meth:`Cluster.closing_positions` the driven body's positions where it ends.

Works on numbers, numpy arrays and CasADi symbols alike (the design's NLP writes its
constraints with it, design/contact_limits.py); a stiffness may be a symbol (a free model
parameter, ``stiffness``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from .model import FRAME, Element
from .scene import Scene


def _symbolic(*xs) -> bool:
    return any(isinstance(x, (ca.SX, ca.MX, ca.DM)) for x in xs)


def _where(cond, a, b):
    if _symbolic(cond, a, b):
        return ca.if_else(cond, a, b)
    return np.where(cond, a, b)


def closed_at_rest(el: Element) -> bool:
    """Whether an element joins its bodies at rest (all at x = 0): a contact of gap 0, a grip whose condition holds."""
    if el.kind == "contact":
        return el.offset >= 0
    if el.kind == "grip":
        return el.acts_while[2] >= 0
    return False


@dataclass(frozen=True)
class Cluster:
    """The bodies of ``scene`` riding on its driven body; ``joins``: body -> (joining element, parent body).

    ``offsets``: body -> ``x_body - x_driven`` while the cluster holds (m).
    """

    scene: Scene
    joins: dict = field(default_factory=dict)
    offsets: dict = field(default_factory=dict)

    @property
    def bodies(self) -> tuple[str, ...]:
        return tuple(self.offsets)

    @property
    def joining(self) -> dict[str, str]:
        """Joining element -> the body it holds on the cluster (its child)."""
        return {el: body for body, (el, _) in self.joins.items()}

    def subtree(self, body: str) -> set[str]:
        """``body`` and the bodies joined to the cluster through it."""
        out = {body}
        grew = True
        while grew:
            grew = False
            for child, (_, parent) in self.joins.items():
                if parent in out and child not in out:
                    out.add(child)
                    grew = True
        return out

    def _position(self, body: str, xd):
        if body in self.offsets:
            return xd + self.offsets[body]
        return 0.0 * xd  # the frame and bodies outside the cluster stay where they start

    def _velocity(self, body: str, vd):
        return vd if body in self.offsets else 0.0 * vd

    def _force(self, el: Element, xd, vd, stiffness=None):
        """The element's compression force with the cluster at ``xd, vd`` (switch included)."""
        a_, b_ = el.bodies
        cd = self._velocity(a_, vd) - self._velocity(b_, vd)
        law = (lambda c: stiffness * c) if stiffness is not None else el.elastic_force
        if el.kind == "grip":
            p, q, off = el.acts_while
            cond = self._position(p, xd) - self._position(q, xd) + off
            return _where(cond >= 0, law(self._position(a_, xd) - self._position(b_, xd)) + el.damping * cd, 0 * xd)
        c = self._position(a_, xd) - self._position(b_, xd) + el.offset
        return _where(c >= 0, law(c) + el.damping * cd, 0 * xd)

    def _outside(self, tree: set[str]) -> list[Element]:
        """Contacts between ``tree`` and the frame or a body outside the cluster (stops, next bodies)."""
        out = []
        for el in self.scene.element_objects:
            if el.kind != "contact":
                continue
            a_, b_ = el.bodies
            inside = (a_ in tree) + (b_ in tree)
            other = b_ if a_ in tree else a_
            if inside == 1 and other not in self.offsets:
                out.append(el)
        return out

    def contact_force(self, element: str, xd, vd, ad, stiffness: dict | None = None, stops: bool = True):
        """Compression force [N] of the joining contact ``element`` while the cluster holds, the driven body at
        ``xd, vd, ad`` (SI, model coordinates). ``stiffness``: element name -> stiffness replacing the model's
        (a free parameter; the preload length stays, so the preload force scales with it). ``stops=False``
        leaves out the contacts to the outside (open wherever the cluster holds): a smooth function."""
        stiffness = stiffness or {}
        child = self.joining[element]
        tree = self.subtree(child)
        masses = self.scene.model.bodies
        total = 0.0 * ad
        outside = set() if stops else {el.name for el in self._outside(tree)}
        for el in self.scene.element_objects:
            if el.name == element or el.name in outside:
                continue
            a_, b_ = el.bodies
            sign = (-1.0 if a_ in tree else 0.0) + (1.0 if b_ in tree else 0.0)
            if sign:
                total = total + sign * self._force(el, xd, vd, stiffness.get(el.name))
        on_tree = sum(masses[b].mass for b in tree) * ad - total  # the joining contact's force on the subtree
        a_, _ = self.scene.model.elements[element].bodies
        return -on_tree if a_ in tree else on_tree

    def holds(self, element: str, xd):
        """Whether the cluster holds at ``xd`` for ``element``'s subtree: every contact from it to the outside
        open (numbers: a boolean array; CasADi: a 0/1 expression)."""
        tree = self.subtree(self.joining[element])
        cond = None
        for el in self._outside(tree):
            a_, b_ = el.bodies
            c = self._position(a_, xd) - self._position(b_, xd) + el.offset
            cond = (c < 0) if cond is None else (ca.logic_and(cond, c < 0) if _symbolic(c) else cond & (c < 0))
        return (0 * xd == 0) if cond is None else cond

    def overrun(self, element: str, xd):
        """How far [m] the contacts from ``element``'s subtree to the outside are closed at ``xd`` (the sum of
        their compressions where positive): 0 wherever the cluster holds, growing past a stop (CasADi or numpy)."""
        tree = self.subtree(self.joining[element])
        total = 0.0 * xd
        for el in self._outside(tree):
            a_, b_ = el.bodies
            c = self._position(a_, xd) - self._position(b_, xd) + el.offset
            total = total + (ca.fmax(c, 0) if _symbolic(c) else np.maximum(c, 0))
        return total

    def closing_positions(self, element: str) -> list[tuple[str, float, float]]:
        """(contact, driven position x_d [m], direction +1/-1 of x_d that closes it) of every contact from
        ``element``'s subtree to the outside: where the cluster ends."""
        tree = self.subtree(self.joining[element])
        out = []
        for el in self._outside(tree):
            a_, b_ = el.bodies
            # c = sa * (xd + off_a) - sb * (xd + off_b) + offset, linear in xd with slope sa - sb (+1 or -1)
            slope = (1.0 if a_ in tree else 0.0) - (1.0 if b_ in tree else 0.0)
            c0 = self._position(a_, 0.0) - self._position(b_, 0.0) + el.offset
            out.append((el.name, -c0 / slope, slope))
        return out


def build_cluster(scene: Scene) -> Cluster:
    """The cluster of ``scene``: the driven body and every body joined to it by elements closed at rest.

    A body reached twice (a loop of closed contacts) makes the contact forces statically indeterminate:
    its second joining element is left out of the tree (its force is then read as zero)."""
    driven = scene.driven
    offsets = {driven: 0.0}
    joins: dict = {}
    grew = True
    while grew:
        grew = False
        for el in scene.element_objects:
            if not closed_at_rest(el) or FRAME in el.bodies:
                continue
            a_, b_ = el.bodies
            if (a_ in offsets) == (b_ in offsets):
                continue
            child, parent = (b_, a_) if a_ in offsets else (a_, b_)
            # closed: x_a - x_b = gap (contact) or 0 (grip)
            gap = -el.offset if el.kind == "contact" else 0.0
            offsets[child] = offsets[parent] + (gap if child == a_ else -gap)
            joins[child] = (el.name, parent)
            grew = True
    return Cluster(scene, joins, offsets)


def softest_stiffness(cluster: Cluster, element: str, spring: str, xd, vd, ad, min_force: float = 0.0) -> float:
    """The smallest stiffness of ``spring`` (N/m, its installed length kept) with which the joining contact
    ``element`` keeps at least ``min_force`` over the motion ``xd, vd, ad`` (numpy arrays, model coordinates)
    wherever the cluster holds: the force is affine in a linear spring's stiffness. 0 if any stiffness will do;
    inf if none will (the spring does not press the contact)."""
    f0 = np.asarray(cluster.contact_force(element, xd, vd, ad, {spring: 0.0}), float)
    slope = np.asarray(cluster.contact_force(element, xd, vd, ad, {spring: 1.0}), float) - f0
    held = np.asarray(cluster.holds(element, xd), bool) & (f0 < min_force)
    if not held.any():
        return 0.0
    if np.any(slope[held] <= 0):
        return float("inf")
    return float(np.max((min_force - f0[held]) / slope[held]))
