"""The stepping scheme of :mod:`identification.model.stepping`, compiled with numba for the fitting models.

The tire law compiled here is :func:`identification.model.tire_law.tire_force`
itself (numba compiles the plain-Python function), and the loop performs the
reference's operations in the same order (less the products with the zeros of
the coordinates' matrix J, which add exact zeros), so the two agree to round-off
(tested ≤ 1e-12 relative).  The first call in a process compiles (a few
seconds, cached on disk afterwards).
"""

from __future__ import annotations

import types

import numpy as np

from . import tire_law
from .scheme import Trajectory
from .stepping import prepared, trajectory_from_arrays
from .tractor import TractorModel

__all__ = ["run_model", "available", "compiled_on_disk"]

def _compiled(fn, helpers: dict, inline: str = "never"):
    """`fn` compiled by numba, its calls to the module-level `helpers` (name: compiled function) resolved to
    them: the law's plain-Python functions are compiled as they stand, with no numba in :mod:`tire_law`.
    With ``inline="always"`` numba inlines it into its caller: the law into the stepping loop, where LLVM
    would not inline it by itself once it holds the bevel's code (measured: the loop 60 % slower)."""
    env = dict(fn.__globals__, **helpers)
    return njit(fastmath=False, inline=inline)(
        types.FunctionType(fn.__code__, env, fn.__name__, fn.__defaults__))


try:   # pragma: no cover - numba is a dependency; the fallback keeps the package importable without it
    import numba

    from .._compile import njit
    _bevel = _compiled(tire_law.bevel_cleat, {})
    _footprint = _compiled(tire_law.footprint_cleat, {"bevel_cleat": _bevel})
    _lug = _compiled(tire_law.lug_road, {}, "always")
    _arc = _compiled(tire_law.arc_area, {})
    _ring = _compiled(tire_law.ring_cleat, {"arc_area": _arc})
    _sink = _compiled(tire_law.static_deflection, {}, "always")
    _force = _compiled(tire_law.tire_force, {"footprint_cleat": _footprint, "lug_road": _lug, "ring_cleat": _ring,
                                             "static_deflection": _sink}, "always")
except ImportError:   # pragma: no cover
    numba = None


def available() -> bool:
    """Whether the compiled stepping is available (numba importable)."""
    return numba is not None


def _step(J, minv, zs, W, rz, rv, hx, hv, em, Q, q0, dq0, h, points, r0, r1, c0, c1):
    # the sums over J's rows run over columns r0[t] to r1[t] - 1 (those outside are zero in row t) and over its
    # columns from row c0[j] to c1[j] - 1: the products with J's zeros add exact zeros, so the sums may skip
    # them (four independent corners: J the identity, one term instead of four)
    nt, nq = J.shape
    n = rz.shape[1]
    hh, hh2 = 0.5 * h, 0.5 * h * h
    q = q0.copy()
    dq = dq0.copy()
    Z = np.empty((nt, n))
    V = np.empty((nt, n))
    F = np.empty((nt, n))
    A = np.empty((nt, n))
    jumps = np.zeros((points.size, nt, nt))
    f = np.zeros(nt)
    fs = np.zeros(nt)
    for t in range(nt):
        zt = zs[t]
        vt = 0.0
        for j in range(r0[t], r1[t]):
            zt += J[t, j] * q[j]
            vt += J[t, j] * dq[j]
        f[t] = _force(zt, vt, hx[t, 0], hv[t, 0], rz[t, 0], rv[t, 0], Q[t])
        Z[t, 0] = zt
        V[t, 0] = vt
        F[t, 0] = f[t]
    ddq = np.zeros(nq)
    for j in range(nq):
        s = 0.0
        for t in range(c0[j], c1[j]):
            s += J[t, j] * (f[t] - W[t])
        ddq[j] = minv[j] * s
    for t in range(nt):
        s = 0.0
        for j in range(r0[t], r1[t]):
            s += J[t, j] * ddq[j]
        A[t, 0] = s
    jq = np.zeros(nq)
    q1 = np.zeros(nq)
    dqp = np.zeros(nq)
    edge = 0
    for i in range(1, n):
        for j in range(nq):
            q1[j] = q[j] + h * dq[j] + hh2 * ddq[j]
            dqp[j] = dq[j] + h * ddq[j] - 0.5 * jq[j]
        any_edge = False
        for t in range(nt):
            zt = zs[t]
            vt = 0.0
            for j in range(r0[t], r1[t]):
                zt += J[t, j] * q1[j]
                vt += J[t, j] * dqp[j]
            if em[t, i]:
                any_edge = True
                fs[t] = _force(zt, vt, hx[t, i], hv[t, i], rz[t, i], 0.0, Q[t])
                f[t] = _force(zt, vt, hx[t, i], hv[t, i], rz[t, i], rv[t, i], Q[t])
            else:
                f[t] = _force(zt, vt, hx[t, i], hv[t, i], rz[t, i], rv[t, i], Q[t])
                fs[t] = f[t]
            Z[t, i] = zt
        for j in range(nq):
            jq[j] = 0.0
        if any_edge:
            for j in range(nq):
                s = 0.0
                for t in range(c0[j], c1[j]):
                    s += J[t, j] * (f[t] - fs[t])
                jq[j] = h * minv[j] * s
            for src in range(nt):
                for hub in range(nt):
                    s = 0.0
                    for j in range(r0[src], r1[src]):
                        s += J[hub, j] * (h * minv[j] * (J[src, j] * (f[src] - fs[src])))
                    jumps[edge, src, hub] = s
            edge += 1
        for j in range(nq):
            s = 0.0
            for t in range(c0[j], c1[j]):
                s += J[t, j] * (f[t] - W[t])
            dd1 = minv[j] * s
            dq[j] = dq[j] + hh * (ddq[j] + dd1)
            q[j] = q1[j]
            ddq[j] = dd1
        for t in range(nt):
            vt = 0.0
            at = 0.0
            for j in range(r0[t], r1[t]):
                vt += J[t, j] * dq[j]
                at += J[t, j] * ddq[j]
            V[t, i] = vt
            F[t, i] = f[t]
            A[t, i] = at
    return Z, V, F, A, jumps


def sparsity(J: np.ndarray) -> tuple:
    """The ranges of J's non-zero entries for :func:`_step`: per row its first and one past its last non-zero
    column, per column its first and one past its last non-zero row (an empty row or column: 0, 0)."""
    rows = np.asarray(J, dtype=float).tolist()     # a few entries: Python lists beat numpy's calls here

    def spans(lines):
        first, last = [], []
        for line in lines:
            nz = [i for i, v in enumerate(line) if v != 0.0]
            first.append(nz[0] if nz else 0)
            last.append(nz[-1] + 1 if nz else 0)
        return np.array(first, dtype=np.int64), np.array(last, dtype=np.int64)

    return (*spans(rows), *spans(list(zip(*rows))))


def drop_stale_cache(stem: str, tag: str, dependency) -> None:
    """Drop the on-disk compilations of this package's module `stem` when module `dependency` changed.

    numba keys a cached function on its own file only, so a kernel compiled
    with an older version of what it calls from another module (the tire law
    :func:`identification.model.tire_law.tire_force`, the chain's
    :func:`identification.model.acquisition.hold`) would be reused; a marker named
    ``<stem>.<tag>-<hash of the dependency's source>`` tells the versions apart.  Only where the package's
    own cache folder cannot be written (:func:`identification._compile.install_cache_locator`, one folder
    per version of the whole package's source) does numba use that ``__pycache__``.
    """
    import hashlib
    import inspect
    from pathlib import Path

    try:
        stamp = hashlib.sha256(inspect.getsource(dependency).encode()).hexdigest()[:16]
        cache = Path(__file__).with_name("__pycache__")
        marker = cache / f"{stem}.{tag}-{stamp}"
        if cache.is_dir() and not marker.exists():
            for old in list(cache.glob(f"{stem}.*.nb[ic]")) + list(cache.glob(f"{stem}.{tag}-*")):
                old.unlink(missing_ok=True)
            marker.touch()
    except OSError:   # pragma: no cover - a read-only install keeps numba's own cache logic
        pass


if numba is not None:
    drop_stale_cache("kernels", "law", tire_law)
    _step = njit(fastmath=False)(_step)


def compiled_on_disk() -> bool:
    """Whether the stepping kernel's compilation is cached on disk for this source (a first run after an
    install or a change compiles it, some seconds); True when it cannot be told."""
    if numba is None:   # pragma: no cover
        return True
    try:
        return bool(_step._cache._cache_file._load_index())   # numba keeps no public handle on its cache
    except Exception:   # pragma: no cover - another numba's internals: nothing to announce
        return True


def run_model(model: TractorModel, start_s: float, step_s: float, n: int) -> Trajectory:
    """Step the model record with the compiled kernel (plain Python if numba is missing)."""
    if numba is None:   # pragma: no cover
        from .stepping import run_model_python
        return run_model_python(model, start_s, step_s, n)
    J, mass, static_z, loads, inputs, q0, dq0 = prepared(model, start_s, step_s, n)
    J = np.ascontiguousarray(J, dtype=float)
    Z, V, F, A, jumps = _step(J, 1.0 / np.asarray(mass, dtype=float),
                              np.asarray(static_z, dtype=float), loads, inputs.road_z, inputs.road_vz,
                              inputs.hub_x, inputs.hub_vx, inputs.edge_mask, model.law_matrix(), np.asarray(q0, dtype=float),
                              np.asarray(dq0, dtype=float), float(step_s), inputs.edge_points, *sparsity(J))
    return trajectory_from_arrays(Z, V, F, A, jumps, inputs=inputs, start_s=start_s, step_s=step_s,
                                  static_z=static_z)
