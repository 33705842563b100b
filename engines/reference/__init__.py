"""The independent reference: seed 000 written again, slowly and literally, from the paper
(model), and the recording contract both paths write (trajectory), for the cross-check
(yade_scripts/crosscheck.py).

May import: NumPy, SciPy. Nothing of the fast code (engines.model, engines.compiled), so that a
misreading cannot hide in both; never YADE.
"""
