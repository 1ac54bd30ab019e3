"""The optimal stroke, pulley and motor by direct collocation; modules in data-flow order:

settings      ``[design]``: DesignSettings, parse_design (with ``[design.contact]``, ``[design.free]``)
contact_setup ``[design.contact]`` checked against ``[model]``; ContactDesign (the rigid cluster in stroke terms)
request       SolveRequest (what one solve needs), Move, DriveSetup, DriveChoice, the ErrorTerm protocol
collocation   the collocated move in unit form (Mesh, MoveVariables, MoveSolution, move_piece)
nlp           the builder (Built), the built structure (Graph), the bounded NlpCache, one solve's Nlp
free          ``[design.free]``: model stiffnesses as NLP variables, the drive's load with them
drive_model   pulley radius, motor, torque and belt force in the NLP
pins          pinned points where a load force switches on
limits        one builder per limit (jerk, peak torque, speed, RMS, belt, inertia ratio, handover accuracy)
contact_limits  the contact model's limits: keep_closed contact forces, impact velocity (a pinned point)
objectives    one builder per objective (REGISTRY, OBJECTIVES)
solver        nlpsol plumbing and options
fine_grid     the solution read between the collocation nodes
diagnose      why a solve is infeasible (relaxed NLP)
refine        solve_one: pinned points, lazy accuracy, mesh refinement
parts         motor and pulley search
solve         solve_design
result        Design, MoveResult, stroke_from_solutions, design_from_data (a design.json read back)
torque        design_torque: the motor torque of a design on its own motor and pulley
compare       compare_with_laws
studies       sweep_design, fastest_feasible, mesh_study, impact_study

Files: strokeopt.files.design_file; text and figures: strokeopt.report.design.
"""
