"""The finite-difference Jacobian of a joint fit, with the parameters of independent tires moved together.

Without a body (four corners) each tire's parameters move its own channel only: the stepping of one tire
never reads another's state, and each channel is sensed and low-passed on its own.  The columns of
k_FL, k_FR, k_RL and k_RR can then be differenced from one model run with all four moved (Curtis, Powell
and Reid's grouping, as ``scipy.optimize.approx_derivative`` does with a sparsity pattern): each
channel's change is its own tire's.  The steps, differences and quotients are those of
``scipy.optimize.least_squares``' forward differences (``diff_step``), so the Jacobian, and the fit, are
the same to the last bit, from fewer model runs.

Parameters shared by channels (the arrival, the stagger and delay, which move edges on the common
grid; a law's exponent or friction) keep a column of their own over every channel.
"""

from __future__ import annotations

import numpy as np

from ..recording import FRONT_TIRES
from ..model.fitting import BODY_EFFECTS, TractorFitModel

__all__ = ["channel_dependence", "column_groups", "forward_steps", "GroupedJacobian"]

#: The value `fit_tractor`'s residual returns where the model cannot be run.
FAILED = 1e6


def channel_dependence(model: TractorFitModel, free) -> np.ndarray | None:
    """``(channels, parameters)`` booleans: the channels each free parameter moves; None when a body couples
    the tires (every channel depends on every parameter)."""
    if any(e in model.effects for e in BODY_EFFECTS):
        return None
    channels = model.problem.channels
    out = np.ones((len(channels), len(free)), dtype=bool)
    for j, name in enumerate(free):
        suffix = name.rsplit("_", 1)[-1] if "_" in name else ""
        if suffix in channels:
            out[:, j] = [c == suffix for c in channels]
        elif suffix in ("front", "rear"):
            out[:, j] = [(c in FRONT_TIRES) == (suffix == "front") for c in channels]
    return out


def column_groups(dependence: np.ndarray) -> list[list[int]]:
    """Columns in groups of disjoint channel sets (greedy, in column order)."""
    groups, used = [], []
    for j in range(dependence.shape[1]):
        for g, mask in zip(groups, used):
            if not np.any(mask & dependence[:, j]):
                g.append(j)
                mask |= dependence[:, j]
                break
        else:
            groups.append([j])
            used.append(dependence[:, j].copy())
    return groups


def forward_steps(diff_step, x0: np.ndarray) -> np.ndarray:
    """The absolute forward-difference steps of ``least_squares(..., diff_step=diff_step)``: ``diff_step * |x|``
    with the sign of x (+ at 0), and where that step vanishes, √eps · max(1, |x|)."""
    sign = (x0 >= 0).astype(float) * 2 - 1
    h = diff_step * sign * np.abs(x0)
    return np.where(((x0 + h) - x0) == 0, np.finfo(float).eps ** 0.5 * sign * np.maximum(1.0, np.abs(x0)), h)


class GroupedJacobian:
    """``jac(x)`` for ``least_squares`` over `residual` (whose value at x it takes from :meth:`value`).

    Parameters
    ----------
    residual : callable
        x -> stacked residual, channel blocks of `rows` rows each.
    diff_step : ndarray
        Relative steps, as ``least_squares``' `diff_step`.
    dependence : ndarray
        :func:`channel_dependence`.
    rows : int
        Rows per channel.
    """

    def __init__(self, residual, diff_step, dependence: np.ndarray, rows: int):
        self.residual, self.diff_step, self.rows = residual, np.asarray(diff_step, dtype=float), rows
        self.dependence = dependence
        self.groups = column_groups(dependence)
        self._last = (None, None)

    def value(self, x) -> np.ndarray:
        """The residual at x (the last one is kept for the Jacobian there)."""
        x = np.asarray(x, dtype=float)
        f = self.residual(x)
        self._last = (x.copy(), f)
        return f

    def _f0(self, x):
        kept, f = self._last
        if kept is not None and np.array_equal(kept, x):
            return f
        return self.value(x)

    def _row_mask(self, j: int) -> np.ndarray:
        return np.repeat(self.dependence[:, j], self.rows)

    def __call__(self, x) -> np.ndarray:
        x0 = np.asarray(x, dtype=float)
        f0 = self._f0(x0)
        h = forward_steps(self.diff_step, x0)
        jac = np.zeros((f0.size, x0.size))
        for group in self.groups:
            x1 = np.copy(x0)
            x1[group] = x0[group] + h[group]
            f1 = self.residual(x1)
            if len(group) > 1 and np.any(f1 == FAILED):   # a failed run: each column on its own
                for j in group:
                    xj = np.copy(x0)
                    xj[j] = x0[j] + h[j]
                    jac[:, j] = (self.residual(xj) - f0) / ((x0[j] + h[j]) - x0[j])
                continue
            df = f1 - f0
            for j in group:
                rows = self._row_mask(j)
                jac[rows, j] = df[rows] / ((x0[j] + h[j]) - x0[j])
        return jac
