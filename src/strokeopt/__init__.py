"""strokeopt: design servo-driven reciprocating mechanisms ("electronic cams").

The data flow::

    problem file (TOML)
        -> Problem            validated, typed, SI units           problem.py
        -> TimingDiagram      dwells and moves on the cam circle   timing.py
        -> StrokeFunction     s, v, a, jerk as CasADi Functions:   laws.py, stroke.py
                              a classic law or a collocation
                              solution
        -> Drive              transmission + motor + load: torque, transmission.py,
                              speed, checks; catalogue sizing      actuators.py, drive.py
        -> Design             direct collocation of every move:   design.py,
                              optimal stroke, pulley and motor,    collocation.py
                              constraint report, design.json
        -> Scene simulation   contact model as data; a scene's     model.py, scene.py,
                              CasADi ODE, CVODES over one cycle:   simulate.py
                              impact, lag, gap N, needle release
        -> Servo loop         cascade position/speed loop, belt    servo.py
                              as a spring (python-control):
                              handover error and its causes; the
                              design's servo accuracy term; the
                              accuracy / stitch-rate trade-off
        -> Report             tables, JSON, plots                  report.py, plots.py

``cli.py`` ties these together; notebooks and tests use the same public API
exported here.
"""

from .drive.catalogue import Belt, Catalogue, Pulley, ServoMotor, load_catalogue
from .drive.checks import Check, DriveLimits, drive_checks
from .drive.load import Load, LoadForce, load_torque
from .drive.sizing import optimal_radius, size_drive
from .drive.spec import DriveSpec
from .design.collocation import Mesh
from .design.objectives import OBJECTIVES
from .design.result import Design
from .design.settings import DesignSettings
from .design.compare import compare_with_laws
from .report.design import design_text
from .design.studies import mesh_study, sweep_design
from .io.design_file import read_design
from .design.solve import solve_design
from .errors import ProblemError, SolverError, StrokeoptError
from .motion.laws import LAW_NAMES, Characteristics, MotionLaw, law_table, make_law
from .contact.model import Body, Element, ForceLaw, Model
from .problem import Problem
from .io.problem_file import load_problem
from .contact.scene import Scene, make_scene
from .servo.kernel import ServoErrorTerm  # noqa: F401  (the design's handover error term of a [servo] problem)
from .servo.accuracy import AccuracyResult, accuracy_report, handover_accuracy
from .servo.plant import DriveAxis, axis_from_problem
from .servo.settings import ServoSettings
from .servo.tradeoff import tradeoff
from .contact.simulate import SceneResult, SimulationOptions, simulate_scene
from .contact.studies import sweep_spm, tolerance_study
from .motion.stroke import Kinematics, Piece, StrokeFunction
from .motion.timing import Interval, TimingDiagram
from .drive.transmission import BeltPulley, ScrewLever, SliderCrank, Transmission, gt3_pitch_diameter

__all__ = [
    "Body", "Element", "ForceLaw", "Model", "Scene", "SceneResult", "SimulationOptions", "make_scene",
    "simulate_scene", "sweep_spm", "tolerance_study",
    "LAW_NAMES", "BeltPulley", "Characteristics", "Interval", "Kinematics", "MotionLaw", "Piece", "Problem",
    "ProblemError", "SolverError", "StrokeFunction", "StrokeoptError", "TimingDiagram", "Transmission",
    "gt3_pitch_diameter", "law_table", "load_problem", "make_law",
    "Belt", "Catalogue", "Check", "DriveLimits", "DriveSpec", "Load", "LoadForce", "Pulley", "ScrewLever", "ServoMotor",
    "SliderCrank", "drive_checks", "load_catalogue", "load_torque", "optimal_radius", "size_drive",
    "OBJECTIVES", "Design", "DesignSettings", "Mesh", "compare_with_laws", "design_text", "mesh_study", "read_design",
    "solve_design", "sweep_design",
    "AccuracyResult", "DriveAxis", "ServoSettings", "accuracy_report", "axis_from_problem", "handover_accuracy",
    "tradeoff",
]
__version__ = "0.1.0"
