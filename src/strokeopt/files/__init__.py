"""Files in and out, a floor above the domain and the studies (it reads into and writes from their objects).

* problem_file.py  a problem file (with ``extends`` and ``--set``) -> :class:`~strokeopt.problem.Problem`
* design_file.py   design.json and the cam table of a solved design, and reading them back
                   (``read_design``, ``load_design``)
* ranges.py        ``--spm`` values, START:STOP:STEP ranges and the cam table's options
"""
