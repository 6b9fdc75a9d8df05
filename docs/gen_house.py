"""Draw the house of cmpsim for docs/developer.md: before and after the house-keeping of issue 13.

Run by mkdocs-gen-files at every build (``mkdocs.yml``), or by hand to write the two SVG files
into a folder: ``python docs/gen_house.py --write DIR``.

* ``house-after.svg`` is drawn from the source as it is: the floors and rooms of
  :data:`cmpsim.testing.house.FLOORS` and every import between rooms, found by parsing each
  module (the same graph ``tests/test_house.py`` checks). An upward import would be drawn in
  red; the test fails before one can be.
* ``house-before.svg`` is the house at commit 29b430c (cmpsim 0.1 with the shear-power law),
  its rooms and imports read from that commit once and written below as data.
"""

from __future__ import annotations

import html
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent if "__file__" in globals() else Path("docs").resolve()
SRC = DOCS.parent / "src" / "cmpsim"

W = 1240  # width of the picture, px
LABEL = 210  # the floors' names on the left
FLOOR_H = 118
BOX_H = 64
GREY, BLUE, RED, ORANGE = "#8a8f98", "#2f6fdd", "#d62828", "#e07a00"

#: The house at 29b430c: (floor, what it held, [(room, lines or note)]), bottom first.
BEFORE_FLOORS = (
    ("kernels", "pure physics", [("grainflow", ""), ("flowfactors", ""), ("contact", ""), ("geometry", ""), ("kinematics", ""), ("removal", "")]),
    ("discretisation", "grid, sparse Reynolds", [("grid", ""), ("reynolds", "")]),
    ("solver", "Newton on the wafer", [("equilibrium", "")]),
    ("model", "one operating point", [("config", "units (pint) #1"), ("setup", ""), ("postprocess", "rim film #1"), ("model", "+ the reference case")]),
    (
        "top (flat)",
        "everything else, side by side",
        [
            ("result", "imports __version__ up"),
            ("cli", "banners, click patch"),
            ("sweeps.py", "1150 lines; units #2"),
            ("reproduction.py", "943 lines; units #3"),
            ("validation.py", "904 lines: the hidden runner; units #4"),
            ("calibration.py", "543 lines"),
            ("cmpsim", "__version__ (and in pyproject)"),
        ],
    ),
)
#: Imports between rooms at 29b430c (io left out), with the ones the issue named coloured.
BEFORE_EDGES = [
    ("calibration.py", "config"), ("cli", "calibration.py"), ("cli", "config"), ("cli", "equilibrium"), ("cli", "model"),
    ("cli", "reproduction.py"), ("cli", "sweeps.py"), ("cli", "validation.py"), ("cmpsim", "config"), ("cmpsim", "equilibrium"),
    ("cmpsim", "model"), ("cmpsim", "result"), ("equilibrium", "contact"), ("equilibrium", "geometry"), ("equilibrium", "grid"),
    ("equilibrium", "reynolds"), ("model", "config"), ("model", "equilibrium"), ("model", "postprocess"), ("model", "result"),
    ("model", "setup"), ("postprocess", "config"), ("postprocess", "equilibrium"), ("postprocess", "flowfactors"),
    ("postprocess", "grainflow"), ("postprocess", "removal"), ("postprocess", "setup"), ("reproduction.py", "config"),
    ("result", "config"), ("result", "contact"), ("reynolds", "flowfactors"), ("reynolds", "grainflow"), ("reynolds", "grid"),
    ("reynolds", "kinematics"), ("setup", "config"), ("setup", "contact"), ("setup", "equilibrium"), ("setup", "flowfactors"),
    ("setup", "geometry"), ("setup", "grainflow"), ("setup", "grid"), ("setup", "kinematics"), ("setup", "reynolds"),
    ("sweeps.py", "config"), ("sweeps.py", "equilibrium"), ("sweeps.py", "model"), ("sweeps.py", "result"),
    ("validation.py", "config"), ("validation.py", "equilibrium"), ("validation.py", "model"),
    # the study runner hidden in validation: its private helpers imported by two other studies
    ("calibration.py", "validation.py", ORANGE), ("reproduction.py", "validation.py", ORANGE),
    # the reference case of the relative removal rate, a study concept, taken from model
    ("reproduction.py", "model", ORANGE),
    # the version imported from the package entrance, which imports them lazily: upwards
    ("sweeps.py", "cmpsim", RED), ("reproduction.py", "cmpsim", RED), ("result", "cmpsim", RED),
]


def _after():
    """Floors with rooms (sub-rooms of packages as notes) and the room imports of the source as it is."""
    sys.path.insert(0, str(SRC.parent))
    from cmpsim.testing.house import FLOORS, UTILITIES, _target, floor_of, imports_of, room_of, source_modules

    modules = source_modules(SRC)
    floors = []
    for name, what, rooms in FLOORS:
        entries = []
        for room in rooms:
            subs = sorted(m.split(".")[2] for m in modules if m.count(".") == 2 and m.split(".")[1] == room)
            if room == "cmpsim":
                entries.append(("cmpsim", "the entrance: lazy names"))
            elif f"cmpsim.{room}" in modules:
                entries.append((room + ("/" if subs else ""), " ".join(subs)))
        floors.append((name, what, entries))
    edges = set()
    for name, path in modules.items():
        for imported in imports_of(path, name):
            a, b = room_of(name), room_of(_target(imported, modules))
            if a == b or b in UTILITIES or a in UTILITIES:
                continue
            fa, fb = floor_of(name), floor_of(f"cmpsim.{b}" if b != "cmpsim" else "cmpsim")
            colour = RED if fb is not None and fa is not None and fb > fa else (BLUE if fa == fb else GREY)
            edges.add((_label(floors, a), _label(floors, b), colour))
    return floors, sorted(edges)


def _label(floors, room: str) -> str:
    for _, _, entries in floors:
        for label, _ in entries:
            if label.rstrip("/") == room:
                return label
    return room


def _svg(title: str, floors, edges, legend: list[tuple[str, str]], rule: str) -> str:
    n = len(floors)
    top = 96
    height = top + n * FLOOR_H + 40 + 22 * len(legend)
    boxes: dict[str, tuple[float, float, float, float, int]] = {}  # label -> x, y, w, h, floor
    out = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{height}" viewBox="0 0 {W} {height}" font-family="Helvetica, Arial, sans-serif">',
        '<defs>',
    ]
    for colour in (GREY, BLUE, RED, ORANGE):
        out.append(
            f'<marker id="m{colour[1:]}" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" markerHeight="7" orient="auto-start-reverse">'
            f'<path d="M0,0 L10,5 L0,10 z" fill="{colour}"/></marker>'
        )
    out.append("</defs>")
    out.append(f'<rect width="{W}" height="{height}" fill="white"/>')
    out.append(f'<text x="16" y="30" font-size="20" font-weight="bold">{html.escape(title)}</text>')
    out.append(f'<text x="16" y="52" font-size="13" fill="#444">{html.escape(rule)}</text>')
    for k, (name, what, entries) in enumerate(floors):
        y0 = top + (n - 1 - k) * FLOOR_H
        shade = "#f4f6fa" if k % 2 == 0 else "#e9edf4"
        out.append(f'<rect x="8" y="{y0}" width="{W - 16}" height="{FLOOR_H - 6}" rx="6" fill="{shade}" stroke="#c9d0dc"/>')
        out.append(f'<text x="20" y="{y0 + 30}" font-size="15" font-weight="bold">{k}. {html.escape(name)}</text>')
        for j, line in enumerate(_wrap(what, 26)):
            out.append(f'<text x="20" y="{y0 + 50 + 15 * j}" font-size="11" fill="#555">{html.escape(line)}</text>')
        m = max(len(entries), 1)
        slot = (W - LABEL - 24) / m
        for j, (label, note) in enumerate(entries):
            w = min(slot - 14, 190)
            x = LABEL + j * slot + (slot - w) / 2
            y = y0 + (FLOOR_H - 6 - BOX_H) / 2
            boxes[label] = (x, y, w, BOX_H, k)
            out.append(f'<rect x="{x:.1f}" y="{y:.1f}" width="{w:.1f}" height="{BOX_H}" rx="5" fill="white" stroke="#34495e" stroke-width="1.3"/>')
            out.append(f'<text x="{x + w / 2:.1f}" y="{y + 20:.1f}" font-size="13.5" font-weight="bold" text-anchor="middle">{html.escape(label)}</text>')
            for i, line in enumerate(_wrap(note, int(w / 6.2))[:3]):
                out.append(f'<text x="{x + w / 2:.1f}" y="{y + 36 + 12 * i:.1f}" font-size="10.5" fill="#555" text-anchor="middle">{html.escape(line)}</text>')
    for edge in edges:
        a, b, colour = edge if len(edge) == 3 else (*edge, GREY)
        if a not in boxes or b not in boxes:
            continue
        xa, ya, wa, ha, fa = boxes[a]
        xb, yb, wb, hb, fb = boxes[b]
        strong = colour != GREY
        style = f'stroke="{colour}" stroke-width="{2.2 if strong else 1}" fill="none" opacity="{0.95 if strong else 0.45}" marker-end="url(#m{colour[1:]})"'
        if fa == fb:  # same floor: an arc above the boxes going right, below them going left
            x1, x2 = xa + wa / 2, xb + wb / 2
            y, lift = (ya, -min(14 + 0.06 * abs(x2 - x1), 34)) if x2 > x1 else (ya + ha, min(10 + 0.04 * abs(x2 - x1), 20))
            out.append(f'<path d="M{x1:.1f},{y:.1f} Q{(x1 + x2) / 2:.1f},{y + 2 * lift:.1f} {x2:.1f},{y:.1f}" {style}/>')
        else:
            down = fb < fa
            x1, y1 = xa + wa / 2 + (wa * 0.3) * ((_spread(b) % 7) / 6 - 0.5), (ya + ha if down else ya)
            x2, y2 = xb + wb / 2 + (wb * 0.3) * ((_spread(a) % 7) / 6 - 0.5), (yb if down else yb + hb)
            out.append(f'<line x1="{x1:.1f}" y1="{y1:.1f}" x2="{x2:.1f}" y2="{y2:.1f}" {style}/>')
    y = top + n * FLOOR_H + 16
    for colour, text in legend:
        out.append(f'<line x1="20" y1="{y:.1f}" x2="60" y2="{y:.1f}" stroke="{colour}" stroke-width="2.2" marker-end="url(#m{colour[1:]})"/>')
        out.append(f'<text x="70" y="{y + 4:.1f}" font-size="12">{html.escape(text)}</text>')
        y += 22
    out.append("</svg>")
    return "\n".join(out) + "\n"


def _spread(label: str) -> int:
    """A stable small number of a label, to spread the arrow ends along a box (not hash(): salted)."""
    return sum(map(ord, label))


def _wrap(text: str, width: int) -> list[str]:
    lines, line = [], ""
    for word in text.split():
        if line and len(line) + 1 + len(word) > width:
            lines.append(line)
            line = word
        else:
            line = f"{line} {word}".strip()
    return lines + ([line] if line else [])


def pictures() -> dict[str, str]:
    """{file name: SVG text} of the two pictures."""
    before = _svg(
        "Before (29b430c): a flat top floor",
        BEFORE_FLOORS,
        BEFORE_EDGES,
        [
            (GREY, "imports a room below"),
            (ORANGE, "a study reaching into another study's private helpers, or into the model for a study concept"),
            (RED, "imports upwards (the version, from the package entrance that imports it)"),
        ],
        "Units parsed in four rooms (#1-#4); warm-then-cold written three times; tables four times; progress twice.",
    )
    floors, edges = _after()
    after = _svg(
        "After: floors and rooms (drawn from the source at build time)",
        floors,
        edges,
        [
            (GREY, "imports a room on a floor below"),
            (BLUE, "imports a room on the same floor (the studies use the one runner, cmpsim.solver.points)"),
            (RED, "imports upwards: none (tests/test_house.py fails first)"),
        ],
        "The rule: nothing imports upwards; the kernels import nothing of cmpsim; io and _version serve every floor.",
    )
    return {"house-before.svg": before, "house-after.svg": after}


def main() -> None:
    if "--write" in sys.argv:  # python docs/gen_house.py --write DIR
        folder = Path(sys.argv[sys.argv.index("--write") + 1])
        for name, text in pictures().items():
            (folder / name).write_text(text, encoding="utf-8")
        return
    import mkdocs_gen_files

    for name, text in pictures().items():
        with mkdocs_gen_files.open(name, "w") as fh:
            fh.write(text)


main()
