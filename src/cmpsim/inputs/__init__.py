"""Floor 5, the inputs: the parameter registry with units, ranges and sources (one entry and its
range check), the unit parser, the configuration with its presets, and the inputs another input
sets (derived).

May import: :mod:`cmpsim.models` and every floor below it, and the utilities.
"""
