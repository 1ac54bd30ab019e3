"""``strokeopt bench``: speed measurements, each beside a reference measured in the same run.

``registry`` holds the machinery (``@benchmark``, ``best_time``); one module per area registers
its benchmarks (``sizing``, ``design``, ``contact``, ``servo``, ``report``); ``run`` imports them and runs them. The
domain packages never import this package.
"""
