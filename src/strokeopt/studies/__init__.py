"""Studies: answers made of many solves and simulations, above the design floor.

* verified.py  :func:`solve_verified`: a design, its full servo simulation, its contact verification per scene
               and one status -- the one pipeline every caller uses (CLI, report, studies, notebooks)
* sweeps.py    stitch-rate sweeps, the mesh study, the impact study
* tradeoff.py  what accuracy costs in stitch rate (classic law and optimal stroke)
"""
