"""Floor 7 (studies), the polisher over time (issue 32): recipes of steps with an end point, the
pad's temperature and life carried through the steps and from wafer to wafer, and the run-to-run
control of a lot.

``recipe`` (the recipe TOML: the film stack, the steps, a target; frozen dataclasses and the
errors that name a step, a film and a line), ``stack`` (the film stack per radius of the wafer
and its removal, top film first, with carry-over into the next film within a time step),
``endpoint`` (what a tool sees: the reflectance at 650 nm of the stack, the detector that stops
an ``until = "endpoint"`` step, the friction torque on the platen), ``engine`` (the time
integration: one wafer solve per distinct step inputs, every film's removal rate from it, the
pad's temperature from :mod:`cmpsim.physics.thermal` driven by the frictional power and setting
the Arrhenius chemical step; :func:`cmpsim.polisher.engine.polish`, ``cmpsim.polish``),
``pad`` (the pad's life through a recipe's time steps: glazing, conditioning, the worn summits),
``report`` (the JSON, CSV and plots of ``cmpsim polish --out DIR``), ``control`` (the run-to-run
rate estimators: the double EWMA of the rate and its drift, the single EWMA), ``zones`` (the zone
feedback that takes only steps it predicts lower the non-uniformity), ``checkpoint`` (a lot's
state between wafers, for ``--resume``), ``incoming`` (a lot's incoming profiles) and ``ride`` (a layout riding
along, ``cmpsim polish --die``: the die model of :mod:`cmpsim.die` at a few wafer sites, driven step
by step by the blanket depth and the duration of each step).

Lives on the studies floor beside :mod:`cmpsim.head`. May import: :mod:`cmpsim.head`, the driver
(:mod:`cmpsim.solver`) and every floor below it, its sibling studies on the same floor (:mod:`cmpsim.die`
and :mod:`cmpsim.layout` for ``ride``; never the other way: the die model knows no recipe), and the utilities.
"""
