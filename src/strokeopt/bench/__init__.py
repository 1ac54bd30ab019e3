"""``strokeopt bench``: speed measurements, each beside a reference measured in the same run.

``registry`` holds the machinery (``@benchmark``, ``best_time``); one module per area registers
its benchmarks (``sizing``, ``design``, ``contact``, ``servo``, ``report``, ``solve_parts``: the reference solve as
a command, in parts); ``run`` imports them and runs them. The
domain packages never import this package.
"""
