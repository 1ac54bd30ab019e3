"""Planar linkages as transmissions: data (model.py), structure (structure.py), closure and exact
kinematics (closure.py, kinematics.py), dynamics (dynamics.py), synthesis (synthesis.py) and the
linkage problem file (files.py).

    problem file [transmission] type = "linkage"
        -> Linkage            joints at a reference pose, links, crank, outputs, masses
        -> Structure          mobility, loops, Grashof four-bars, groups solved together
        -> Kinematics.solve   Newton continuation over the input, derivatives by AD
        -> dynamics           reduced inertia, power-balance torque, Newton-Euler reactions
        -> summary            what the command reports; synthesis.py fits a geometry to a table
"""

from .model import Crank, Joint, Link, Linkage, Load, Output
from .structure import Structure, analyse_structure
from .kinematics import Cycle, Kinematics, kinematics_of
from .files import LinkageProblem, load_linkage_file

__all__ = ["Crank", "Cycle", "Joint", "Kinematics", "Link", "Linkage", "LinkageProblem", "Load", "Output",
           "Structure", "analyse_structure", "kinematics_of", "load_linkage_file"]
