"""The motion: what the driven body does over one cycle.

* laws.py    the classic motion laws, each written once for floats and CasADi symbols; C_v, C_a, C_j computed
* stroke.py  ``StrokeFunction``: one representation of a stroke (classic law or optimised), numeric and symbolic
* timing.py  ``TimingDiagram``: dwells and moves on the cam circle, their times at a stitch rate
"""
