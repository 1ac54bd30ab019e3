"""strokeopt: design servo-driven reciprocating mechanisms ("electronic cams").

The data flow, one package per step (floors in docs/architecture.md; imports point down only)::

    problem file (TOML, extends, --set)
      files/      -> data              the file, its extends chain, the --set texts     files/problem_file.py
      problem.py  -> Problem           checked field by field, SI units; variants in memory (with_overrides)
      motion/     -> TimingDiagram, StrokeFunction   s, v, a, jerk as CasADi Functions: a law or a design
      drive/      -> torque, checks    transmission + motor + load; catalogue; the resolved drive (selection)
      contact/    -> SceneResult       the mechanism as data; a scene's CasADi ODE (CVODES)
      servo/      -> AccuracyResult    cascade loop and belt: the handover error and the design's error term
      linkage/    -> Linkage           planar linkages as data: structure, closure, kinematics, synthesis
      design/     -> Design            direct collocation (transcription/) and its search (search/)
      studies/    -> VerifiedDesign    solve_verified: the design, its servo simulation, its contact
                                       verification, one status and verdict; sweeps, impact, trade-off;
                                       the study runner (tasks on dask.distributed)
      files/      -> design.json, cam tables (and back)
      report/     -> text, JSON, figures, HTML (formats what it is given)

``cli`` parses, calls one library function and reports; ``bench`` measures. Notebooks and tests use the
public API exported here: ``solve_verified`` gives the same answer as ``strokeopt solve``.
"""

import os as _os

# One BLAS thread unless the environment says otherwise (set before numpy is first imported): strokeopt's
# matrices are small, and a second BLAS thread spent more CPU than it saved (a held-accuracy solve: 12.3 s
# CPU, 7.3 s wall with two threads; 7.0 s CPU, 7.1 s wall with one), and it took the core a study's second
# worker runs on. Dask's workers set the same.
for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    _os.environ.setdefault(_name, "1")

from .drive.catalogue import Belt, Catalogue, Pulley, ServoMotor, load_catalogue
from .drive.checks import Check, DriveLimits, drive_checks
from .drive.load import Load, LoadForce, load_torque
from .drive.sizing import optimal_radius, size_drive
from .drive.spec import DriveSpec
from .design.transcription.collocation import Mesh
from .design.transcription.objectives import OBJECTIVES
from .design.result import Design
from .design.transcription.settings import DesignSettings
from .design.compare import compare_with_laws
from .report.design import design_text
from .studies.sweeps import mesh_study, sweep_design
from .files.design_file import read_design
from .design.solve import solve_design
from .errors import ProblemError, SolverError, StrokeoptError
from .motion.laws import LAW_NAMES, Characteristics, MotionLaw, law_table, make_law
from .contact.model import Body, Element, ForceLaw, Model
from .problem import Problem
from .files.problem_file import load_problem
from .contact.scene import Scene, make_scene
from .servo.kernel import ServoErrorTerm
from .servo.accuracy import AccuracyResult, accuracy_report, handover_accuracy
from .servo.plant import DriveAxis, axis_from_problem
from .servo.settings import ServoSettings
from .studies.tradeoff import tradeoff
from .studies.verified import VerifiedDesign, solve_verified, verify_design
from .contact.simulate import SceneResult, SimulationOptions, simulate_scene
from .contact.studies import sweep_spm, tolerance_study
from .contact.verify import design_verification, verification, verify
from .contact.cluster import Cluster, build_cluster, softest_stiffness
from .studies.sweeps import impact_study
from .studies.runner import StudyRunner
from .motion.stroke import Kinematics, Piece, StrokeFunction
from .motion.timing import Interval, TimingDiagram
from .drive.crank_slider import CrankSlider
from .drive.screw_lever import ScrewLever
from .drive.transmission import BeltPulley, Gearbox, Transmission, gt3_pitch_diameter
from .transmissions import TRANSMISSIONS

__all__ = [
    "Body", "Element", "ForceLaw", "Model", "Scene", "SceneResult", "SimulationOptions", "make_scene",
    "simulate_scene", "sweep_spm", "tolerance_study", "verify",
    "LAW_NAMES", "BeltPulley", "Characteristics", "Interval", "Kinematics", "MotionLaw", "Piece", "Problem",
    "ProblemError", "SolverError", "StrokeFunction", "StrokeoptError", "TimingDiagram", "Transmission",
    "gt3_pitch_diameter", "law_table", "load_problem", "make_law",
    "Belt", "Catalogue", "Check", "DriveLimits", "DriveSpec", "Load", "LoadForce", "Pulley", "ScrewLever", "ServoMotor",
    "CrankSlider", "Gearbox", "TRANSMISSIONS", "drive_checks", "load_catalogue", "load_torque", "optimal_radius", "size_drive",
    "OBJECTIVES", "Design", "DesignSettings", "Mesh", "compare_with_laws", "design_text", "mesh_study", "read_design",
    "solve_design", "sweep_design",
    "AccuracyResult", "DriveAxis", "ServoErrorTerm", "ServoSettings", "accuracy_report", "axis_from_problem", "handover_accuracy",
    "tradeoff", "VerifiedDesign", "solve_verified", "verify_design", "StudyRunner",
    "Cluster", "build_cluster", "design_verification", "impact_study", "softest_stiffness", "verification",
]
__version__ = "0.1.0"
