"""Planar linkages as transmissions: a crank-driven linkage as data, solved exactly, its crank torque and
its dimensions fitted to a table. Modules in data-flow order:

* model.py      ``Linkage``: joints at a reference pose, links (masses), the crank, outputs, process loads
* structure.py  ``analyse_structure``: Gruebler mobility, loops, Grashof four-bars, groups solved together
* closure.py    loop closure as CasADi SX from the data; Newton steps; derivatives by AD (Taylor mode)
* kinematics.py ``Kinematics.solve``: Newton continuation over the input angle, branch kept, refusals
* dynamics.py   reduced inertia, power-balance crank torque, Newton-Euler joint reactions
* files.py      ``load_linkage_file`` -> ``LinkageProblem`` (``[transmission] type = "linkage"``)
* targets.py    the ``[synthesis]`` section and the fit of a solved linkage against it
* synthesis.py  ``synthesize``: dimensional synthesis in the simultaneous form (IPOPT)
* summary.py    ``summarize``: what ``strokeopt linkage`` reports
"""
