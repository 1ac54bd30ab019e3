"""Search: solving the transcribed NLP and choosing the parts.

* refine.py     one solve with its pins, the lazy accuracy and the mesh refinement
* parts.py      the catalogue search: motors enumerated (or Bonmin), tooth counts next to the continuous optimum
* diagnose.py   which limit a failed solve cannot meet, and by how much (LimitError)
* fine_grid.py  the solution read on a fine grid between the collocation nodes
"""
