"""Runnable experiments: ``python -m jaxlens.experiments.<name>``.

* ``classical``: ab initio curriculum design of the paper's six-element plastic aspheric
  lens (80.8° FoV, F/2.0, 7.66 mm sensor diagonal) and the Table 1 ablation.
* ``tolerance``: tolerance analysis of a classical design (``tolerance.json`` and the RMS
  histogram), also run by ``classical`` on its best design.
"""
