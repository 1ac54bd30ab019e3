"""The ground floor: what every package uses and nothing of the domain.

* fields.py  checked, typed access to TOML tables (``Fields``), ranges with reasons, ``--set`` overrides
* plain.py   numbers as they leave strokeopt: JSON (NaN refused) and the one number format

Reading and writing files (problem files, design files, cam tables) is :mod:`strokeopt.files`, a floor
above the domain.
"""
