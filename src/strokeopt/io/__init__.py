"""Files in and out: every file strokeopt reads or writes, checked field by field.

* fields.py        checked, typed access to TOML tables (``Fields``) and ``--set`` overrides
* problem_file.py  a problem file -> :class:`~strokeopt.problem.Problem` (each package reads its section)
* ranges.py        ``--spm`` values and START:STOP:STEP ranges
* design_file.py   design.json and the cam table of a solved design, and reading them back
* plain.py         numbers as they leave strokeopt: JSON (NaN refused) and the one number format
"""
