"""Transcription: the design problem stated as one NLP (what the problem is, apart from how it is searched).

* settings.py, contact_setup.py  the [design] section and its [design.contact] part
* request.py                     one solve's request: the problem at a rate, the drive setup, the moves
* collocation.py                 the moves' collocation polynomials (states, defects, evaluation)
* pins.py                        pinned points between nodes (where a torque or a contact force peaks)
* drive_model.py, limits.py, contact_limits.py   the drive's load model and one builder per limit
* objectives.py, free.py         the objectives and the free model parameters
* nlp.py                         the builder (Built), the built structure (Graph) and its bounded cache
* solver.py                      IPOPT/Bonmin through CasADi: options and one call
"""
