"""What the data can identify, read from the fit's Jacobian.

:func:`choose` keeps candidate inputs in their order of preference while each adds a direction
the data see (a column of the Jacobian of the whitened residuals that the columns kept before
do not span) and one degree of freedom is left; :func:`separability` says after a fit which
inputs the data cannot tell apart (|correlation| >= :data:`CORRELATION_LIMIT`) and gives the
singular values of the scaled Jacobian. :func:`zero_columns` is the one test of "the data do not
change with this input" of every fit (:data:`ZERO_JACOBIAN`), and :func:`refuse_flat` refuses an
input asked for whose column is zero at the fit.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Choice", "choose", "separability", "zero_columns", "refuse_flat", "CORRELATION_LIMIT", "SEPARATION_LIMIT", "ZERO_JACOBIAN"]

#: |correlation| of two fitted inputs at or above which the data cannot separate them.
CORRELATION_LIMIT = 0.99
#: Part of a candidate's Jacobian column outside the span of the columns kept (relative norm)
#: below which it cannot be separated from them: sin(angle) 0.1, i.e. a correlation of 0.995.
SEPARATION_LIMIT = 0.1
#: Norm of a Jacobian column (whitened residuals per unit fit variable, dimensionless) at or below which the data
#: do not depend on a free input at all: absolutely (a unit change of the input's fit variable moves the residuals
#: by 1e-9 of their uncertainties), or relative to the largest column when that is above 1 (1e-9 of what another
#: input does). An exact zero in practice: e.g. the edge exclusion for wafer-mean rates.
ZERO_JACOBIAN = 1e-9


def zero_columns(J: np.ndarray) -> np.ndarray:
    """Which columns of ``J`` (whitened residuals x fit variables) are zero, one bool per column: finite, with
    a norm at most :data:`ZERO_JACOBIAN` times the largest finite column's norm or 1, whichever is larger.
    A column with a non-finite entry is not called zero (the model had no value there; said elsewhere)."""
    J = np.asarray(J, dtype=float)
    finite = np.all(np.isfinite(J), axis=0)
    norms = np.linalg.norm(np.where(np.isfinite(J), J, 0.0), axis=0)
    largest = float(norms[finite].max()) if finite.any() else 0.0
    return finite & (norms <= ZERO_JACOBIAN * max(largest, 1.0))


def refuse_flat(J: np.ndarray, names, data: str, kind: str, option: str = "free", error=ValueError) -> None:
    """Raise ``error`` naming the inputs ``names`` (asked for with ``option``) whose columns of the Jacobian at the
    fit ``J`` are zero (:func:`zero_columns`): their "fitted" values would be their starts, or wherever the
    optimiser left them. ``data``: what the data are ("these test structures"); ``kind``: what to free instead."""
    flat = [n for n, z in zip(names, zero_columns(J)) if z]
    if flat:
        raise error(f"{option} {', '.join(flat)}: {data} do not change with {'it' if len(flat) == 1 else 'them'} (column of the Jacobian "
                    f"zero at the fit): not identifiable from these data, nothing fitted; free {kind} the data depend on (without "
                    f"{option} the data choose them)")


@dataclass
class Choice:
    """The inputs kept (``chosen``, each with its reason) and the ones left (``left``, each with why)."""

    chosen: list = field(default_factory=list)  # [(name, why)]
    left: list = field(default_factory=list)  # [(name, why)]
    notes: list = field(default_factory=list)  # on quantities that choose no input

    @property
    def names(self) -> list[str]:
        return [n for n, _ in self.chosen]

    def lines(self) -> list[str]:
        out = [f"fit {n}: {why}" for n, why in self.chosen]
        out += [f"fixed {n}: {why}" for n, why in self.left]
        return out + list(self.notes)


def choose(J: np.ndarray, names: list[str], whys: list[str], max_free: int) -> Choice:
    """Keep the columns of ``J`` (whitened residuals x fit variables, one per candidate in ``names``,
    in order of preference) that the data can separate, at most ``max_free`` of them."""
    J = np.asarray(J, dtype=float)
    norms = np.linalg.norm(J, axis=0)
    zero = zero_columns(J)
    out = Choice()
    kept: list[int] = []
    for k, (name, why) in enumerate(zip(names, whys)):
        col = J[:, k]
        if not np.all(np.isfinite(col)) or zero[k]:
            out.left.append((name, "the data do not change with it (its column of the Jacobian is zero): not identifiable from these data"))
            continue
        if kept:
            A = J[:, kept]
            coef, *_ = np.linalg.lstsq(A, col, rcond=None)
            rest = np.linalg.norm(col - A @ coef) / norms[k]
            if rest < SEPARATION_LIMIT:
                cos = [abs(float(J[:, i] @ col) / (norms[i] * norms[k])) for i in kept]
                other = names[kept[int(np.argmax(cos))]] if len(kept) == 1 or max(cos) > 0.5 else " and ".join(names[i] for i in kept)
                out.left.append((name, f"{name} and {other} cannot be separated by these data (the part of its effect they do not already "
                                       f"give is {100 * rest:.1f} %); fix one: {name} kept at its value"))
                continue
        if len(kept) >= max_free:
            out.left.append((name, f"no degree of freedom left for it ({J.shape[0]} points, {len(kept)} input(s) already free, one point kept "
                                   "for the error estimate)"))
            continue
        kept.append(k)
        out.chosen.append((name, why))
    return out


def separability(J: np.ndarray, names: list[str], correlation: np.ndarray | None = None) -> tuple[list[str], np.ndarray]:
    """(messages on the inputs the data cannot separate, singular values of J with unit columns).

    A pair whose correlation is at or beyond +-:data:`CORRELATION_LIMIT` is reported as "X and Y
    cannot be separated by these data; fix one"; a zero singular value as "not identifiable".
    """
    J = np.asarray(J, dtype=float)
    if J.size == 0 or not np.all(np.isfinite(J)):
        return [], np.array([])
    norms = np.linalg.norm(J, axis=0)
    unit = J / np.where(norms > 0, norms, 1.0)
    sv = np.linalg.svd(unit, compute_uv=False)
    msgs = []
    if correlation is not None and np.all(np.isfinite(correlation)):
        for i in range(len(names)):
            for j in range(i + 1, len(names)):
                c = float(correlation[i, j])
                if abs(c) >= CORRELATION_LIMIT:
                    msgs.append(f"{names[i]} and {names[j]} cannot be separated by these data (correlation {c:+.4f}); fix one")
    elif len(names) > 1:
        cos = unit.T @ unit
        for i in range(len(names)):
            for j in range(i + 1, len(names)):
                if norms[i] > 0 and norms[j] > 0 and abs(cos[i, j]) >= CORRELATION_LIMIT:
                    msgs.append(f"{names[i]} and {names[j]} cannot be separated by these data (their effects on the residuals are "
                                f"{'parallel' if cos[i, j] > 0 else 'opposite'}: cosine {cos[i, j]:+.4f}); fix one")
    if not msgs and len(names) > 1 and sv[-1] < 1e-6 * sv[0]:
        msgs.append(f"{', '.join(names)}: the Jacobian is singular (smallest singular value {sv[-1]:.2g} of {sv[0]:.2g}): "
                    "the data cannot separate them; fix one")
    for n, zero in zip(names, zero_columns(J)):
        if zero:
            msgs.append(f"{n} is not identifiable: the data do not change with it")
    return msgs, sv


def choose_records(names: list[str], whys: list[str], jacobian, records, config, max_free: int | None = None,
                   label: str = "these records") -> Choice:
    """The candidates ``names`` (with their reasons ``whys``) that ``records`` choose: kept while the
    Jacobian at the start, ``jacobian(records, names, config)``, separates them, with one degree of
    freedom left unless every record carries its uncertainty (then absolute: no point is needed for
    the error estimate)."""
    if not names:
        return Choice(notes=[f"{label}: these records choose no input"])
    J = jacobian(records, names, config)
    if max_free is None:
        max_free = len(records) if all(r.uncertainty is not None for r in records) else max(len(records) - 1, 1)
    return choose(J, names, whys, max_free)
