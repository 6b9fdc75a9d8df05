"""Hotspots: the windows of a die where a quantity exceeds its limit, and their files.

Four quantities have limits (``spec``, m): ``thickness`` (a window's final surface height off the
die's mean, :attr:`cmpsim.die.evolution.DieEvolution.thickness`; its magnitude is compared),
``step_height``, ``dishing`` and ``erosion`` (copper). A hotspot is one window and one quantity:
``{"kind", "x", "y", "value", "limit"}`` (m; x, y the centre of the window's part inside the
die, in the layout's coordinates), with ``"level"`` in a stack; a run that carries a
calibration's covariance adds ``"interval"`` [low, high] (m, 95 %) and ``"probability"`` (of
exceeding the limit; :mod:`cmpsim.die.uncertainty`), an uncalibrated run has neither key.

Files (written atomically): ``hotspots.lyrdb``, KLayout's report database (XML: one category per
quantity, or per level with a sub-category per quantity; the cell is the layout's top cell; each
item a box in microns, the window inside the die, with its value and limit), and
``hotspots.csv``. The database is written with the standard library: KLayout (GPL) is never
imported by cmpsim.
"""

from __future__ import annotations

import io as _io
from pathlib import Path

import numpy as np

__all__ = ["SPEC_KINDS", "parse_spec", "find_hotspots", "find_at_risk", "AT_RISK", "SURE", "risk_counts", "count_hotspots", "write_lyrdb", "write_csv"]

#: The quantities a hotspot limit applies to, and what each means.
SPEC_KINDS = {
    "thickness": "final surface height of the window off the die's mean (its magnitude)",
    "step_height": "step height between the two levels of the window",
    "dishing": "copper dishing: depth of the lines below the cleared field",
    "erosion": "field oxide lost below its original top",
}


def parse_spec(spec, what: str = "--spec") -> dict[str, float]:
    """Limits (m) from ``{"kind": "5 nm" or 5e-9}`` or ``["kind=5nm", ...]``; ValueError naming ``what``
    (``--spec``, or e.g. a stack file's ``[spec]`` table)."""
    from ..inputs.units import to_si

    if spec is None:
        return {}
    items = spec.items() if isinstance(spec, dict) else []
    if not isinstance(spec, dict):
        pairs = []
        for text in spec:
            if "=" not in str(text):
                raise ValueError(f"--spec {text!r} must be KIND=LIMIT, e.g. thickness=5nm; kinds: {', '.join(SPEC_KINDS)}")
            k, v = str(text).split("=", 1)
            pairs.append((k.strip(), v.strip()))
        items = pairs
    out = {}
    for kind, value in items:
        if kind not in SPEC_KINDS:
            from ..inputs.param import did_you_mean

            raise ValueError(f"{what} {kind!r} is not a quantity with a limit{did_you_mean(kind, SPEC_KINDS)}; valid: {', '.join(SPEC_KINDS)}")
        limit = to_si(value, "m", f"{what} {kind}", "5 nm")
        if not (np.isfinite(limit) and limit > 0):
            raise ValueError(f"{what} {kind} = {value!r} must be a length > 0")
        out[kind] = float(limit)
    return out


def _window_boxes(x, y, cell, extent):
    """(x0, y0, x1, y1) of every window clipped to the die's outline, each (ny, nx)."""
    X, Y = np.meshgrid(x, y)
    x0 = np.maximum(X - 0.5 * cell, extent[0])
    x1 = np.minimum(X + 0.5 * cell, extent[2])
    y0 = np.maximum(Y - 0.5 * cell, extent[1])
    y1 = np.minimum(Y + 0.5 * cell, extent[3])
    return x0, y0, x1, y1


def _window(kind: str, limit: float, v: np.ndarray, boxes, iy: int, ix: int, level: str | None) -> dict:
    """A listed window: its quantity, the centre of its part inside the die (m), value and limit (m), box, level."""
    x0, y0, x1, y1 = boxes
    h = {"kind": kind, "x": float(0.5 * (x0[iy, ix] + x1[iy, ix])), "y": float(0.5 * (y0[iy, ix] + y1[iy, ix])),
         "value": float(v[iy, ix]), "limit": float(limit), "box": (float(x0[iy, ix]), float(y0[iy, ix]), float(x1[iy, ix]), float(y1[iy, ix]))}
    if level is not None:
        h["level"] = level
    return h


def find_hotspots(fields: dict, x, y, cell: float, extent, spec: dict, level: str | None = None, sigma: dict | None = None) -> list[dict]:
    """The hotspots of per-window ``fields`` (name -> (ny, nx) array, m) against ``spec`` (kind -> limit, m).

    Windows wholly outside the die's outline ``extent`` (xmin, ymin, xmax, ymax) are skipped; the
    position is the centre of the window's part inside it. Sorted by value / limit, largest first.
    With ``sigma`` (kind -> (ny, nx) standard deviation, m; a calibrated run,
    :mod:`cmpsim.die.uncertainty`) every hotspot also carries ``interval`` [low, high] (m, 95 %)
    and ``probability`` (that the quantity exceeds its limit in magnitude).
    """
    from .uncertainty import exceedance_probability

    x0, y0, x1, y1 = _window_boxes(np.asarray(x), np.asarray(y), cell, extent)
    inside = (x1 > x0) & (y1 > y0)
    out = []
    for kind, limit in spec.items():
        v = fields.get(kind)
        if v is None:
            continue
        v = np.asarray(v, dtype=float)
        with np.errstate(invalid="ignore"):
            hit = inside & np.isfinite(v) & (np.abs(v) > limit)
        for iy, ix in zip(*np.nonzero(hit)):
            h = _window(kind, limit, v, (x0, y0, x1, y1), iy, ix, level)
            if sigma is not None and kind in sigma:
                sd = float(np.asarray(sigma[kind])[iy, ix])
                h["interval"] = [h["value"] - 1.96 * sd, h["value"] + 1.96 * sd]
                h["probability"] = float(exceedance_probability(h["value"], sd, limit))
            out.append(h)
    out.sort(key=lambda h: -abs(h["value"]) / h["limit"])
    return out


#: The probability of exceeding its limit from which a window under it is "at risk": its 95 % interval
#: (value +- 1.96 sigma) reaches the limit (P(X > limit) = 0.025 at value + 1.96 sigma = limit).
AT_RISK = 0.025
#: The probability over which a hotspot fails "for sure": its whole 95 % interval is over the limit.
SURE = 0.975


def _graded(fields: dict, sigma: dict, x, y, cell: float, extent, spec: dict):
    """Per quantity with a limit and a sigma: (kind, limit, value, sigma, over, under, probability of
    exceeding (eq. U2), window boxes): ``over``/``under`` the windows inside the die with a finite value
    over / at most their limit (arrays (ny, nx))."""
    from .uncertainty import exceedance_probability

    x0, y0, x1, y1 = _window_boxes(np.asarray(x), np.asarray(y), cell, extent)
    inside = (x1 > x0) & (y1 > y0)
    for kind, limit in spec.items():
        v, sd = fields.get(kind), sigma.get(kind)
        if v is None or sd is None:
            continue
        v, sd = np.asarray(v, dtype=float), np.asarray(sd, dtype=float)
        with np.errstate(invalid="ignore"):
            ok = inside & np.isfinite(v)
            over = ok & (np.abs(v) > limit)
        p = np.zeros(v.shape)
        p[ok] = exceedance_probability(v[ok], sd[ok], limit)
        yield kind, float(limit), v, sd, over, ok & ~over, p, (x0, y0, x1, y1)


def risk_counts(fields: dict, sigma: dict, x, y, cell: float, extent, spec: dict) -> tuple[float, int, int]:
    """(expected number of windows x quantities over their limits, the sum of every window's probability
    of exceeding (eq. U2); hotspots that fail for sure, probability > :data:`SURE`; windows at risk, as
    :func:`find_at_risk`) of a calibrated die: what a wafer of dies reports per die."""
    expected, sure, risk = 0.0, 0, 0
    for _, _, _, sd, over, under, p, _ in _graded(fields, sigma, x, y, cell, extent, spec):
        expected += float(np.sum(p))
        sure += int(np.count_nonzero(over & (p > SURE)))
        risk += int(np.count_nonzero(under & (sd > 0) & (p >= AT_RISK)))
    return expected, sure, risk


def find_at_risk(fields: dict, x, y, cell: float, extent, spec: dict, sigma: dict, level: str | None = None,
                 threshold: float = AT_RISK) -> list[dict]:
    """The windows of a calibrated run that are *under* their limit but may exceed it: probability of
    exceeding (eq. U2) at least ``threshold``, i.e. their 95 % interval reaches the limit. The
    complement of :func:`find_hotspots` (which lists the windows over it, each with its probability):
    together they say which windows fail for sure, which only might, and which might although they
    pass. Same keys as a hotspot (``interval`` [low, high] m, ``probability``); sorted by probability,
    largest first. Empty without ``sigma``."""
    if not sigma:
        return []
    out = []
    for kind, limit, v, sd, _, under, p, (x0, y0, x1, y1) in _graded(fields, sigma, x, y, cell, extent, spec):
        for iy, ix in zip(*np.nonzero(under & (sd > 0) & (p >= threshold))):
            h = _window(kind, limit, v, (x0, y0, x1, y1), iy, ix, level)
            h["interval"] = [float(v[iy, ix] - 1.96 * sd[iy, ix]), float(v[iy, ix] + 1.96 * sd[iy, ix])]
            h["probability"] = float(p[iy, ix])
            out.append(h)
    out.sort(key=lambda h: -h["probability"])
    return out


def count_hotspots(fields: dict, x, y, cell: float, extent, spec: dict) -> int:
    """The number of hotspots :func:`find_hotspots` would return (vectorised: no list is built)."""
    x0, y0, x1, y1 = _window_boxes(np.asarray(x), np.asarray(y), cell, extent)
    inside = (x1 > x0) & (y1 > y0)
    n = 0
    for kind, limit in spec.items():
        v = fields.get(kind)
        if v is None:
            continue
        with np.errstate(invalid="ignore"):
            n += int(np.count_nonzero(inside & np.isfinite(v) & (np.abs(v) > limit)))
    return n


def public(hotspots: list[dict]) -> list[dict]:
    """The hotspots as in the JSON: without the internal ``box``."""
    return [{k: v for k, v in h.items() if k != "box"} for h in hotspots]


def lyrdb_text(hotspots: list[dict], top: str, description: str = "", original_file: str = "") -> str:
    """KLayout report database XML of the hotspots (boxes in microns)."""
    import xml.etree.ElementTree as ET

    root = ET.Element("report-database")
    ET.SubElement(root, "description").text = description or "cmpsim die: CMP hotspots"
    ET.SubElement(root, "original-file").text = original_file
    ET.SubElement(root, "generator").text = "cmpsim die"
    ET.SubElement(root, "top-cell").text = top
    ET.SubElement(root, "tags")
    cats = ET.SubElement(root, "categories")
    levels: dict[str | None, list[str]] = {}
    for h in hotspots:
        kinds = levels.setdefault(h.get("level"), [])
        if h["kind"] not in kinds:
            kinds.append(h["kind"])

    def category(parent, name, text):
        c = ET.SubElement(parent, "category")
        ET.SubElement(c, "name").text = name
        ET.SubElement(c, "description").text = text
        return ET.SubElement(c, "categories")

    for level, kinds in levels.items():
        parent = cats if level is None else category(cats, level, f"level {level}")
        for kind in kinds:
            category(parent, kind, SPEC_KINDS[kind])
    cells = ET.SubElement(root, "cells")
    c = ET.SubElement(cells, "cell")
    ET.SubElement(c, "name").text = top
    ET.SubElement(c, "variant")
    ET.SubElement(c, "references")
    items = ET.SubElement(root, "items")
    for h in hotspots:
        it = ET.SubElement(items, "item")
        ET.SubElement(it, "tags")
        ET.SubElement(it, "category").text = h["kind"] if h.get("level") is None else f"{h['level']}.{h['kind']}"
        ET.SubElement(it, "cell").text = top
        ET.SubElement(it, "visited").text = "false"
        ET.SubElement(it, "multiplicity").text = "1"
        ET.SubElement(it, "image")
        vals = ET.SubElement(it, "values")
        bx = [v * 1e6 for v in h["box"]]
        ET.SubElement(vals, "value").text = f"box: ({bx[0]:.6f},{bx[1]:.6f};{bx[2]:.6f},{bx[3]:.6f})"
        ET.SubElement(vals, "value").text = (f"text: '{h['kind']} {h['value'] * 1e9:.3f} nm, limit {h['limit'] * 1e9:.3f} nm"
                                             + (f", level {h['level']}" if h.get("level") else "") + "'")
    ET.indent(root, " ")
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def write_lyrdb(path, hotspots: list[dict], top: str, description: str = "", original_file: str = "") -> Path:
    """Write ``hotspots.lyrdb`` (KLayout report database) atomically."""
    from ..io import atomic_write_text

    atomic_write_text(Path(path), lyrdb_text(hotspots, top, description, original_file))
    return Path(path)


def write_csv(path, hotspots: list[dict]) -> Path:
    """Write the hotspots as CSV (SI: m), atomically: level, kind, x, y, value, limit and the window box; a calibrated
    run adds interval_low_m, interval_high_m (95 %) and probability (of exceeding the limit)."""
    from ..io import atomic_write_text

    buf = _io.StringIO()
    sure = any("probability" in h for h in hotspots)  # a calibrated run: the 95 % interval and the probability of exceeding the limit
    buf.write("level,kind,x_m,y_m,value_m,limit_m,xmin_m,ymin_m,xmax_m,ymax_m" + (",interval_low_m,interval_high_m,probability" if sure else "") + "\n")
    for h in hotspots:
        b = h["box"]
        buf.write(f"{h.get('level') or ''},{h['kind']},{h['x']:.9g},{h['y']:.9g},{h['value']:.6g},{h['limit']:.6g},"
                  f"{b[0]:.9g},{b[1]:.9g},{b[2]:.9g},{b[3]:.9g}")
        if sure:
            iv = h.get("interval") or ("", "")
            buf.write(f",{iv[0]:.6g},{iv[1]:.6g},{h['probability']:.6g}" if "probability" in h else ",,,")
        buf.write("\n")
    atomic_write_text(Path(path), buf.getvalue())
    return Path(path)
