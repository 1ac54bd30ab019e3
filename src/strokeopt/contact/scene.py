"""Scenes: the part of a model one question needs, built into a CasADi ODE.

A scene names the bodies and elements it needs (``[scenes.release]`` in the
problem file: the shell, the control member and the cage, their springs, the
pad and the pin/cage contacts). :meth:`Scene.build` writes the equations of
motion of exactly those: a body not named has no state, an element not named
is not built, not integrated and not reported. The driven body is not a state
either: it follows the stroke, ``x_driven(t) = sign * (s(t) - s_ref)``.

States are scaled so that tolerances mean something next to 1e9 N/m contacts:
positions in mm (an absolute tolerance of 1e-6 is 1 nm, 1 N on such a contact),
velocities in m/s. Time is normalised per stroke piece (``sigma`` in [0, 1],
``t = t_start + sigma * duration``) so that one integrator object restarts at
every joint of the stroke (where its derivatives may jump) with the piece
index and duration as parameters.

A scene has a time budget: ``max_steps`` (default :data:`MAX_STEPS`), the integrator steps one cycle
may take at the default tolerance (simulate.py stops a scene that needs more, naming its stiffest
contact and the step it forced, and refuses at once a contact whose period is shorter than the
budget's mean step: :meth:`Scene.contact_periods`).

Switching: ``smoothing = 0`` uses hard ``if_else`` switches (the source's
``L = 1 while c >= 0``); ``smoothing = eps > 0`` (m) replaces the compression
by ``eps * softplus(c / eps)`` and the switch by ``sigmoid(c / eps)``, which
adds ``k * eps * ln 2`` of force at zero compression (see simulate.py for
what each costs).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import casadi as ca

from .model import FRAME, Element, Model

if TYPE_CHECKING:
    from ..io.fields import Fields
    from ..motion.stroke import StrokeFunction


#: Integrator steps a scene may take over one cycle at the default tolerance (rtol 1e-5), unless its
#: ``max_steps`` says otherwise: 20 times what the reference problem's scenes take (release 22 600, handover
#: 51 300 at 500 spm; a million steps are 3-4 s of CPU). A tighter tolerance gets more (``step_budget``).
MAX_STEPS = 1_000_000
BUDGET_RTOL = 1e-5  # the tolerance max_steps is stated at
#: A tighter tolerance gets at most this many times ``max_steps``: the budget bounds the time of a run at any
#: tolerance (a scene too stiff for it is refused in about the same time at rtol 1e-8 as at the default).
BUDGET_GROWTH = 4.0

#: The integrator's tolerances a simulation accepts (SimulationOptions.check; simulate --rtol, --atol).
#: rtol: up to 1e-2 (at 0.1 the reference scene's peak forces leave their plausible bound and its impact is
#: known to 10 %); down to 1e-12, a few thousand times the double's rounding (the tolerance study's reference
#: is 1e-9). atol, on the scaled states (positions in mm, velocities in m/s): up to 1e-3, the 1 um below which
#: a gap counts as closed (contact/events.GAP_CLOSED); at 1e-1 the follower's lag starts 20 deg early;
#: down to 1e-12 (states of order 10 mm then hold 13 digits).
TOLERANCE_RANGES = {"rtol": (1e-12, 1e-2), "atol": (1e-12, 1e-3)}


@dataclass(frozen=True)
class Scene:
    """The bodies and elements of a model that one simulation needs.

    ``max_steps``: the integrator steps one cycle may take at the default tolerance (its time budget: a scene
    that needs more stops, naming its stiffest contact)."""

    name: str
    model: Model = field(repr=False)
    bodies: tuple[str, ...]
    elements: tuple[str, ...]
    description: str = ""
    max_steps: int = MAX_STEPS

    def step_budget(self, rtol: float) -> int:
        """The steps a cycle may take at relative tolerance ``rtol``: ``max_steps``, times
        ``(1e-5 / rtol)^(1/3)`` below 1e-5 (BDF of order 2 takes steps ~ rtol^(1/3): 20 100 at 1e-5,
        200 000 at 1e-8, 900 000 at 1e-10 in the release scene at 600 spm, 1.8 million in the handover
        scene), at most :data:`BUDGET_GROWTH` times ``max_steps``."""
        return int(self.max_steps * min(max(1.0, (BUDGET_RTOL / rtol) ** (1.0 / 3.0)), BUDGET_GROWTH))

    def check_resolvable(self, file: str, period: float, budget: int) -> None:
        """Refuse a scene whose stiffest contact rings faster than ``budget`` steps can follow over a cycle of
        ``period`` s: a contact period shorter than ``period / budget`` leaves less than one step per period even
        if every step of the budget went to it (a ProblemError naming the contact's stiffness)."""
        from ..errors import ProblemError

        periods = self.contact_periods()
        if not periods or periods[0][0] >= period / budget:
            return
        shortest, name, body = periods[0]
        el = self.model.elements[name]
        table = "links" if el.kind == "link" else ("springs" if el.kind == "spring" else "contacts")
        k_max = el.stiffness * (shortest * budget / period) ** 2
        raise ProblemError(file, f"model.{table}.{name}.stiffness_N_m",
                           f"{el.stiffness:.3g} N/m on the {self.model.bodies[body].mass * 1e3:.3g} g {body} rings with "
                           f"a period of {shortest:.2g} s, shorter than scene {self.name!r} can resolve in its cycle of "
                           f"{period:.3g} s with its budget of {budget:,} steps ({period / budget:.2g} s a step): soften "
                           f"it (below {k_max:.2g} N/m), or raise scenes.{self.name}.max_steps")

    def contact_periods(self) -> list[tuple[float, str, str]]:
        """``(period s, element, lightest body)`` of every element with a linear stiffness, shortest first:
        ``2 pi sqrt(m / k)`` with ``m`` the lightest body on it (the frame and force laws aside)."""
        out = []
        for el in self.element_objects:
            if el.force_law is not None or not el.stiffness > 0:
                continue
            bodies = [b for b in el.bodies if b != FRAME]
            if not bodies:
                continue
            light = min(bodies, key=lambda b: self.model.bodies[b].mass)
            out.append((2 * math.pi * math.sqrt(self.model.bodies[light].mass / el.stiffness), el.name, light))
        return sorted(out)

    @property
    def driven(self) -> str:
        return self.model.driven

    @property
    def free_bodies(self) -> tuple[str, ...]:
        """The bodies that have states, in state order (not the driven body, not the riders)."""
        return tuple(b for b in self.bodies if b != self.driven and self.model.bodies[b].rides_on is None)

    @property
    def riders(self) -> tuple[str, ...]:
        """The bodies carried by a free body through the transmission (no state of their own)."""
        return tuple(b for b in self.bodies if self.model.bodies[b].rides_on is not None)

    @property
    def state_size(self) -> int:
        return 2 * len(self.free_bodies)

    @property
    def element_objects(self) -> tuple[Element, ...]:
        els = self.model.elements
        return tuple(els[e] for e in self.elements)

    def build(self, stroke: "StrokeFunction", sign: float, s_ref: float, smoothing: float = 0.0) -> "SceneODE":
        """The scene's ODE with the driven body following ``stroke``: ``x = sign * (s - s_ref)``."""
        return SceneODE(self, stroke, float(sign), float(s_ref), float(smoothing))


def default_scene(scenes: dict) -> str:
    """The scene a design is held to and verified in when none is named: ``release`` if present, else the first."""
    return "release" if "release" in scenes else next(iter(scenes))


def make_scene(model: Model, name: str, bodies, elements, description: str = "", where=None,
               max_steps: int = MAX_STEPS) -> Scene:
    """A scene from names, checked against the model. ``where = (file, field)`` for error messages."""
    from ..errors import ProblemError

    file, fld = where or ("scene", name)
    bodies = tuple(bodies)
    elements = tuple(elements)
    for b in bodies:
        if b not in model.bodies:
            raise ProblemError(file, f"{fld}.bodies", f"unknown body {b!r}; the model has: {', '.join(model.bodies)}")
    if len(set(bodies)) != len(bodies):
        raise ProblemError(file, f"{fld}.bodies", "names a body twice")
    if model.driven not in bodies:
        raise ProblemError(file, f"{fld}.bodies", f"must include the driven body {model.driven!r} (nothing moves without it)")
    for b in bodies:
        host = model.bodies[b].rides_on
        if host is not None and host not in bodies:
            raise ProblemError(file, f"{fld}.bodies", f"body {b!r} rides on {host!r}, which the scene does not name")
    known = model.elements
    for e in elements:
        if e not in known:
            raise ProblemError(file, f"{fld}.elements", f"unknown element {e!r}; the model has: {', '.join(known)}")
        missing = sorted(known[e].body_names - set(bodies))
        if missing:
            raise ProblemError(file, f"{fld}.elements", f"element {e!r} needs bod{'ies' if len(missing) > 1 else 'y'} "
                                                        f"{', '.join(map(repr, missing))}, which the scene does not name")
    if len(set(elements)) != len(elements):
        raise ProblemError(file, f"{fld}.elements", "names an element twice")
    return Scene(name, model, bodies, elements, description, int(max_steps))


def parse_scenes(f: "Fields | None", model: Model | None) -> dict[str, Scene] | None:
    """Read ``[scenes.<name>]`` tables (bodies, elements, description). None if absent."""
    if f is None:
        return None
    if model is None:
        raise f.error("", "scenes need a [model] section to take their bodies and elements from")
    scenes = {}
    for name in list(f.data):
        sf = f.table(name)
        description = sf.string("description", "")
        # the steps one cycle may take at rtol 1e-5 (more at tighter tolerances): at least 10 000 (the reference
        # scenes take 22 600 and 51 300), at most 1e9 (an hour of CPU)
        max_steps = sf.number("max_steps", MAX_STEPS, integer=True, min=10_000, max=1e9)
        bodies = sf.raw("bodies")
        elements = sf.raw("elements", [])
        for key, value in (("bodies", bodies), ("elements", elements)):
            if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
                raise sf.error(key, f"must be an array of names, got {value!r}")
        sf.finish()
        scenes[name] = make_scene(model, name, bodies, elements, description, where=(sf.file, sf.path),
                                  max_steps=max_steps)
    f.finish()
    if not scenes:
        raise f.error("", "defines no scene")
    return scenes


def _through_transmission(tr, stage: str, s, v, a):
    """Position, speed and acceleration of member ``stage`` of transmission ``tr`` while its load follows
    ``s, v, a`` (CasADi): the motor angle from the inverse, the member by the chain rule (AD)."""
    phi, omega, eps = tr.motor_kinematics(s, v, a)
    q = ca.SX.sym("q")
    g = tr.stage_map("motor", stage, q)
    d1 = ca.jacobian(g, q)
    g0, g1, g2 = ca.Function("driven_stage", [q], [g, d1, ca.jacobian(d1, q)])(phi)
    return g0, g1 * omega, g1 * eps + g2 * omega**2


def _link_force(el, c, cd, eps: float):
    """Force of a link (compression ``c``, its rate ``cd``) with a dead zone of +-clearance/2, and its
    switching function (>= 0 while it acts). Without clearance it always acts: no switch at all."""
    h = el.clearance / 2
    if h == 0:
        return el.stiffness * c + el.damping * cd, ca.SX(1)
    if eps > 0:
        cz = eps * _softplus((c - h) / eps) - eps * _softplus((-c - h) / eps)
        return el.stiffness * cz + (_sigmoid((c - h) / eps) + _sigmoid((-c - h) / eps)) * el.damping * cd, \
            ca.fabs(c) - h
    cz = ca.if_else(c > h, c - h, ca.if_else(c < -h, c + h, 0))
    return ca.if_else(ca.fabs(c) > h, el.stiffness * cz + el.damping * cd, 0), ca.fabs(c) - h


def _softplus(z):
    return ca.fmax(z, 0) + ca.log(1 + ca.exp(-ca.fabs(z)))


def _sigmoid(z):
    return 0.5 * (1 + ca.tanh(0.5 * z))


class SceneODE:
    """The CasADi equations of one scene driven by one stroke.

    * ``dae``: ``{"x", "p", "t", "ode"}`` for ``casadi.integrator`` in normalised piece time
      ``sigma``, ``p = [piece index, piece start time, piece duration]``;
    * ``outputs``: Function ``(sigma, x, p) -> [t, x_d, v_d, a_d, accelerations, element forces, drive force]``
      (SI) to evaluate along a trajectory;
    * ``forces``: Function ``(sigma, x, p) -> [element forces; drive force]`` (N), the same forces alone.
    """

    def __init__(self, scene: Scene, stroke: "StrokeFunction", sign: float, s_ref: float, smoothing: float):
        self.scene = scene
        self.smoothing = smoothing
        free = scene.free_bodies
        n = len(free)
        sigma = ca.SX.sym("sigma")
        z = ca.SX.sym("z", 2 * n)
        p = ca.SX.sym("p", 3)
        k, t0, dur = p[0], p[1], p[2]
        tau = sigma * dur
        s_list, v_list, a_list = [], [], []
        for piece in stroke.pieces:
            s, v, a, _ = piece.symbolic(tau)
            s_list.append(s)
            v_list.append(v)
            a_list.append(a)
        if len(stroke.pieces) == 1:
            s, v, a = s_list[0], v_list[0], a_list[0]
        else:
            s = ca.conditional(k, s_list, s_list[-1])
            v = ca.conditional(k, v_list, v_list[-1])
            a = ca.conditional(k, a_list, a_list[-1])
        model = scene.model
        stage = model.bodies[scene.driven].stage
        if stage is None:
            xd, vd, ad = sign * (s - s_ref), sign * v, sign * a
        else:  # the driven body follows the stroke through the transmission: its stage's coordinate
            xd, vd, ad = _through_transmission(model.transmission, stage, s, v, a)

        pos = {scene.driven: xd, FRAME: ca.SX(0)}
        vel = {scene.driven: vd, FRAME: ca.SX(0)}
        for i, b in enumerate(free):
            pos[b] = z[i] * 1e-3
            vel[b] = z[n + i]
        carried = {}  # rider -> (host, dq/dx, d2q/dx2)
        for r in scene.riders:
            body = model.bodies[r]
            q = ca.SX.sym("q")
            g = model.rider_map(body, q)
            d1 = ca.jacobian(g, q)
            gf = ca.Function("rider", [q], [g, d1, ca.jacobian(d1, q)])
            host = body.rides_on
            g0, g1, g2 = gf(pos[host])
            pos[r], vel[r] = g0, g1 * vel[host]
            carried[r] = (host, g1, g2)
        force_on = {b: ca.SX(0) for b in scene.bodies}
        force_on[FRAME] = ca.SX(0)
        forces, switches = [], []
        eps = smoothing
        for el in scene.element_objects:
            a_, b_ = el.bodies
            if el.kind == "link":
                f, sw = _link_force(el, pos[a_] - pos[b_], vel[a_] - vel[b_], eps)
                switches.append(sw)
            elif el.kind == "grip":
                c = pos[a_] - pos[b_]
                cond = pos[el.acts_while[0]] - pos[el.acts_while[1]] + el.acts_while[2]
                switches.append(cond)
                active = el.elastic_force(c) + el.damping * (vel[a_] - vel[b_])
                if eps > 0:
                    f = _sigmoid(cond / eps) * active
                else:
                    f = ca.if_else(cond >= 0, active, 0)
            else:
                c = pos[a_] - pos[b_] + el.offset
                cd = vel[a_] - vel[b_]
                switches.append(c)
                if eps > 0:
                    f = el.elastic_force(eps * _softplus(c / eps)) + _sigmoid(c / eps) * el.damping * cd
                else:
                    f = ca.if_else(c >= 0, el.elastic_force(c) + el.damping * cd, 0)
            forces.append(f)
            force_on[a_] -= f
            force_on[b_] += f
        masses = scene.model.bodies
        # a host's equation carries its riders (Lagrange): (m + sum I g'^2) x'' = F + sum g' F_r - sum I g' g'' x'^2
        generalised = {b: force_on[b] for b in free}
        inertia = {b: masses[b].mass for b in free}
        for r, (host, g1, g2) in carried.items():
            generalised[host] += g1 * force_on[r] - masses[r].mass * g1 * g2 * vel[host] ** 2
            inertia[host] += masses[r].mass * g1**2
        acc = ca.vertcat(*[generalised[b] / inertia[b] for b in free]) if n else ca.SX(0, 1)
        drive = masses[scene.driven].mass * ad - force_on[scene.driven]
        rider_out = []
        for r, (host, g1, g2) in carried.items():
            i = free.index(host)
            rider_out += [pos[r], vel[r], g1 * acc[i] + g2 * vel[host] ** 2]
        ode = ca.vertcat(dur * 1e3 * z[n:], dur * acc)
        self.dae = {"x": z, "p": p, "t": sigma, "ode": ode}
        # the same ODE over a sub-interval [sigma_a, sigma_b] of a piece, in its own time theta in [0, 1]
        theta, pr = ca.SX.sym("theta"), ca.SX.sym("pr", 5)
        sig_ab = pr[3] + theta * (pr[4] - pr[3])
        ode_sub = ca.substitute([(pr[4] - pr[3]) * ode], [sigma, p], [sig_ab, pr[:3]])[0]
        self.refine_dae = {"x": z, "p": pr, "t": theta, "ode": ode_sub}
        self.outputs = ca.Function(
            "scene_outputs", [sigma, z, p],
            [t0 + tau, xd, vd, ad, acc, ca.vertcat(*forces) if forces else ca.SX(0, 1), drive,
             ca.vertcat(*rider_out) if rider_out else ca.SX(0, 1)],
            ["sigma", "z", "p"], ["t", "x_d", "v_d", "a_d", "acc", "forces", "drive", "riders"])
        self.rhs = ca.Function("scene_rhs", [sigma, z, p], [ode], ["sigma", "z", "p"], ["ode"])
        # the element forces and the drive force in one column (peaks.py locates their peaks)
        self.forces = ca.Function("scene_forces", [sigma, z, p], [ca.vertcat(*forces, drive)], ["sigma", "z", "p"],
                                  ["forces"])
        # the switching functions (an element acts while its value is >= 0), one per element
        sw = ca.vertcat(*switches) if switches else ca.SX(0, 1)
        self.switches = ca.Function("scene_switches", [sigma, z, p], [sw], ["sigma", "z", "p"], ["sw"])
        # and their rates in time (1/s times their unit): how fast an element nears acting (peaks.py)
        rate = (ca.jtimes(sw, z, ode) + ca.jacobian(sw, sigma)) / dur if switches else ca.SX(0, 1)
        self.switch_rates = ca.Function("scene_switch_rates", [sigma, z, p], [sw, rate], ["sigma", "z", "p"],
                                        ["sw", "rate"])

    @property
    def state_size(self) -> int:
        return int(self.dae["x"].numel())
