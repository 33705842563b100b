"""Studies of the numerics: speed against accuracy (tradeoffs: points and metrics; tradeoffs_judged:
the judgement and the validation's verdicts), the stability map (stability): their points, metrics
and judgements, no YADE; ensembles and their statistics (ensemble); seed 003's judged points
(biaxial_judged); the seismic study's trends and their verdicts (liquefaction), its reconstruction,
its variants and their verdicts (reconstruction). The verdicts live here; postproc only draws and
writes them.

May import: engines.model, engines.compiled, engines.reference, packing, engines.seeds (never
engines.yade: tests/test_layers.py); the runs are engines.run.tradeoffs, engines.run.stability,
engines.run.biaxial_study and engines.run.reconstruction, the figures postproc.tradeoffs,
postproc.stability, postproc.biaxial_plots and postproc.liquefaction.
"""
