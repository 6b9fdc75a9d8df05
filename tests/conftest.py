"""Test settings shared by every test module."""

import os
import tempfile
from pathlib import Path

from hypothesis import settings
from hypothesis.configuration import set_hypothesis_home_dir

# Hypothesis writes nothing into the checkout: no example database (every run draws its
# examples afresh; a failure prints the example that reproduces it), and its other caches
# (e.g. the constants of the code under test) go to the temporary directory. On CI (CI set, as
# .ci/run exports it) the examples are derandomized, so that a run is repeatable: a developer's runs
# draw afresh and find what CI's fixed draw does not (`pytest --hypothesis-seed=N` repeats one).
set_hypothesis_home_dir(Path(tempfile.gettempdir()) / "cmpsim-hypothesis")
settings.register_profile("cmpsim", database=None, derandomize=bool(os.environ.get("CI")))
settings.load_profile("cmpsim")
