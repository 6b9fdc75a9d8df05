"""Floor 7 (studies), the polisher over time (issue 32): a recipe of steps polished through time.

``recipe`` (the recipe TOML: the film stack, the steps, a target; frozen dataclasses and the
errors that name a step, a film and a line), ``stack`` (the film stack per radius of the wafer
and its removal, top film first, with carry-over into the next film within a time step),
``endpoint`` (what a tool sees: the reflectance at 650 nm of the stack, the detector that stops
an ``until = "endpoint"`` step, the friction torque on the platen) and ``engine`` (the time
integration: one wafer solve per distinct step inputs, every film's removal rate from it, the
pad's temperature from :mod:`cmpsim.physics.thermal` driven by the frictional power and setting
the Arrhenius chemical step; :func:`cmpsim.polisher.engine.polish`, ``cmpsim.polish``).
``report`` writes the JSON, CSV and plots of ``cmpsim polish --out DIR``.

May import: :mod:`cmpsim.solver` and every floor below it, its sibling studies on the same
floor, and the utilities.
"""
