"""The floors of cmpsim and the rule the house keeps: nothing imports upwards.

:data:`FLOORS` lists the floors from the bottom up, each with its rooms (modules, or
packages with rooms of their own). A module may import from its own floor and the floors
below it, never from a floor above; the kernels import nothing of cmpsim at all. ``io`` and
``_version`` (and ``tables``, the terminal tables) are utilities that every floor may import and that import nothing of cmpsim.
The rule holds for every import, at the top of a module or inside a function.

``tests/test_house.py`` checks the rule on the source (parsed with :mod:`ast`, nothing is
imported); ``docs/gen_house.py`` draws the house of ``docs/developer.md`` from the same table
and the same import graph.
"""

from __future__ import annotations

import ast
from pathlib import Path

__all__ = ["FLOORS", "UTILITIES", "MODEL_OPTIONS", "source_modules", "imports_of", "floor_of", "violations", "import_cycles", "option_name_comparisons"]

#: (floor, what it holds, rooms), bottom first. A room is a module or a package of cmpsim.
FLOORS: tuple[tuple[str, str, tuple[str, ...]], ...] = (
    ("kernels", "pure vectorised physics, each function an equation of the paper or a source: grain flow, flow factors, contact, geometry, kinematics, removal, abrasion, kinetics, materials, the elastic pad stack, the grooves", ("physics",)),
    ("numerics", "the polar grid and its face operators; the finite-volume assembly; the guarded sparse LU; the hand-written GMRES; the layered pad on the grid; the wafer as a plate", ("numerics",)),
    ("operators", "the coupled operators the plug-ins use: the sparse Reynolds and cavitation systems, the pad-coupled Newton matrix, the film with the pad deflection and with the position in one Newton iteration, its linear response, the state, the membrane's bending", ("operators",)),
    ("models", "the models of the four axes and their registry", ("models",)),
    ("inputs", "the registries of the inputs: units, ranges and sources (one entry and its range check); the configuration; inputs another input sets", ("inputs",)),
    ("results", "the outputs with units and meanings; the result of one point; uniformity", ("results",)),
    ("solver", "the driver: set-up, the wafer problem, load balance, equilibrium, post-processing; one Config in, one Result out; the runner every study shares", ("solver",)),
    ("studies", "many points: the head's studies, the polisher over time (recipes, end point, pad temperature, lot control, a die riding along the steps), sweeps, validation, reproduction, calibration, the die model and the layouts it reads; test tools", ("head", "polisher", "layout", "sweeps", "validation", "reproduction", "calibration", "die", "testing")),
    ("faces", "what people call: the package entrance, the command line (also `python -m cmpsim`), the web", ("cmpsim", "__main__", "cli", "web")),
)
#: Modules any floor may import; they import nothing of cmpsim.
UTILITIES = ("io", "_version", "tables")


def _name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def source_modules(root: Path) -> dict[str, Path]:
    """{dotted module name: path} of every module under ``root`` (the ``cmpsim`` source folder)."""
    root = Path(root)
    return {_name(p, root): p for p in sorted(root.rglob("*.py"))}


def imports_of(path: Path, name: str, top_level_only: bool = False) -> set[str]:
    """The cmpsim modules that module ``name`` (at ``path``) imports, relative imports resolved.

    ``from . import x`` counts as importing ``package.x``. With ``top_level_only`` only the
    imports run when the module is imported (not those inside functions) are returned.
    """
    tree = ast.parse(Path(path).read_text(encoding="utf-8"))
    package = name if Path(path).name == "__init__.py" else name.rpartition(".")[0]
    nodes = tree.body if top_level_only else ast.walk(tree)
    found: set[str] = set()
    for node in nodes:
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.split(".")[0] == "cmpsim"}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            if module.split(".")[0] != "cmpsim":
                continue
            if node.module is None or module == "cmpsim":  # from . import x: the module x (or a name of the package)
                found |= {f"{module}.{a.name}" for a in node.names}
            else:
                found.add(module)
    return found


def room_of(module: str) -> str:
    """The room of a dotted module name: ``cmpsim.sweeps.plan`` -> ``sweeps``, ``cmpsim`` -> ``cmpsim``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else parts[0]


def floor_of(module: str) -> int | None:
    """Index in :data:`FLOORS` of the floor of ``module`` (None for a utility or an unknown room)."""
    room = room_of(module)
    for k, (_, _, rooms) in enumerate(FLOORS):
        if room in rooms:
            return k
    return None


def _target(name: str, modules: dict[str, Path]) -> str:
    """An imported name resolved to a module: ``cmpsim.inputs.config.Config`` is not a module, ``cmpsim.inputs.config`` is."""
    while name not in modules and "." in name:
        name = name.rpartition(".")[0]
    return name


def violations(root: Path) -> list[str]:
    """Every import that breaks the rule, as ``'a imports b (floor x above floor y)'`` lines."""
    modules = source_modules(root)
    out = []
    for name, path in modules.items():
        room = room_of(name)
        here = floor_of(name)
        if here is None and room not in UTILITIES:
            out.append(f"{name} is on no floor: add its room to cmpsim.testing.house.FLOORS (and docs/developer.md)")
            continue
        for imported in sorted(imports_of(path, name)):
            target = _target(imported, modules)
            if room_of(target) == room:
                continue
            there = floor_of(target)
            if room in UTILITIES:
                out.append(f"{name} is a utility and imports {target}")
            elif here == 0:
                out.append(f"{name} is a kernel and imports {target}: kernels import nothing of cmpsim")
            elif there is not None and there > here:
                out.append(f"{name} imports {target}: floor '{FLOORS[there][0]}' is above floor '{FLOORS[here][0]}'")
    return out


def import_cycles(root: Path, top_level_only: bool = True) -> list[list[str]]:
    """Cycles of the imports run when modules are imported (top-level imports only), or with
    ``top_level_only=False`` of every import, also those inside functions (two modules that
    need each other, whichever waits until a call)."""
    modules = source_modules(root)
    graph = {n: {_target(i, modules) for i in imports_of(p, n, top_level_only=top_level_only)} & set(modules) - {n} for n, p in modules.items()}
    cycles, state = [], {}

    def visit(node, stack):
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                cycles.append(stack[stack.index(nxt):] + [nxt])
            elif nxt not in state:
                visit(nxt, stack)
        stack.pop()
        state[node] = 2

    for n in sorted(graph):
        if n not in state:
            visit(n, [])
    return cycles


#: The inputs that pick a model (one class per value, chosen in :mod:`cmpsim.models`).
MODEL_OPTIONS = ("pad_compliance", "slurry_model", "cavitation", "removal_law", "carrier", "removal_kinetics", "abrasive", "film")
#: The modules allowed to read an option's name: where the inputs are checked and where the
#: models are picked by name (the registry).
OPTION_READERS = ("cmpsim.inputs.config", "cmpsim.solver.setup", "cmpsim.models")


def _option_ref(node: ast.AST) -> bool:
    """``x.cavitation``, ``cavitation`` or ``x["cavitation"]``: a reference to a model option."""
    if isinstance(node, ast.Attribute):
        return node.attr in MODEL_OPTIONS
    if isinstance(node, ast.Name):
        return node.id in MODEL_OPTIONS
    if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant):
        return node.slice.value in MODEL_OPTIONS
    return False


def _str_constant(node: ast.AST) -> bool:
    """A str constant, or a tuple / list / set literal holding one (``x in ("a", "b")``)."""
    if isinstance(node, ast.Constant):
        return isinstance(node.value, str)
    if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        return any(_str_constant(e) for e in node.elts)
    return False


def option_name_comparisons(root: Path, allowed=OPTION_READERS) -> list[str]:
    """Every comparison of a model option's name with a string outside ``allowed``.

    A ``Compare`` node of the AST one of whose operands refers to a model option
    (:data:`MODEL_OPTIONS`: ``problem.cavitation``, ``slurry_model``, ...) and another is a
    string constant or a literal collection of strings (``== "jfo"``, ``in ("gumbel", "jfo")``).
    Returns ``'module:line: source'`` lines. New physics adds a class to :mod:`cmpsim.models`,
    not a branch on a name in the solver.
    """
    out = []
    for name, path in source_modules(Path(root)).items():
        if name in allowed:
            continue
        text = Path(path).read_text(encoding="utf-8")
        for node in ast.walk(ast.parse(text)):
            if not isinstance(node, ast.Compare):
                continue
            operands = [node.left, *node.comparators]
            if any(_option_ref(a) for a in operands) and any(_str_constant(a) for a in operands):
                out.append(f"{name}:{node.lineno}: {ast.get_source_segment(text, node)}")
    return out
