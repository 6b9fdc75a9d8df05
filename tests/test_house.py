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


def test_units_and_config_do_not_need_each_other():
    """The parameter registry hands its entries to cmpsim.units; units never imports config,
    not even inside a function (issue 22: the config <-> units circle)."""
    cycles = import_cycles(SRC, top_level_only=False)
    assert not [c for c in cycles if {"cmpsim.units", "cmpsim.config"} & set(c)], cycles
    assert "cmpsim.config" not in imports_of(SRC / "units.py", "cmpsim.units")


def _package(tmp_path, modules: dict[str, str]):
    """A package ``cmpsim`` under ``tmp_path`` with the given {module: source}."""
    root = tmp_path / "cmpsim"
    root.mkdir()
    for name, text in {"__init__": "", **modules}.items():
        (root / f"{name}.py").write_text(text)
    return root


def test_the_cycle_check_sees_imports_inside_functions(tmp_path):
    root = _package(tmp_path, {"config": "from . import units\n", "units": "def f():\n    from .config import PARAMETERS\n"})
    assert import_cycles(root) == []
    assert import_cycles(root, top_level_only=False) == [["cmpsim.config", "cmpsim.units", "cmpsim.config"]]


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
        {"config": "", "studies": "", "contact": "from .config import PARAMETERS\n", "equilibrium": "def f():\n    from cmpsim.studies import solve_point\n"},
    )
    found = violations(root)
    assert any(v.startswith("cmpsim.contact is a kernel and imports cmpsim.config") for v in found), found
    assert any(v.startswith("cmpsim.equilibrium imports cmpsim.studies") for v in found), found
