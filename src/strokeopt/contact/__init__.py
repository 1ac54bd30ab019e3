"""The contact model: a mechanism's bodies, springs and contacts as data, simulated over one cycle.

Modules in data-flow order:

* model.py     bodies, springs, contacts, grips and force laws, read from ``[model]``
* events.py    the event roles of ``[model.events]``, the metric names, event location and metrics
* scene.py     the part of a model one question needs, built into a CasADi ODE
* cluster.py   the bodies that ride on the driven body, and the contact forces that hold them (algebraic)
* options.py   how a scene is integrated (tolerances, output grid, step budget, peak location): ``SimulationOptions``
* simulate.py  one cycle with the driven body following a stroke (CVODES/IDAS): ``SceneResult``
* studies.py   speed sweeps and the integrators' work-precision study
* verify.py    a design's stroke re-simulated in a scene (``verify``)
* chain.py     a model on a transmission's members (an elastic chain) against the rigid chain
"""
