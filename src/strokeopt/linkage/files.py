"""The linkage problem file: ``[transmission] type = "linkage"`` with ``[machine]``, the joints at a
reference pose, the links with their masses, the crank, the outputs, process loads and the
synthesis targets. Every field is read through :class:`~strokeopt.io.fields.Fields` (ranges, unknown
keys refused); every geometric refusal names the file, the field and, where it has one, the angle.

Read with :func:`load_linkage_file`; the result is a :class:`LinkageProblem`.
"""

from __future__ import annotations

import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import ProblemError
from ..io.fields import Fields, apply_overrides
from .model import Crank, Joint, Link, Linkage, Load, Output

KGF_CM_S2 = 9.80665 * 0.01    # kg m^2 per kgf cm s^2 (1 kgf = 9.80665 N, 1 cm = 0.01 m)
KINDS = ("angle", "arc", "x", "y")
#: The least distance of two joints of one link [m]: closer, the link has no direction (a crank of length zero).
JOINTS_APART_M = 1e-6


@dataclass
class LinkageProblem:
    """A linkage with the machine's speed and the file's limits and targets (SI)."""

    file: str
    name: str
    description: str
    linkage: Linkage
    rpm: float                      # crank speed [1/min]
    min_transmission_index: float   # limit of the transmission index (sin of Alt's angle for a dyad)
    near_dwell_pct: float           # near dwell: output within this share of the swing of an extreme
    angles: int                     # samples per turn
    synthesis: dict = field(default_factory=dict)   # [synthesis] as read (synthesis.py checks it)

    @property
    def omega(self) -> float:
        """Crank speed [rad/s]."""
        return self.rpm * 2 * math.pi / 60


def load_linkage_file(path, overrides: list[str] | None = None, check_cycle: bool = True) -> LinkageProblem:
    """Read and validate a linkage problem file; with ``check_cycle`` also solve its cycle once, so a
    geometry that cannot close or passes a dead centre is refused here (naming the angle)."""
    file = str(path)
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ProblemError(file, "", "no such file") from None
    except tomllib.TOMLDecodeError as exc:
        raise ProblemError(file, "", f"not valid TOML: {exc}") from None
    overridden = apply_overrides(data, list(overrides or []), file)
    kind = data.get("transmission", {}).get("type") if isinstance(data.get("transmission"), dict) else None
    if kind != "linkage":  # a problem of another machine: say so before asking for a linkage's fields
        raise ProblemError(file, "transmission.type", f"is {kind or 'belt_pulley (the default)'!s}: strokeopt linkage "
                                                      "reads a linkage problem file ([transmission] type = \"linkage\", "
                                                      "e.g. problems/loom_beatup_sixbar.toml)")
    top = Fields(data, file, overridden=overridden)
    prob = top.table("problem")
    name = prob.string("name")
    description = prob.string("description", "")
    prob.finish()
    machine = top.table("machine")
    # the crank turns once a machine cycle: its rpm is the machine's rate (1-20000 /min, as any problem's spm)
    rpm = machine.number("spm", min=1, max=20000)
    machine.string("cycle", "stitch")   # what a cycle is called: the problem reader checks it
    machine.finish()
    tr = top.table("transmission")
    tr.string("type", choices=("linkage",))
    gravity = tr.number("gravity_m_s2", 0.0, min=0, max=20)   # 0: no gravity; 9.81 along -y
    linkage, limits = read_linkage(tr, file, name, gravity)
    tr.finish()
    synth = top.table("synthesis", required=False)
    synthesis = dict(synth.data) if synth is not None else {}   # checked below by targets.read_spec
    top.raw("drive", None)   # the motor and gearbox on the crank: the problem reader's ([drive], `strokeopt size`)
    top.finish()
    problem = LinkageProblem(file, name, description, linkage, rpm, *limits, synthesis)
    if synth is not None:   # checked now (names, ranges, misspelt keys), used by --synthesize
        from .targets import read_spec

        read_spec(problem, Fields(dict(synthesis), file, "synthesis", overridden))
    if check_cycle:
        from .kinematics import kinematics_of

        try:
            kinematics_of(linkage).solve(problem.angles)
        except ProblemError as exc:
            raise blame_the_set(exc, data, overridden) from None
    return problem


GEOMETRY_KEYS = ("x_mm", "y_mm", "reference_angle_deg")


def blame_the_set(exc: ProblemError, data: dict, overridden: frozenset) -> ProblemError:
    """A geometry refused by the kinematics after a --set of a joint's coordinate (or the reference angle):
    the error names the field the user set and the joint it moves, then the links and the angle where the
    chain fails; without such a --set, the error as the kinematics made it (the first link of the group)."""
    moved = sorted(f for f in overridden if f.rsplit(".", 1)[-1] in GEOMETRY_KEYS)
    if not moved:
        return exc
    names = []
    for f in moved:
        m = re.fullmatch(r"transmission\.joints\[(\d+)\]\.\w+", f)
        joints = data.get("transmission", {}).get("joints", [])
        if m and int(m.group(1)) <= len(joints) and isinstance(joints[int(m.group(1)) - 1], dict):
            names.append(f"joint {joints[int(m.group(1)) - 1].get('name')}")
        else:
            names.append("the reference pose")
    what = ", ".join(dict.fromkeys(names))
    return ProblemError(exc.file, ", ".join(moved), f"{what} as set by --set: {exc.message}")


def read_linkage(tr: Fields, file: str, name: str, gravity: float):
    """The :class:`Linkage` of a ``[transmission]`` table ``tr`` (joints, links, crank, outputs, loads) and its
    limits ``(min_transmission_index, near_dwell_pct, angles)``."""
    fields: dict[str, str] = {"structure": tr.where("links")}
    ref_deg = tr.number("reference_angle_deg", 0.0, min=-360, max=360)   # input angle at the reference pose
    index_min = tr.number("min_transmission_index", 0.0, min=0, max=1)   # sin(Alt's angle) of a dyad
    dwell = tr.number("near_dwell_pct", 5.0, min=0.1, max=50)   # loom: 5 % of the swing
    angles = tr.number("angles", 720, min=36, max=36000, integer=True)    # samples per turn
    joints: list[Joint] = []
    for jf in tr.tables("joints"):
        jname = jf.string("name")
        if any(j.name == jname for j in joints):
            raise jf.error("name", f"joint {jname!r} is named twice")
        x = jf.number("x_mm", min=-1e5, max=1e5) / 1e3   # a machine is smaller than 100 m
        y = jf.number("y_mm", min=-1e5, max=1e5) / 1e3
        joints.append(Joint(jname, x, y, jf.boolean("ground", False)))
        fields[f"joint:{jname}"] = jf.path
        jf.finish()
    names = [j.name for j in joints]
    links = [_read_link(lf, names, joints, fields) for lf in tr.tables("links")]
    seen = set()
    for link in links:
        if link.name in seen:
            raise ProblemError(file, fields[f"link:{link.name}"], f"link {link.name!r} is named twice")
        seen.add(link.name)
    crank = _read_crank(tr.table("crank"), links, joints, math.radians(ref_deg), fields)
    outputs = tuple(_read_output(of, names, links) for of in tr.tables("outputs", required=False))
    for k, out in enumerate(outputs):
        if any(o.name == out.name for o in outputs[:k]):
            raise ProblemError(file, tr.where(f"outputs[{k + 1}].name"), f"output {out.name!r} is named twice")
    loads = tuple(_read_load(lf, names, links) for lf in tr.tables("loads", required=False))
    linkage = Linkage(tuple(joints), tuple(links), crank, outputs, loads, gravity, file, name, fields)
    from .structure import analyse_structure

    analyse_structure(linkage)   # mobility, links fixed by two known joints, square closure
    return linkage, (index_min, dwell, angles)


def _joint_names(f: Fields, key: str, names: list[str], count: int | None = None) -> list[str]:
    value = f.raw(key)
    value = [value] if isinstance(value, str) and count == 1 else value
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise f.error(key, f"must be {'a joint name' if count == 1 else 'an array of joint names'}")
    for v in value:
        if v not in names:
            raise f.error(key, f"names the unknown joint {v!r}; joints: {', '.join(names)}")
    if len(set(value)) != len(value):
        raise f.error(key, "names a joint twice")
    return value


def _read_link(lf: Fields, names: list[str], joints: list[Joint], fields: dict) -> Link:
    name = lf.string("name")
    fields[f"link:{name}"] = lf.path
    js = tuple(_joint_names(lf, "joints", names))
    at = {j.name: (j.x, j.y) for j in joints}
    for i, a in enumerate(js):   # a link's joints apart: a link of length zero has no direction, no pose
        for b in js[i + 1:]:
            if math.dist(at[a], at[b]) < JOINTS_APART_M:
                raise lf.error("joints", f"joints {a} and {b} of link {name} coincide ({math.dist(at[a], at[b]) * 1e3:.3g} "
                                         f"mm apart at the reference pose, less than {JOINTS_APART_M * 1e3:g} mm): move "
                                         "one of them")
    mass = lf.number("mass_kg", 0.0, min=0, max=1e4)              # 0: massless (kinetostatics of the rest)
    cg = lf.raw("cg_mm", None)
    line = lf.raw("cg_on_line", None)
    if line is not None:   # the centre of gravity at a distance from the first joint towards the second
        ends = _joint_names(lf, "cg_on_line", names)
        if len(ends) != 2:
            raise lf.error("cg_on_line", f"must name two joints (the line from the first towards the second), got "
                                         f"{len(ends)}")
        a, b = (next(j for j in joints if j.name == n) for n in ends)
        dist = lf.number("cg_distance_mm", min=0, max=1e5) / 1e3
        if cg is not None:
            raise lf.error("cg_on_line", "give the centre of gravity once (cg_mm or cg_on_line)")
        span = math.dist((a.x, a.y), (b.x, b.y))
        cg = [(a.x + dist * (b.x - a.x) / span) * 1e3, (a.y + dist * (b.y - a.y) / span) * 1e3]
    if cg is not None:
        if not (isinstance(cg, list) and len(cg) == 2 and all(isinstance(c, (int, float)) for c in cg)):
            raise lf.error("cg_mm", "must be [x, y] in mm (at the reference pose)")
        cg = (cg[0] / 1e3, cg[1] / 1e3)
    elif mass > 0:
        raise lf.error("cg_mm", "a link with mass needs its centre of gravity [x, y] at the reference pose")
    inertia = lf.number("inertia_kg_m2", None, min=0, max=1e4)
    in_kgf = lf.number("inertia_kgf_cm_s2", None, min=0, max=1e5)
    if inertia is not None and in_kgf is not None:
        raise lf.error("inertia_kgf_cm_s2", "give the moment of inertia once (inertia_kg_m2 or inertia_kgf_cm_s2)")
    inertia = in_kgf * KGF_CM_S2 if in_kgf is not None else (inertia or 0.0)
    about = lf.raw("inertia_about", None)
    if about is not None:   # the file's inertia is about a joint: to the centre of gravity by Steiner
        about = _joint_names(lf, "inertia_about", names, 1)[0]
        jt = next(j for j in joints if j.name == about)
        d2 = (jt.x - (cg or (jt.x, jt.y))[0]) ** 2 + (jt.y - (cg or (jt.x, jt.y))[1]) ** 2
        inertia -= mass * d2
        if inertia < -1e-12:
            raise lf.error("inertia_about", f"the inertia about {about} is below m d^2 = {mass * d2:.4g} kg m^2: "
                                            "the centre of gravity is too far from it")
        inertia = max(inertia, 0.0)
    lf.finish()
    return Link(name, js, mass, cg, inertia)


def _read_crank(cf: Fields, links: list[Link], joints: list[Joint], ref: float, fields: dict) -> Crank:
    lname = cf.string("link", choices=tuple(link.name for link in links))
    pivot = cf.string("pivot")
    link = next(link for link in links if link.name == lname)
    grounds = [j for j in link.joints if next(x for x in joints if x.name == j).ground]
    if pivot not in grounds:
        raise cf.error("pivot", f"must be the ground joint of link {lname} ({', '.join(grounds) or 'it has none'})")
    if len(grounds) != 1:
        raise cf.error("link", f"the crank {lname} must have exactly one ground joint, has {len(grounds)}")
    fields["crank"] = cf.path
    cf.finish()
    return Crank(lname, pivot, ref)


def _read_output(of: Fields, names: list[str], links: list[Link]) -> Output:
    name = of.string("name")
    kind = of.string("kind", choices=KINDS)
    joint = _joint_names(of, "joint", names, 1)[0]
    about = None
    if kind in ("angle", "arc"):
        about = _joint_names(of, "about", names, 1)[0]
        if not any(joint in link.joints and about in link.joints for link in links):
            raise of.error("about", f"{about} and {joint} are not on one link")
    sign = {"ccw": 1.0, "cw": -1.0}[of.string("positive", "ccw", choices=("ccw", "cw"))]
    of.finish()
    return Output(name, kind, joint, about, sign)


def _read_load(lf: Fields, names: list[str], links: list[Link]) -> Load:
    name = lf.string("name")
    lname = lf.string("link", choices=tuple(link.name for link in links))
    joint = _joint_names(lf, "joint", names, 1)[0]
    link = next(link for link in links if link.name == lname)
    if joint not in link.joints:
        raise lf.error("joint", f"{joint} is not a joint of link {lname}")
    start = lf.number("from_deg", min=-360, max=720)
    end = lf.number("to_deg", min=-360, max=720)
    if not 0 < end - start <= 360:
        raise lf.error("to_deg", f"the window {start:g} -> {end:g} deg must be 0 to 360 deg long")
    f0 = lf.number("force_start_N", min=-1e7, max=1e7)
    f1 = lf.number("force_end_N", min=-1e7, max=1e7)
    direction = lf.number("direction_deg", min=-360, max=360)   # from the link's line (first -> second joint)
    lf.finish()
    return Load(name, lname, joint, math.radians(start), math.radians(end), f0, f1, math.radians(direction))
