"""Weighted least squares with profile-likelihood intervals: which parameter values make a rig
scenario reproduce measured data, and how well the data pin them down.

Cost. S(theta) = sum over channels c and points i of ((model - measured) / sigma_c)^2, sigma_c
the noise of channel c, estimated from the fit's own residuals (sigma_c^2 = SSE_c / n_c x
N / (N - p), re-estimated at the optimum; N points, p parameters): channels of different units
weigh by how well the model follows them. With Gaussian noise, S is -2 log-likelihood up to a
constant, so the profile-likelihood 95 % interval of a parameter is where its profile (S
minimised over the others) stays within chi2_1(0.95) = 3.84 of the minimum (Venzon & Moolgavkar
1988; Raue et al. 2009); a profile that stays below that up to a bound gives a one-sided interval.
Standard errors come from the Jacobian J of the weighted residuals at the optimum: cov =
(J^T J)^-1 (curvature of S for k alone: se = sqrt(2 / S'')); correlations from the same matrix.

k. Searched as log10 k over [:data:`THETA_LO`, :data:`THETA_HI`] (0.01 to 10^4 W/K), and at the
exact limits k = 0 (adiabatic) and k = inf (isothermal), which the model computes exactly. An
optimum at a limit is reported as that limit (not as a large finite number), with a one-sided
interval. k alone is fitted on a batched grid (every k of a grid is one column of one circuit):
a grid over the whole range, a finer one around the best point, a parabola through the lowest
three, the interval ends refined where the profile crosses the threshold.

Other keys (``circuit.pipe.zeta`` ...) are searched in log10 within a factor 100 of the
scenario's value (and the key's valid range), jointly with k by scipy.optimize.least_squares;
their profiles re-fit the others at each point and run on a sweep executor (``--jobs``, ``--dask``).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np
from scipy.optimize import least_squares

from cosim.identify.model import RigModel

K_KEY = "k_W_per_K"
THETA_LO, THETA_HI = -2.0, 4.0
#: where a joint fit starts k [W/K]: mid-range on the log scale of the paper's values (0 ... 10^4)
K_START_W_PER_K = 10.0
#: chi-square quantile, 1 degree of freedom, 95 %
CHI2_95 = 3.841458820694124
#: an interval wider than this (decades of the parameter) draws the warning that the data do
#: not identify it
WIDE_DECADES = 2.0


@dataclass
class Estimate:
    """One parameter: estimate, standard error (NaN at a limit), 95 % profile interval
    (``ci_low``/``ci_high``; 0 or inf for a one-sided one), ``limit``: '0' or 'inf' (k at a
    limit), 'bound' (a joint fit's estimate at its search bound) or ''."""

    key: str
    value: float
    se: float
    ci_low: float
    ci_high: float
    limit: str = ""

    @property
    def identifiable(self) -> bool:
        """The interval is bounded on at least one side and, if on both, narrower than WIDE_DECADES."""
        lo, hi = self.ci_low, self.ci_high
        if lo <= 0.0 or math.isinf(hi):
            return not (lo <= 0.0 and math.isinf(hi))
        return math.log10(hi / lo) <= WIDE_DECADES


@dataclass
class Profile:
    """A parameter's profile: values, S - S_min at each, the 95 % threshold."""

    key: str
    values: np.ndarray
    delta_S: np.ndarray
    threshold: float = CHI2_95


@dataclass
class Identification:
    """The result: estimates, the correlation matrix (parameters in the order of ``estimates``),
    the noise estimated per channel, the weighted cost at the optimum over N points, the model's
    predictions there (channel -> values), the profiles, warnings, model evaluations and wall time."""

    estimates: List[Estimate]
    correlation: np.ndarray
    sigma: Dict[str, float]
    cost: float
    n: int
    predicted: Dict[str, np.ndarray]
    profiles: List[Profile]
    warnings: List[str] = field(default_factory=list)
    evaluations: int = 0
    wall_s: float = 0.0


def k_of(theta: float) -> float:
    """k [W/K] of the search coordinate theta = log10 k; -inf and inf are the exact limits."""
    return 0.0 if theta == -math.inf else math.inf if theta == math.inf else 10.0 ** theta


def _sse(pred: Dict[str, np.ndarray], data) -> Dict[str, float]:
    """Per channel, the sum of squared errors of one case, scaled up over points the model could
    not give (NaN) so that candidates stay comparable."""
    out = {}
    for c, measured in data.channels.items():
        r = pred[c] - measured
        ok = np.isfinite(r)
        out[c] = float(np.sum(r[ok] ** 2) * measured.size / max(ok.sum(), 1)) if ok.any() else math.inf
    return out


def _noise(sse: Dict[str, float], data, p: int) -> Dict[str, float]:
    """sigma_c from the residuals of the best fit: sqrt(SSE_c / n_c x N / (N - p)), floored at
    1e-12 of the channel's scale (a noise-free record)."""
    N = data.n
    return {c: max(math.sqrt(sse[c] / v.size * N / max(N - p, 1)), 1e-12 * float(np.max(np.abs(v))))
            for c, v in data.channels.items()}


class _KGrid:
    """Batched evaluations of the cost against theta = log10 k (others held)."""

    def __init__(self, model: RigModel, others=()):
        self.model, self.others = model, others
        self.sse: Dict[float, Dict[str, float]] = {}
        self.pred: Dict[float, Dict[str, np.ndarray]] = {}
        self.calls = 0

    def run(self, thetas: Sequence[float]) -> None:
        new = [t for t in dict.fromkeys(float(t) for t in thetas) if t not in self.sse]
        if not new:
            return
        self.calls += 1
        pred = self.model.predict([k_of(t) for t in new], self.others)
        for i, t in enumerate(new):
            case = {c: v[i] for c, v in pred.items()}
            self.pred[t], self.sse[t] = case, _sse(case, self.model.data)

    def cost(self, sigma: Dict[str, float]) -> Tuple[np.ndarray, np.ndarray]:
        """(thetas sorted, S at each) for the noise ``sigma``."""
        ts = np.array(sorted(self.sse))
        return ts, np.array([sum(self.sse[t][c] / sigma[c] ** 2 for c in sigma) for t in ts])


def fit_k(model: RigModel, grid_points: int = 25) -> Identification:
    """k alone (see the module docstring)."""
    t0 = time.perf_counter()
    data = model.data
    g = _KGrid(model)
    g.run([-math.inf, *np.linspace(THETA_LO, THETA_HI, grid_points), math.inf])
    sigma = {c: float(np.std(v)) or 1.0 for c, v in data.channels.items()}
    for _ in range(2):                                        # noise from the best point's residuals
        ts, S = g.cost(sigma)
        sigma = _noise(g.sse[ts[int(np.argmin(S))]], data, 1)
    ts, S = g.cost(sigma)
    best = ts[int(np.argmin(S))]
    spacing = (THETA_HI - THETA_LO) / (grid_points - 1)
    if math.isfinite(best):
        g.run(np.linspace(best - spacing, best + spacing, 9))
        ts, S = g.cost(sigma)
        finite = np.isfinite(ts)
        i = int(np.argmin(np.where(finite, S, np.inf)))
        if 0 < i < len(ts) - 1 and np.all(np.isfinite(ts[i - 1:i + 2])):
            a, b, c = np.polyfit(ts[i - 1:i + 2], S[i - 1:i + 2], 2)
            best = float(np.clip(-b / (2 * a), ts[i - 1], ts[i + 1])) if a > 0 else float(ts[i])
        else:
            best = float(ts[i])
        best = _newton(g, sigma, best)
        sigma = _noise(g.sse[best], data, 1)
    ts, S = g.cost(sigma)
    S_best = float(S[ts == best][0])
    if math.isfinite(best) and (S_best > S[0] or S_best > S[-1]):
        best = float(ts[int(np.argmin(S))])                   # a limit beats the finite optimum
        S_best = float(S.min())
    limit = "0" if best == -math.inf else "inf" if best == math.inf else ""
    se, curvature = math.nan, math.nan
    if not limit:
        d = NEWTON_D
        S3 = [sum(g.sse[t][c] / sigma[c] ** 2 for c in sigma) for t in (best - d, best, best + d)]
        curvature = (S3[0] - 2 * S3[1] + S3[2]) / d ** 2
        se = k_of(best) * math.log(10) * math.sqrt(2.0 / curvature) if curvature > 0 else math.inf
    lo, hi = _interval(g, sigma, best, S_best, curvature)
    est = Estimate(K_KEY, k_of(best), float(se), float(k_of(lo)), float(k_of(hi)), limit)
    ts, S = g.cost(sigma)
    profile = Profile(K_KEY, np.array([k_of(t) for t in ts]), S - S_best)
    warnings = _warnings([est]) + _missing(g.pred[best])
    return Identification([est], np.ones((1, 1)), sigma, S_best, data.n, g.pred[best], [profile], warnings,
                          g.calls, time.perf_counter() - t0)


#: half-width of the three-point stencil of the Newton steps on S(theta) (log10 k: 2.3 % of k)
NEWTON_D = 0.01


def _newton(g: _KGrid, sigma, best: float, iterations: int = 5, tol_se: float = 0.1) -> float:
    """Newton steps on S(theta) from ``best``, each from a three-point stencil (one batch): S is
    not quadratic in theta over the coarse grid's spacing, its parabola only gets close. Stops,
    without moving, once the next step would be below ``tol_se`` standard errors of theta
    (sqrt(2 / S'')): the optimum is then known far better than the data know it."""
    d = NEWTON_D
    for _ in range(iterations):
        g.run([best - d, best, best + d])
        Sm, S0, Sp = (sum(g.sse[t][c] / sigma[c] ** 2 for c in sigma) for t in (best - d, best, best + d))
        curvature = (Sp - 2 * S0 + Sm) / d ** 2
        if curvature > 0:
            step = -0.5 * (Sp - Sm) / d / curvature
            if abs(step) < tol_se * math.sqrt(2.0 / curvature):
                break
        else:
            step = d if Sp < Sm else -d
        best = float(np.clip(best + float(np.clip(step, -4 * d, 4 * d)), THETA_LO, THETA_HI))
    g.run([best - d, best, best + d])
    return best


def _interval(g: _KGrid, sigma, best: float, S_best: float, curvature: float = math.nan,
              width: float = 1e-3, rounds: int = 4) -> Tuple[float, float]:
    """The 95 % interval in theta around ``best``: where S crosses S_best + chi2 on each side. A
    first batch at 0.8, 1 and 1.25 times the quadratic prediction sqrt(2 chi2 / S'') each side,
    then batches of four points inside each side's bracket until it is narrower than ``width``
    (1e-3 in log10 k: 0.23 % of k), the crossing interpolated linearly in its last bracket. A side
    that never crosses reaches its limit (-inf: k = 0, inf: k = inf); with the optimum at k = inf,
    a crossing between it and the grid's top is reported at the top (a conservative, wider
    interval: larger finite k need RK4 steps ~ 1/k)."""
    threshold = S_best + CHI2_95
    if math.isfinite(best) and curvature > 0:
        dq = math.sqrt(2.0 * CHI2_95 / curvature)
        g.run([best + side * f * dq for side in (-1, 1) for f in (0.8, 1.0, 1.25)])
    ends = {}
    for round_ in range(rounds + 1):
        last = round_ == rounds                               # interpolate in whatever bracket there is
        ts, S = g.cost(sigma)
        todo = []
        for side in (-1, 1):
            if side in ends:
                continue
            order = np.argsort(side * ts)
            t_side, S_side = ts[order], S[order]
            start = int(np.flatnonzero(t_side == best)[0])
            above = [j for j in range(start + 1, len(t_side)) if S_side[j] >= threshold]
            if not above:
                ends[side] = side * math.inf
                continue
            j = above[0]
            a, b = t_side[j - 1], t_side[j]
            if math.isinf(b):
                ends[side] = a
                continue
            if math.isinf(a) and a > 0:                       # from k = inf down to the grid's top: k
                ends[side] = b                                # above 10^THETA_HI costs steps ~ k; the
                continue                                      # interval is at least [10^THETA_HI, inf]
            if math.isinf(a):                                 # from k = 0 up to the grid's bottom: cheap
                a = b - 1.0
            ya, yb = S_side[j - 1] - threshold, S_side[j] - threshold
            if abs(b - a) < width or last or not np.isfinite(ya):
                ends[side] = float(a - ya * (b - a) / (yb - ya)) if np.isfinite(ya) else float(b)
            else:
                todo += list(np.linspace(a, b, 6)[1:-1])
        if not todo:
            break
        g.run(todo)
    return ends.get(-1, -math.inf), ends.get(1, math.inf)


def _missing(pred: Dict[str, np.ndarray]) -> List[str]:
    """A warning for the points the model could not give at the optimum (a periodic state that
    did not stabilise): they are left out of the cost."""
    n = max(int(np.sum(~np.isfinite(v))) for v in pred.values())
    return [f"the model gives no value at {n} point(s) (a periodic state that did not stabilise, near the pipe "
            f"resonance): left out of the fit"] if n else []


def _warnings(estimates: Sequence[Estimate]) -> List[str]:
    out = []
    for e in estimates:
        if e.ci_low <= 0.0 and math.isinf(e.ci_high):
            out.append(f"{e.key} is not identifiable from these data: its profile stays within the 95 % threshold "
                       f"from 0 to infinity (an excitation that does not cover the thermal time constant? see "
                       f"pneumorail identify --plan)")
        elif not e.identifiable:
            out.append(f"{e.key} is poorly identified: its 95 % interval {e.ci_low:.3g} ... {e.ci_high:.3g} spans "
                       f"{math.log10(e.ci_high / e.ci_low):.1f} decades")
    return out


# ------------------------------------------------------------------------- several parameters
@dataclass(frozen=True)
class Searched:
    """A key searched in log10 between ``lo`` and ``hi`` (log10 of its bounds), from ``start``."""

    key: str
    lo: float
    hi: float
    start: float


def searched(model: RigModel, keys: Sequence[str]) -> List[Searched]:
    """k over [THETA_LO, THETA_HI] from K_START_W_PER_K; any other key within a factor 100 of the
    scenario's value (its start), clipped to its valid range (cosim.scenario.schema)."""
    from cosim.identify.keys import key_value_and_range
    out = []
    for key in keys:
        if key == K_KEY:
            out.append(Searched(key, THETA_LO, THETA_HI, math.log10(K_START_W_PER_K)))
            continue
        value, lo, hi = key_value_and_range(model, key)
        out.append(Searched(key, math.log10(max(value / 100.0, lo)), math.log10(min(value * 100.0, hi)),
                            math.log10(value)))
    return out


def _split(params: Sequence[Searched], u: np.ndarray) -> Tuple[float, Tuple[Tuple[str, float], ...]]:
    k, others = 10.0 ** u[0] if params[0].key == K_KEY else None, []
    for p, ui in zip(params, u):
        if p.key != K_KEY:
            others.append((p.key, float(10.0 ** ui)))
    return k, tuple(others)


def _residuals(model: RigModel, params, u, sigma, fixed: Optional[Tuple[int, float]] = None) -> np.ndarray:
    if fixed is not None:
        u = np.insert(np.asarray(u, float), fixed[0], fixed[1])
    k, others = _split(params, u)
    base_k = k if k is not None else model.base.k_W_per_K[0]
    pred = model.predict([base_k], others)
    r = [np.nan_to_num((pred[c][0] - v) / sigma[c], nan=0.0) for c, v in model.data.channels.items()]
    return np.concatenate(r)


def fit_joint(model: RigModel, params: Sequence[Searched], executor=None) -> Identification:
    """Several keys at once (k first if fitted), by least squares from each key's start
    (:func:`searched`)."""
    t0 = time.perf_counter()
    data = model.data
    u0 = np.array([p.start for p in params])
    lo, hi = np.array([p.lo for p in params]), np.array([p.hi for p in params])
    sigma = {c: float(np.std(v)) or 1.0 for c, v in data.channels.items()}
    calls = 0
    res = None
    for _ in range(2):                                        # fit, noise from its residuals, refit
        res = least_squares(lambda u: _residuals(model, params, u, sigma), np.clip(u0, lo, hi), bounds=(lo, hi),
                            diff_step=1e-3, x_scale=1.0, xtol=1e-6, ftol=1e-10)
        calls += res.nfev + res.njev * len(params)
        r = _residuals(model, params, res.x, {c: 1.0 for c in sigma})
        sizes = [v.size for v in data.channels.values()]
        parts = np.split(r, np.cumsum(sizes)[:-1])
        sigma = _noise({c: float(np.sum(part ** 2)) for c, part in zip(data.channels, parts)}, data, len(params))
        u0 = res.x
    r = _residuals(model, params, res.x, sigma)
    S_best = float(r @ r)
    J = _jacobian(model, params, res.x, sigma)              # at the final noise estimate
    cov = np.linalg.pinv(J.T @ J)
    se_u = np.sqrt(np.diag(cov))
    corr = cov / np.outer(se_u, se_u)
    profiles, estimates = [], []
    for i, p in enumerate(params):
        prof = profile_joint(model, params, res.x, sigma, i, se_u[i], executor)
        profiles.append(prof)
        value = 10.0 ** res.x[i]
        ci = _profile_interval(prof, S_best)
        estimates.append(Estimate(p.key, value, value * math.log(10) * se_u[i], ci[0], ci[1],
                                  "bound" if min(res.x[i] - p.lo, p.hi - res.x[i]) < 1e-3 else ""))
    k, others = _split(params, res.x)
    pred = model.predict([k if k is not None else model.base.k_W_per_K[0]], others)
    return Identification(estimates, corr, sigma, S_best, data.n, {c: v[0] for c, v in pred.items()}, profiles,
                          _warnings(estimates), calls, time.perf_counter() - t0)


def _jacobian(model, params, u, sigma, d: float = 1e-3) -> np.ndarray:
    r0 = _residuals(model, params, u, sigma)
    cols = []
    for i in range(len(u)):
        du = np.array(u, float)
        du[i] += d
        cols.append((_residuals(model, params, du, sigma) - r0) / d)
    return np.stack(cols, axis=1)


def _profile_point(scenario_file, overrides, data_file, keys, sigma, index, value, start):
    """One point of a profile (a module-level function: it runs on a sweep executor): the cost
    with parameter ``index`` fixed at ``value`` (log10), the others re-fitted from ``start``."""
    from cosim.identify.data import read_measurements
    model = RigModel(scenario_file, tuple(overrides), read_measurements(data_file))
    params = searched(model, keys)
    rest = [i for i in range(len(params)) if i != index]
    if not rest:
        r = _residuals(model, params, np.array([value]), sigma)
        return float(r @ r)
    lo, hi = np.array([params[i].lo for i in rest]), np.array([params[i].hi for i in rest])
    res = least_squares(lambda u: _residuals(model, params, u, sigma, (index, value)),
                        np.clip(np.asarray(start, float), lo, hi), bounds=(lo, hi), diff_step=1e-3, xtol=1e-6)
    return float(res.fun @ res.fun)


def profile_joint(model, params, u_best, sigma, index, se, executor=None, points: int = 9) -> Profile:
    """The profile of parameter ``index`` over +- 3 standard errors (within its bounds)."""
    from cosim.sweep.executors import Serial
    p = params[index]
    span = 3.0 * se if np.isfinite(se) and se > 0 else 1.0
    grid = np.linspace(max(p.lo, u_best[index] - span), min(p.hi, u_best[index] + span), points)
    start = [u_best[i] for i in range(len(params)) if i != index]
    tasks = [(str(j), (model.scenario_file, model.overrides, model.data.file, [q.key for q in params], sigma, index,
                       float(v), start)) for j, v in enumerate(grid)]
    S = np.full(points, np.nan)
    for done in (executor or Serial()).run(_profile_point, tasks):
        if done.error is None:
            S[int(done.key)] = done.result
    r = _residuals(model, params, u_best, sigma)
    return Profile(p.key, 10.0 ** grid, S - float(r @ r))


def _profile_interval(prof: Profile, S_best: float) -> Tuple[float, float]:
    """Where the profile crosses the threshold (linear interpolation in log10); the grid's end
    where it does not (then the interval is at least that wide)."""
    x, y = np.log10(prof.values), prof.delta_S - prof.threshold
    i0 = int(np.nanargmin(prof.delta_S))
    ends = []
    for side in (-1, 1):
        end = x[0] if side < 0 else x[-1]
        j = i0
        while 0 <= j + side < len(x):
            if y[j + side] >= 0 > y[j]:
                end = x[j] + (x[j + side] - x[j]) * (-y[j]) / (y[j + side] - y[j])
                break
            j += side
        ends.append(10.0 ** end)
    return ends[0], ends[1]
