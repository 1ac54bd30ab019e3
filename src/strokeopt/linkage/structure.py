"""Structure of a linkage from its data: Gruebler mobility, independent loops, the Grashof class of each
four-bar sub-loop, the closure equations and the groups that must be solved simultaneously.

The closure equations are written per link, never per mechanism: a link's joints are ordered known
first (ground, then crank joints), its first two joints are held at their reference distance and
every further joint is *placed* in the frame of the first two (a ternary link stays rigid and keeps
its orientation: no mirror image). The unknowns are the coordinates of every joint that is neither
on the ground nor on the crank. A group is a diagonal block of the block-triangular form of the
equations' sparsity (Dulmage-Mendelsohn): a dyad (2 links, 3 joints) is solvable by a circle
intersection; a triad (the loom's 4 links, 6 joints) is not, and is solved as one system.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import casadi as ca

from ..errors import ProblemError
from .model import Linkage


@dataclass(frozen=True)
class Equation:
    """``distance``: |p_a - p_b| = reference (one row); ``place``: p_c in the frame of (a, b) (two rows)."""

    kind: str
    link: str
    a: str
    b: str
    c: str | None = None

    @property
    def rows(self) -> int:
        return 1 if self.kind == "distance" else 2


@dataclass(frozen=True)
class Group:
    """Joints solved together and the links whose equations tie them; ``kind`` dyad, triad, placement
    (a point of a link already placed) or ``n-link group``."""

    kind: str
    joints: tuple[str, ...]           # unknown joints of the group
    links: tuple[str, ...]
    attached: tuple[str, ...]         # known joints the group hangs on
    rows: tuple[int, ...]             # equation rows (into the closure vector)
    cols: tuple[int, ...]             # unknown coordinates

    def to_dict(self) -> dict:
        return {"kind": self.kind, "links": list(self.links), "joints": list(self.joints),
                "attached_to": list(self.attached), "equations": len(self.rows)}


@dataclass(frozen=True)
class FourBar:
    links: tuple[str, ...]            # in loop order; "ground" for the frame
    joints: tuple[str, ...]
    lengths: tuple[float, ...]        # [m], link i between joints i-1 and i of the loop
    grashof: str                      # "Grashof", "change point" or "non-Grashof"
    kind: str                         # relative to the reference link (ground, else the crank)
    reference: str

    @property
    def change_point_distance(self) -> float:
        """``|s + l - (p + q)|`` [m]: how far the lengths are from a change point, where the loop can fold onto a
        line and pass into its other branch (a tolerance of this size on any link changes its Grashof class)."""
        s, l = min(self.lengths), max(self.lengths)
        return abs(2 * (s + l) - sum(self.lengths))

    @property
    def near_change_point(self) -> bool:
        """Within :data:`CHANGE_POINT_WARN` of the longest link from a change point (and not one)."""
        return self.grashof != "change point" and self.change_point_distance < CHANGE_POINT_WARN * max(self.lengths)

    def to_dict(self) -> dict:
        return {"links": list(self.links), "joints": list(self.joints),
                "lengths_mm": [round(v * 1e3, 4) for v in self.lengths], "grashof": self.grashof,
                "class": self.kind, "relative_to": self.reference,
                "change_point_distance_mm": self.change_point_distance * 1e3, "near_change_point": self.near_change_point}


#: A four-bar within this share of its longest link from a change point is warned of (branch or toggle risk): 1 %,
#: a few tenths of a millimetre on a machine's links, the size of a link's manufacturing and wear tolerances.
CHANGE_POINT_WARN = 0.01


@dataclass(frozen=True)
class Structure:
    mobility: int
    n_links: int                      # with the ground
    n_revolute: int
    n_loops: int
    known: tuple[str, ...]            # ground and crank joints
    unknown: tuple[str, ...]          # joints solved for (two coordinates each, in this order)
    equations: tuple[Equation, ...]
    groups: tuple[Group, ...]
    four_bars: tuple[FourBar, ...]
    tracers: tuple[str, ...]          # joints of one moving link only

    def to_dict(self) -> dict:
        return {"mobility": self.mobility, "links": self.n_links, "revolute_joints": self.n_revolute,
                "independent_loops": self.n_loops, "groups": [g.to_dict() for g in self.groups],
                "four_bar_loops": [f.to_dict() for f in self.four_bars], "tracer_points": list(self.tracers)}


def _bodies(linkage: Linkage) -> dict[str, tuple[str, ...]]:
    """Every body (the links and the ground) with its joints."""
    bodies = {"ground": tuple(j.name for j in linkage.joints if j.ground)}
    bodies.update({link.name: link.joints for link in linkage.links})
    return bodies


def count_mobility(linkage: Linkage) -> tuple[int, int, int]:
    """Gruebler: M = 3 (n - 1) - 2 r with n bodies (ground included) and r revolute pairs; loops r - n + 1."""
    bodies = _bodies(linkage)
    revolute = 0
    for joint in linkage.joints:
        count = sum(joint.name in js for js in bodies.values())
        revolute += max(count - 1, 0)
    n = len(bodies)
    return 3 * (n - 1) - 2 * revolute, revolute, revolute - n + 1


def analyse_structure(linkage: Linkage) -> Structure:
    """The structure of ``linkage``, or a ProblemError naming what is wrong (mobility first)."""
    file = linkage.file
    mobility, revolute, loops = count_mobility(linkage)
    if mobility != 1:
        raise ProblemError(file, linkage.field_of("structure", "links"),
                           f"the linkage has mobility {mobility} (Gruebler: 3 x ({len(linkage.links) + 1} - 1) - "
                           f"2 x {revolute} revolute pairs); one driven crank needs mobility 1")
    crank = linkage.link(linkage.crank.link)
    known = [j.name for j in linkage.joints if j.ground]
    known += [name for name in crank.joints if name not in known]
    used = {name for link in linkage.links for name in link.joints}
    for joint in linkage.joints:
        if joint.name not in used and not joint.ground:
            raise ProblemError(file, linkage.field_of(f"joint:{joint.name}", "joints"),
                               f"joint {joint.name} belongs to no link")
    unknown = tuple(j.name for j in linkage.joints if j.name not in known and j.name in used)
    equations = _equations(linkage, known)
    rows = sum(e.rows for e in equations)
    if rows != 2 * len(unknown):  # mobility 1 with a crank should give a square system
        raise ProblemError(file, linkage.field_of("structure", "links"),
                           f"{rows} closure equations for {2 * len(unknown)} unknown coordinates: the links "
                           "do not determine every joint from the crank")
    tracers = tuple(j for j in unknown if sum(j in link.joints for link in linkage.links) == 1)
    groups = _groups(linkage, equations, unknown, known)
    return Structure(mobility, len(linkage.links) + 1, revolute, loops, tuple(known), unknown, tuple(equations),
                     groups, _four_bars(linkage), tracers)


def _equations(linkage: Linkage, known: list[str]) -> list[Equation]:
    out = []
    for link in linkage.links:
        if link.name == linkage.crank.link:
            continue
        ordered = sorted(link.joints, key=lambda n: (0, known.index(n)) if n in known else (1, link.joints.index(n)))
        a, b = ordered[0], ordered[1]
        if b in known:
            raise ProblemError(linkage.file, linkage.field_of(f"link:{link.name}", "links"),
                               f"link {link.name} joins {a} and {b}, which are both ground or crank joints: "
                               "it cannot move (make it part of the ground or of the crank)")
        out.append(Equation("distance", link.name, a, b))
        out += [Equation("place", link.name, a, b, c) for c in ordered[2:]]
    return out


def _groups(linkage: Linkage, equations: list[Equation], unknown: tuple[str, ...],
            known: list[str]) -> tuple[Group, ...]:
    col = {name: i for i, name in enumerate(unknown)}
    rows, cols, row_eq = [], [], []
    r = 0
    for eq in equations:
        names = [n for n in (eq.a, eq.b, eq.c) if n is not None and n in col]
        for k in range(eq.rows):
            for n in names:
                rows += [r, r]
                cols += [2 * col[n], 2 * col[n] + 1]
            row_eq.append(eq)
            r += 1
    sp = ca.Sparsity.triplet(r, 2 * len(unknown), rows, cols)
    _, rowperm, colperm, rowblock, colblock, *_ = sp.btf()
    groups = []
    for b in range(len(rowblock) - 1):
        brows = tuple(rowperm[rowblock[b]:rowblock[b + 1]])
        bcols = tuple(colperm[colblock[b]:colblock[b + 1]])
        joints = tuple(dict.fromkeys(unknown[c // 2] for c in sorted(bcols)))
        eqs = list(dict.fromkeys(row_eq[i] for i in brows))
        links = tuple(dict.fromkeys(e.link for e in eqs))
        attached = tuple(dict.fromkeys(n for e in eqs for n in (e.a, e.b, e.c) if n is not None and n not in joints))
        if all(e.kind == "place" for e in eqs):
            kind = "placement"
        else:
            kind = {2: "dyad", 4: "triad"}.get(len(links), f"{len(links)}-link group")
        groups.append(Group(kind, joints, links, attached, tuple(sorted(brows)), tuple(sorted(bcols))))
    return tuple(groups)


def _four_bars(linkage: Linkage) -> tuple[FourBar, ...]:
    """Every loop of four bodies joined by four distinct revolutes, classified by Grashof."""
    bodies = _bodies(linkage)
    names = list(bodies)
    shared = {}
    for a, b in itertools.combinations(names, 2):
        common = [j for j in bodies[a] if j in bodies[b]]
        if common:
            shared[(a, b)] = shared[(b, a)] = common
    found, seen = [], set()
    for cycle in itertools.permutations(names, 4):
        key = frozenset(cycle)
        if cycle[0] != min(cycle) or key in seen:
            continue
        pairs = [(cycle[i], cycle[(i + 1) % 4]) for i in range(4)]
        if not all(p in shared for p in pairs):
            continue
        for joints in itertools.product(*(shared[p] for p in pairs)):
            if len(set(joints)) == 4:
                seen.add(key)
                found.append(_classify(linkage, cycle, joints))
                break
    return tuple(found)


def _classify(linkage: Linkage, cycle, joints) -> FourBar:
    # body cycle[i] lies between joints[i-1] and joints[i]
    lengths = tuple(linkage.length(joints[i - 1], joints[i]) for i in range(4))
    ref_name = "ground" if "ground" in cycle else (linkage.crank.link if linkage.crank.link in cycle else cycle[0])
    ref = cycle.index(ref_name)
    s = min(range(4), key=lambda i: lengths[i])
    longest = max(lengths)
    rest = sum(lengths) - lengths[s] - longest
    total = lengths[s] + longest
    tol = 1e-9 * sum(lengths)
    grashof = "change point" if abs(total - rest) <= tol else ("Grashof" if total < rest else "non-Grashof")
    if grashof == "non-Grashof":
        kind = "triple rocker (no link turns fully)"
    elif s == ref:
        kind = "double crank"
    elif (s - ref) % 4 == 2:
        kind = "double rocker"
    else:
        kind = f"crank-rocker class ({cycle[s]}, the shortest, could turn fully)"
    return FourBar(tuple(cycle), tuple(joints), lengths, grashof, kind, ref_name)
