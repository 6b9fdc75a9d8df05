"""The house of cmpsim: nothing imports upwards (docs/developer.md, cmpsim.testing.house)."""

from pathlib import Path

from cmpsim.testing.house import FLOORS, UTILITIES, floor_of, import_cycles, imports_of, source_modules, violations

SRC = Path(__file__).resolve().parents[1] / "src" / "cmpsim"


def test_nothing_imports_upwards_and_kernels_import_nothing_of_cmpsim():
    assert violations(SRC) == []


def test_no_module_imports_the_package_root_or_its_version_upwards():
    """The version lives in cmpsim._version; only the faces may import the package entrance."""
    for name, path in source_modules(SRC).items():
        if floor_of(name) != len(FLOORS) - 1:
            assert not {i for i in imports_of(path, name) if i == "cmpsim" or i.startswith("cmpsim.__")}, name


def test_importing_any_module_runs_no_import_loop():
    assert import_cycles(SRC) == []


def test_the_solver_rooms_do_not_need_each_other():
    """compliance <-> equilibrium was a circle (one way at import, the other inside functions);
    no two rooms of cmpsim need each other now, not even inside a function (issue 22). Within a
    package, ``sweeps.executors`` looks ``sweeps._run_point`` up at call time on purpose."""
    from cmpsim.testing.house import room_of

    across = [c for c in import_cycles(SRC, top_level_only=False) if len({room_of(m) for m in c}) > 1]
    assert across == [], across


def test_units_and_config_do_not_need_each_other():
    """The parameter registry hands its entries to cmpsim.inputs.units; units never imports config,
    not even inside a function (issue 22: the config <-> units circle)."""
    cycles = import_cycles(SRC, top_level_only=False)
    assert not [c for c in cycles if {"cmpsim.inputs.units", "cmpsim.inputs.config"} & set(c)], cycles
    assert "cmpsim.inputs.config" not in imports_of(SRC / "inputs" / "units.py", "cmpsim.inputs.units")


def _package(tmp_path, modules: dict[str, str]):
    """A package ``cmpsim`` under ``tmp_path`` with the given {dotted module: source}: ``"inputs.config"``
    is the module ``config`` of the subpackage ``inputs`` (its ``__init__`` is made)."""
    root = tmp_path / "cmpsim"
    root.mkdir()
    for name, text in {"__init__": "", **modules}.items():
        *folders, leaf = name.split(".")
        where = root.joinpath(*folders)
        where.mkdir(parents=True, exist_ok=True)
        if folders and not (where / "__init__.py").exists():
            (where / "__init__.py").write_text("")
        (where / f"{leaf}.py").write_text(text)
    return root


def test_the_cycle_check_sees_imports_inside_functions(tmp_path):
    root = _package(tmp_path, {"inputs.config": "from . import units\n", "inputs.units": "def f():\n    from .config import PARAMETERS\n"})
    assert import_cycles(root) == []
    assert import_cycles(root, top_level_only=False) == [["cmpsim.inputs.config", "cmpsim.inputs.units", "cmpsim.inputs.config"]]


def test_every_room_of_the_table_exists_and_every_module_has_a_floor():
    modules = source_modules(SRC)
    rooms = {n.split(".")[1] if "." in n else n for n in modules}
    listed = {r for _, _, rs in FLOORS for r in rs}
    assert listed - {"web"} <= rooms, listed - rooms  # the web face may be absent from a checkout
    assert rooms <= listed | set(UTILITIES), rooms - listed - set(UTILITIES)


def test_the_rule_catches_an_upward_import(tmp_path):
    """A kernel importing the config, and the solver importing a study, are both reported."""
    root = _package(
        tmp_path,
        {
            "inputs.config": "",
            "head.tuning": "",
            "physics.contact": "from ..inputs.config import PARAMETERS\n",
            "solver.equilibrium": "def f():\n    from cmpsim.head.tuning import tune_zones\n",
            "numerics.grid": "from cmpsim.physics import contact\n",  # downwards: allowed
        },
    )
    found = violations(root)
    assert any(v.startswith("cmpsim.physics.contact is a kernel and imports cmpsim.inputs.config") for v in found), found
    assert any(v.startswith("cmpsim.solver.equilibrium imports cmpsim.head.tuning") for v in found), found
    assert not [v for v in found if v.startswith("cmpsim.numerics")], found


def test_no_module_outside_the_registry_tests_a_model_option_by_name():
    """Each model axis is a family of classes picked by name in cmpsim.models (and checked in
    cmpsim.inputs.config); the solver, the Reynolds assembly and the post-processing ask the objects.
    On b10a4ba this scan found 17 places (issue 22)."""
    from cmpsim.testing.house import option_name_comparisons

    assert option_name_comparisons(SRC) == []


def test_the_option_scan_catches_a_name_test(tmp_path):
    from cmpsim.testing.house import option_name_comparisons

    root = _package(
        tmp_path,
        {
            "inputs.config": "ok = cfg.cavitation == 'jfo'\n",  # config checks its inputs: allowed
            "solver.equilibrium": (
                "a = problem.cavitation == 'jfo'\n"
                "b = 'granular' != lub.slurry_model\n"
                "c = config.removal_law in ('paper', 'shear_power')\n"
                "d = carrier not in ['rigid']\n"
                "e = problem.variant == 'hydrodynamic'\n"  # not a model axis of the registry
                "f = problem.cavitation == other\n"  # not a string
            ),
        },
    )
    found = option_name_comparisons(root)
    assert [line.split(":")[1] for line in found] == ["1", "2", "3", "4"], found


def test_every_option_value_has_a_class_behind_its_protocol():
    """The registry covers exactly the values Config accepts, and each class implements its protocol."""
    from cmpsim import models
    from cmpsim.inputs.config import PARAMETERS, Config

    axes = {
        "pad_compliance": (models.PAD_MODELS, models.PadModel),
        "slurry_model": (models.SLURRY_MODELS, None),
        "cavitation": (models.CAVITATION_MODELS, models.CavitationModel),
        "removal_law": (models.REMOVAL_LAWS, None),
        "carrier": (models.CARRIERS, models.CarrierModel),
    }
    for option, (registry, protocol) in axes.items():
        assert set(registry) == set(PARAMETERS[option].choices), option
        for name, cls in registry.items():
            assert cls.name == name
    cfg = Config.default()
    for name in models.PAD_MODELS:
        assert isinstance(models.pad_model(cfg.replace(pad_compliance=name)), models.PadModel)
    for name in models.REMOVAL_LAWS:
        assert isinstance(models.removal_law(cfg.replace(removal_law=name)), models.RemovalLaw)
    for cav in models.CAVITATION_MODELS:
        assert isinstance(models.slurry_model("newtonian", cav, -1e4, 3e4), models.SlurryModel)
    assert isinstance(models.carrier("rigid"), models.CarrierModel)
    assert isinstance(models.carrier(cfg.replace(carrier="membrane")), models.CarrierModel)


def test_the_registry_refuses_unknown_names_and_inapplicable_cavitation():
    import pytest

    from cmpsim import models

    with pytest.raises(ValueError, match=r"carrier must be one of \('rigid', 'membrane'\); got 'gimbal'"):
        models.carrier("gimbal")
    with pytest.raises(ValueError, match=r"carrier 'membrane' needs its inputs"):
        models.carrier("membrane")
    with pytest.raises(ValueError, match="applies to the Newtonian slurry only"):
        models.slurry_model("granular", "gumbel", -1e4, 3e4)
    with pytest.raises(ValueError, match=r"cavitation_pressure must be a gauge pressure"):
        models.slurry_model("newtonian", "jfo", None, 3e4)


def test_no_room_is_over_about_600_lines():
    """Small modules with one job (issue 22: none over about 600 lines; 650 leaves the 'about')."""
    long = {name: n for name, path in source_modules(SRC).items() if (n := len(path.read_text(encoding="utf-8").splitlines())) > 650}
    assert long == {}, long


def test_the_package_face_holds_at_most_eight_modules():
    """The floors are folders (issue 31): only the package face and the utilities sit in src/cmpsim/."""
    top = sorted(p.name for p in SRC.glob("*.py"))
    assert len(top) <= 8, top


def test_every_floor_folder_says_what_lives_there_and_what_it_may_import():
    """Each subpackage's docstring names its floor's contents and the floors it may import."""
    import ast

    for _, _, rooms in FLOORS:
        for room in rooms:
            init = SRC / room / "__init__.py"
            if room == "cmpsim" or not init.exists():
                continue
            doc = ast.get_docstring(ast.parse(init.read_text(encoding="utf-8"))) or ""
            assert len(doc) > 80, room
    for room in ("physics", "numerics", "operators", "inputs", "results", "solver", "head"):
        doc = ast.get_docstring(ast.parse((SRC / room / "__init__.py").read_text(encoding="utf-8")))
        assert "May import" in doc, room


def test_cmpsim_run_loads_only_the_libraries_it_runs():
    """Imports where they are used (issue 31): the base case's `cmpsim run` loads numpy, the
    sparse solvers, scipy.special and rich, not the libraries of other paths."""
    import subprocess
    import sys

    code = (
        "import sys, io, contextlib\n"
        "from cmpsim.cli import main\n"
        "sys.argv = ['cmpsim', 'run']\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    try:\n"
        "        main()\n"
        "    except SystemExit as e:\n"
        "        assert not e.code, e.code\n"
        "print(' '.join(sorted(sys.modules)))\n"
    )
    loaded = set(subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout.split())
    assert "cmpsim.solver.equilibrium" in loaded and "scipy.sparse.linalg" in loaded  # it did solve
    heavy = {"scipy.stats", "scipy.optimize", "scipy.interpolate", "xarray", "matplotlib", "dask", "distributed", "pandas", "pint"}
    assert not heavy & loaded, sorted(heavy & loaded)


def test_the_recipe_engine_and_the_riding_die_do_not_need_each_other():
    """polisher.engine drives polisher.ride; ride imported engine's cache key and units inside
    functions (issue 37). The key is the config's own (Config.key) and the engine merges the ride's
    units, so no circle is left among the polisher's modules, not even inside a function."""
    cycles = import_cycles(SRC, top_level_only=False)
    assert not [c for c in cycles if any(m.startswith("cmpsim.polisher.") for m in c)], cycles
    assert not {i for i in imports_of(SRC / "polisher" / "ride.py", "cmpsim.polisher.ride") if i.startswith("cmpsim.polisher.engine")}
