"""Test settings shared by every test module."""

import tempfile
from pathlib import Path

from hypothesis import settings
from hypothesis.configuration import set_hypothesis_home_dir

# Hypothesis writes nothing into the checkout: no example database (every run draws its
# examples afresh; a failure prints the example that reproduces it), and its other caches
# (e.g. the constants of the code under test) go to the temporary directory.
set_hypothesis_home_dir(Path(tempfile.gettempdir()) / "cmpsim-hypothesis")
settings.register_profile("cmpsim", database=None)
settings.load_profile("cmpsim")
