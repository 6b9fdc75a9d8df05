"""The lot's controller sees the wafers through metrology with errors (``metrology_noise``): the errors
are reproducible from the seed and kept in the checkpoint, the lot's records keep the true thicknesses,
and a bad sigma is refused by name (docs/polisher.md, "Metrology noise")."""

import json
from importlib import resources

import numpy as np
import pytest
from click.testing import CliRunner

from cmpsim.cli import main
from cmpsim.polisher.incoming import measurement_errors
from cmpsim.polisher.lot import run_lot

RECIPE_PATH = resources.files("cmpsim") / "data" / "recipe_oxide.toml"
RECIPE = RECIPE_PATH.read_text(encoding="utf-8")
LOT = dict(control="ewma", conditioning="none", overrides={"grid": "coarse"}, zone_feedback=False)


def test_the_errors_are_normal_reproducible_and_apart_from_the_incoming_draw():
    a_in, a_out = measurement_errors(400, 50, 2e-9, seed=5)
    b_in, _ = measurement_errors(400, 50, 2e-9, seed=5)
    assert a_in.shape == a_out.shape == (400, 50) and np.array_equal(a_in, b_in)
    assert np.std(a_in) == pytest.approx(2e-9, rel=0.03) and abs(np.mean(a_out)) < 1e-10
    assert abs(np.corrcoef(a_in.ravel(), a_out.ravel())[0, 1]) < 0.02
    for bad in (-1e-9, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="metrology_noise must be a standard deviation >= 0 m"):
            measurement_errors(2, 3, bad)


@pytest.fixture(scope="module")
def lots():
    return {"exact": run_lot(RECIPE, 3, seed=1, **LOT), "noisy": run_lot(RECIPE, 3, seed=1, metrology_noise=3e-9, **LOT)}


def test_the_controller_acts_on_what_it_measures_and_the_records_keep_the_truth(lots):
    exact, noisy = lots["exact"].wafers, lots["noisy"].wafers
    # the same seed, the same incoming wafers; and the records keep them as they are, not as measured
    assert [w.incoming_mean for w in exact] == [w.incoming_mean for w in noisy]
    assert all(a.polish_time != b.polish_time for a, b in zip(exact[1:], noisy[1:]))  # the measured rate steers the time
    target = lots["exact"].target
    assert max(abs(w.final_thickness_mean / target - 1) for w in exact[1:]) < 1e-3
    assert all(abs(w.final_thickness_mean / target - 1) < 0.02 for w in noisy)  # a 3 nm metrology, not a lost lot


class Stop(Exception):
    pass


def _stop_after_2(record):
    if record.index == 2:
        raise Stop


def test_a_noisy_lot_interrupted_resumes_bit_for_bit(lots, tmp_path):
    path = tmp_path / "lot.checkpoint.json"
    with pytest.raises(Stop):
        run_lot(RECIPE, 3, seed=1, metrology_noise=3e-9, checkpoint=path, after_wafer=_stop_after_2, **LOT)
    resumed = run_lot(RECIPE, 3, seed=1, metrology_noise=3e-9, checkpoint=path, resume=True, **LOT)
    assert [w.to_record() for w in resumed.wafers] == [w.to_record() for w in lots["noisy"].wafers]


def test_without_a_seed_the_errors_drawn_are_kept_in_the_checkpoint(tmp_path):
    """Without a seed each lot draws other errors; a resumed lot reads the checkpoint's, so two resumes of
    one checkpoint polish its last wafer alike."""
    import shutil

    path = tmp_path / "a" / "lot.checkpoint.json"
    path.parent.mkdir()
    with pytest.raises(Stop):
        run_lot(RECIPE, 3, checkpoint=path, after_wafer=_stop_after_2, metrology_noise=2e-9, **LOT)
    saved = json.loads(path.read_text())
    assert saved["inputs"]["metrology_noise"] == 2e-9 and np.shape(saved["setup"]["metrology"]["final"])[0] == 3
    copy = tmp_path / "b" / "lot.checkpoint.json"
    copy.parent.mkdir()
    shutil.copy(path, copy)
    one = run_lot(RECIPE, 3, checkpoint=path, resume=True, metrology_noise=2e-9, **LOT)
    two = run_lot(RECIPE, 3, checkpoint=copy, resume=True, metrology_noise=2e-9, **LOT)
    assert one.wafers[2].to_record() == two.wafers[2].to_record()


def test_the_command_line_refuses_a_bad_metrology_noise_by_name():
    for bad in ("-1 nm", "5 s", "abc"):
        res = CliRunner().invoke(main, ["lot", str(RECIPE_PATH), "--wafers", "2", "--control", "ewma", "--metrology-noise", bad])
        assert res.exit_code == 2 and "--metrology-noise" in res.output, res.output
    for bad in (-1e-9, True, float("nan")):
        with pytest.raises(ValueError, match="metrology_noise"):
            run_lot(RECIPE, 2, metrology_noise=bad, **LOT)
