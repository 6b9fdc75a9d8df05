"""Floor 6, the results: the output registry (name, SI unit, meaning), the result of one
operating point with its tables and plots, and the within-wafer uniformity measures.

May import: :mod:`cmpsim.inputs` and every floor below it, and the utilities.
"""
