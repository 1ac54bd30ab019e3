"""What the design needs of the contact model: ``[design.contact]`` checked against ``[model]``, and
:class:`ContactDesign` (the rigid cluster of contact/cluster.py in the stroke's coordinates).

:func:`check_contact` runs when the problem file is read (io/problem_file.py), so a bad name is a
one-line error naming the field; :func:`contact_design` builds the :class:`ContactDesign` of a
solve (``SolveRequest.contact``), read by design/contact_limits.py (the NLP's rows and the checks).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .settings import ContactSettings
from ...contact.cluster import Cluster, build_cluster
from ...contact.scene import default_scene
from ...contact.simulate import drive_reference
from ...errors import ProblemError

FIELD = "design.contact"


def _where(cl: Cluster) -> str:
    return ", ".join(f"{body} via {el}" for body, (el, _) in cl.joins.items()) or "no body"


def check_contact(contact: ContactSettings | None, model, scenes, file: str) -> None:
    """Every name of ``[design.contact]`` against the model and its scenes (ProblemError naming the field)."""
    if contact is None:
        return
    if model is None or not scenes:
        raise ProblemError(file, FIELD, "needs a [model] and a [scenes.*] section (the contact model it holds)")
    scene_name = contact.scene or default_scene(scenes)
    if scene_name not in scenes:
        raise ProblemError(file, f"{FIELD}.scene", f"no scene {scene_name!r}; the problem has: {', '.join(scenes)}")
    scene = scenes[scene_name]
    cl = build_cluster(scene)
    for name in contact.keep_closed:
        fld = f"{FIELD}.keep_closed"
        if name not in model.elements:
            raise ProblemError(file, fld, f"unknown element {name!r}; the model's contacts: {', '.join(model.contacts)}")
        el = model.elements[name]
        if el.kind != "contact":
            raise ProblemError(file, fld, f"{name!r} is a {el.kind}; only a contact (it can open) is kept closed")
        if name not in scene.elements:
            raise ProblemError(file, fld, f"contact {name!r} is not in scene {scene_name!r} (set {FIELD}.scene)")
        if name not in cl.joining:
            raise ProblemError(file, fld, f"contact {name!r} does not touch the driven body's cluster ({scene.driven} "
                                          f"with the bodies its contacts closed at rest hold: {_where(cl)})")
    if contact.impact_velocity_max is not None and _impact(model, cl) is None:
        impact = model.events.impact
        why = ("[model.events] names no impact contact" if impact is None else
               f"the impact contact {impact!r} is not met by a body riding on {scene.driven} in scene {scene_name!r} "
               f"({_where(cl)})")
        raise ProblemError(file, f"{FIELD}.impact_velocity_max_m_s", f"cannot be held: {why}")


def _impact(model, cl: Cluster):
    """(joining element, driven position [m], closing direction) of the model's impact contact, or None."""
    impact = model.events.impact
    if impact is None or impact not in cl.scene.elements:
        return None
    for element in cl.joining:
        for name, xd, direction in cl.closing_positions(element):
            if name == impact:
                return element, xd, direction
    return None


@dataclass(frozen=True)
class ContactDesign:
    """The contact limits of one problem: the settings, the cluster and the stroke's coordinates in the model's
    (``x_d = sign * (s - s_ref)``); ``impact``: (joining element, driven position x_d [m], closing direction of
    x_d) of the impact contact, or None."""

    settings: ContactSettings
    cluster: Cluster
    sign: float
    s_ref: float
    impact: tuple | None

    def driven(self, s, v, a):
        """The driven body's position, velocity, acceleration (model coordinates) from the stroke's."""
        return self.sign * (s - self.s_ref), self.sign * v, self.sign * a

    @property
    def impact_position(self) -> float | None:
        """The stroke position [m] where the cluster meets the impact contact."""
        return None if self.impact is None else self.s_ref + self.impact[1] / self.sign

    def closes_impact(self, move) -> bool:
        """Whether ``move`` (a design Move) crosses the impact position in the direction that closes the contact."""
        pos = self.impact_position
        if pos is None:
            return False
        lo, hi = sorted((move.start, move.start + move.stroke))
        return lo < pos < hi and np.sign(self.sign * move.stroke) == self.impact[2]

    def rest_force(self, element: str, stiffness: dict | None = None) -> float:
        """The joining contact's force with everything at rest at the start position (N)."""
        return float(self.cluster.contact_force(element, 0.0, 0.0, 0.0, stiffness))


def contact_design(problem, settings) -> ContactDesign | None:
    """The :class:`ContactDesign` of ``problem`` under ``settings`` (DesignSettings), None without ``[design.contact]``."""
    contact = getattr(settings, "contact", None)
    if contact is None or getattr(problem, "model", None) is None:
        return None
    scene = problem.scenes[contact.scene or default_scene(problem.scenes)]
    cl = build_cluster(scene)
    sign, s_ref = drive_reference(problem)
    return ContactDesign(contact, cl, sign, s_ref, _impact(problem.model, cl))
