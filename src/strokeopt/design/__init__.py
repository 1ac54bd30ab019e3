"""The optimal stroke, pulley and motor by direct collocation, on two floors and a top:

transcription/  what the design problem is, as one NLP: settings ([design], [design.contact]), the solve's
                request and drive setup, collocation, pins, the drive model, one builder per limit and per
                objective, free model parameters, the NLP builder (Built, Graph, the bounded NlpCache), the
                solver call
search/         how it is solved: refine (pinned points, lazy accuracy, mesh refinement), parts (the motors
                enumerated or Bonmin, tooth counts), diagnose (which limit fails: LimitError), fine_grid
solve           solve_design: one design (its request, its search, its checks and one judgement)
result          Design (immutable, with its resolved drive), MoveResult, move_results, stroke_from_solutions,
                design_from_data (a design.json read back)
torque          design_torque: the motor torque of a design on its own motor and pulley
compare         compare_with_laws

Studies of many designs and the verified pipeline: strokeopt.studies; files: strokeopt.files.design_file;
text and figures: strokeopt.report.design.
"""
