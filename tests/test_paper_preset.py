"""The `paper` preset keeps the paper's model exactly: results pinned to cmpsim 0.1.0.

The reference numbers in ``tests/data/paper_preset_reference.json`` were computed by cmpsim
0.1.0 (commit d1cfb40), the faithful implementation of the paper, before any physics beyond
the paper was added. Whatever the default model becomes, ``Config.paper()`` must reproduce
them to 1e-7 relative, so that ``cmpsim reproduce`` and every study of the paper's figures do
not move.

Why 1e-7 and not the Newton tolerance 1e-9: 0.1.0's numbers are themselves only as close to
the root as its Newton iteration stopped. For the elastic 6 psi / 30 rpm case its attack
angle (2.4e-6 rad, the smallest of the set) lies 2.2e-8 relative from the root, measured by
solving the case to a residual of 1e-13, and its fluid load fraction (8e-4) 1.1e-8; this
version's Newton path (issue 15: a coarse first step, one step less) lands 1.4e-10 from the
root. Until issue 15 both versions took the same path and agreed to 1e-10, and this test
pinned 1e-8. ``test_the_paper_preset_is_converged_to_its_root`` pins this version's own
distance from the root (1e-9); issue 15 asks 1e-6 of the speed work.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import cmpsim
from cmpsim.inputs.config import Config

REFERENCE = json.loads((Path(__file__).parent / "data" / "paper_preset_reference.json").read_text())
#: Solver diagnostics: residuals are round-off sized and not results.
DIAGNOSTICS = {"load_residual", "moment_residual"}
#: Relative agreement with 0.1.0 (see the module docstring).
RTOL = 1e-7


def schema1(result) -> dict:
    """The 0.1 (schema 1) scalar names of a result, whatever the current JSON layout is."""
    to_schema1 = getattr(result, "to_schema1", None)
    return to_schema1() if to_schema1 is not None else result.to_dict()


@pytest.mark.parametrize("case", sorted(REFERENCE["cases"]))
def test_paper_preset_reproduces_cmpsim_0_1_results_to_1e_7(case):
    ref = REFERENCE["cases"][case]
    got = schema1(cmpsim.solve(Config.paper().replace(**ref["settings"])))
    angle_scale = abs(ref["scalars"]["attack_angle_rad"])
    for name, want in ref["scalars"].items():
        if name in DIAGNOSTICS:
            continue
        # the cross tilt is ~1e-3 of the attack angle: compare it on the attack angle's scale
        atol = RTOL * angle_scale if name == "cross_tilt_rad" else 0.0
        assert got[name] == pytest.approx(want, rel=RTOL, abs=atol), name


@pytest.mark.parametrize("case", ["base_lep", "elastic_6psi_30rpm"])
def test_the_paper_preset_is_converged_to_its_root(case):
    # the position at the default tolerance against the same problem solved to a residual of
    # 1e-13: what the Newton tolerance leaves of the root, on every output
    cfg = Config.paper().replace(**REFERENCE["cases"][case]["settings"])
    got = schema1(cmpsim.solve(cfg, relative=False))
    exact = schema1(cmpsim.solve(cfg.replace(tolerance=1e-13), relative=False))
    angle_scale = abs(exact["attack_angle_rad"])
    for name, want in exact.items():
        if name in DIAGNOSTICS or not isinstance(want, float):
            continue
        atol = 1e-9 * angle_scale if name == "cross_tilt_rad" else 0.0
        assert got[name] == pytest.approx(want, rel=1e-9, abs=atol), name
