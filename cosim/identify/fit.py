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
interval. k alone is fitted on batched grids (every k of a grid is one column of one circuit): a
grid over the whole range, then a bracketed minimisation (:func:`_minimise`: batches spread inside
the bracket of the lowest point) to within 0.01 standard errors, the noise re-estimated at the
minimum and the minimum refined for it until both settle. The estimate is the least S of all the
points evaluated, so the profile reported (every point, S - S_min) is >= 0 and the interval,
where it crosses the threshold each side, holds the estimate.

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

    def S(self, theta: float, sigma: Dict[str, float]) -> float:
        """S at an evaluated theta for the noise ``sigma``."""
        return sum(self.sse[theta][c] / sigma[c] ** 2 for c in sigma)

    def cost(self, sigma: Dict[str, float]) -> Tuple[np.ndarray, np.ndarray]:
        """(thetas sorted, S at each) for the noise ``sigma``."""
        ts = np.array(sorted(self.sse))
        return ts, np.array([self.S(t, sigma) for t in ts])

    def lowest(self, sigma: Dict[str, float]) -> float:
        """The evaluated theta of least S for the noise ``sigma`` (the limits included)."""
        ts, S = self.cost(sigma)
        return float(ts[int(np.argmin(S))])


#: k values a refinement batch spreads evenly over a bracket: a batch of 32 k costs what one k
#: costs (one circuit, a column per k; the example's 60 s record: 6.0 s for 32 k, 6.2 s for one,
#: the RK4 loop's Python overhead dominating), and narrows the bracket (32 + 1) / 2 = 16.5-fold
BATCH = 32
#: the minimum is refined until the evaluated points next to the lowest one are within this many
#: standard errors of log10 k: the estimate is then within 0.01 se of the minimum, its S within
#: 1e-4 of S_min (against the interval's 3.84)
TOL_SE = 0.01
#: ... or within this in log10 k (k to 2e-9, far below what any record resolves): the end where
#: S'' is 0 at round-off, or where the minimum sits at the search range's edge
THETA_FLOOR = 1e-9
#: points each side of the vertex of the parabola through the lowest three, TOL_SE / 2 apart,
#: added to a batch: where that vertex is within 0.04 se of the minimum (S near enough a parabola
#: over the bracket), the batch brackets the minimum to TOL_SE (the even spread alone needs
#: log(bracket / (TOL_SE se)) / log 16.5 batches)
VERTEX_POINTS = 8
#: bound on the batches of one refinement (from the coarse grid's bracket of 0.5 in log10 k, the
#: even spread alone reaches THETA_FLOOR within 8)
MAX_BATCHES = 9
#: bound on the rounds of "minimum for the noise, noise from the minimum's residuals" (it settles
#: in two or three: the noise moves the minimum by far less than a standard error)
SIGMA_ROUNDS = 6
#: half-width of the three-point stencil whose second difference is S'' at the estimate, the
#: standard error's curvature (log10 k: 2.3 % of k); centred on the minimum, the odd (lopsided)
#: part of S cancels in it
CURVATURE_D = 0.01
#: bound on the passes of "minimum, curvature, interval" (a second only where a point of the
#: stencil or the interval undercuts the minimum: a second minimum close to it)
SETTLE_PASSES = 3
#: the interval's ends are interpolated linearly in a bracket narrower than this in log10 k (0.23 %
#: of k) and than INTERVAL_REL of the quadratic half-width sqrt(2 chi2 / S''): a chord across a
#: parabola puts the crossing inside it by (width / half-width)^2 / 8 of the half-width, <= 0.5 %
INTERVAL_WIDTH = 1e-3
INTERVAL_REL = 0.2
#: first guesses at each end of the interval: this many points from 0.7 to 1.3 times the quadratic
#: half-width (0.086 of it apart, inside INTERVAL_REL: a crossing among them needs no more batches)
INTERVAL_GUESSES = 8


def fit_k(model: RigModel, grid_points: int = 25) -> Identification:
    """k alone (see the module docstring)."""
    t0 = time.perf_counter()
    data = model.data
    g = _KGrid(model)
    g.run([-math.inf, *np.linspace(THETA_LO, THETA_HI, grid_points), math.inf])
    sigma = {c: float(np.std(v)) or 1.0 for c, v in data.channels.items()}
    for _ in range(2):                                        # noise from the grid's best point
        sigma = _noise(g.sse[g.lowest(sigma)], data, 1)
    best, sigma = _consistent_minimum(g, sigma, data)
    for pass_ in range(SETTLE_PASSES):
        curvature = _curvature(g, sigma, best)
        lo, hi = _interval(g, sigma, best, g.S(best, sigma), curvature)
        if g.lowest(sigma) == best or pass_ == SETTLE_PASSES - 1:
            break
        best, sigma = _consistent_minimum(g, sigma, data)    # the stencil or the interval found lower S
    S_best = g.S(best, sigma)
    limit = "0" if best == -math.inf else "inf" if best == math.inf else ""
    se = math.nan if limit else k_of(best) * math.log(10) * math.sqrt(2.0 / curvature) if curvature > 0 else math.inf
    est = Estimate(K_KEY, k_of(best), float(se), float(k_of(lo)), float(k_of(hi)), limit)
    ts, S = g.cost(sigma)
    profile = Profile(K_KEY, np.array([k_of(t) for t in ts]), S - S_best)
    warnings = _warnings([est]) + _missing(g.pred[best]) + _unsettled(profile)
    return Identification([est], np.ones((1, 1)), sigma, S_best, data.n, g.pred[best], [profile], warnings,
                          g.calls, time.perf_counter() - t0)


def _curvature(g: _KGrid, sigma, best: float) -> float:
    """S'' at ``best`` from the stencil of CURVATURE_D each side (NaN at a limit)."""
    if not math.isfinite(best):
        return math.nan
    stencil = (best - CURVATURE_D, best, best + CURVATURE_D)
    g.run(stencil)
    return _parabola(stencil, [g.S(t, sigma) for t in stencil])[0]


def _unsettled(profile: Profile) -> List[str]:
    """A warning where the profile still has points below the estimate's S (SETTLE_PASSES did
    not settle: several minima close together)."""
    below = profile.delta_S[profile.delta_S < 0]
    return [f"the estimate is not the minimum of its profile: {below.size} point(s) down to S - S_min = "
            f"{below.min():.3g} (several minima?); its interval is unreliable"] if below.size else []


def _consistent_minimum(g: _KGrid, sigma, data, rounds: int = SIGMA_ROUNDS) -> Tuple[float, Dict[str, float]]:
    """The minimum of S and the noise estimated from its residuals, each for the other (S weighs
    the channels by 1 / sigma_c^2, so the noise moves the minimum): minimise for the noise, take
    the noise from the minimum, until the minimum stays. Returns the evaluated theta of least S
    for the returned noise: whatever the rounds, the estimate is the minimum of the cost reported
    with it."""
    best = None
    for _ in range(rounds):
        theta = _minimise(g, sigma)
        if theta == best:
            break
        best, sigma = theta, _noise(g.sse[theta], data, 1)
    return g.lowest(sigma), sigma


def _minimise(g: _KGrid, sigma, batch: int = BATCH, tol_se: float = TOL_SE,
              max_batches: int = MAX_BATCHES) -> float:
    """The minimum of S(theta) for the noise ``sigma``, bracketed: the lowest evaluated point and
    its evaluated neighbours bracket a minimum. Each batch spreads ``batch`` points evenly inside
    the bracket, plus VERTEX_POINTS each side of the vertex of the parabola through the lowest
    three (a guess: it only helps if it is right), until the neighbours are within ``tol_se``
    standard errors (from the same parabola's curvature) of the lowest point. The estimate is an
    evaluated point, the least of them: no model of S's shape is trusted for it (Newton steps
    on a stencil wider than the standard error stop off the minimum where S is lopsided). A
    lowest point at a limit (k = 0 or inf) is returned as it is."""
    for _ in range(max_batches):
        ts, S = g.cost(sigma)
        i = int(np.argmin(S))
        if not math.isfinite(ts[i]):
            return float(ts[i])
        a, c = _bracket(ts, i)
        j = _around(ts, i)
        curvature, vertex = _parabola(ts[j:j + 3], S[j:j + 3])
        se = math.sqrt(2.0 / curvature) if curvature > 0 else math.inf
        if max(ts[i] - a, c - ts[i]) <= max(tol_se * se, THETA_FLOOR):
            break
        guess = vertex + 0.5 * tol_se * se * np.arange(-VERTEX_POINTS, VERTEX_POINTS + 1) if se < math.inf else []
        g.run([*np.linspace(a, c, batch + 2)[1:-1], *(t for t in guess if a < t < c)])
    return g.lowest(sigma)


def _bracket(ts: np.ndarray, i: int) -> Tuple[float, float]:
    """The finite neighbours of ``ts[i]`` in the sorted ``ts`` (``ts[i]`` itself on a side without
    one: the search range's edge)."""
    a = ts[i - 1] if i > 0 and math.isfinite(ts[i - 1]) else ts[i]
    c = ts[i + 1] if i + 1 < len(ts) and math.isfinite(ts[i + 1]) else ts[i]
    return float(a), float(c)


def _around(ts: np.ndarray, i: int) -> int:
    """The first of the three finite points of the sorted ``ts`` centred on ``ts[i]`` (the three
    nearest it at an edge)."""
    finite = np.flatnonzero(np.isfinite(ts))
    return int(np.clip(i - 1, finite[0], finite[-1] - 2))


def _parabola(x: Sequence[float], y: Sequence[float]) -> Tuple[float, float]:
    """(y'', vertex) of the parabola through three points, any spacing (NaN vertex if y'' = 0)."""
    (x0, x1, x2), (y0, y1, y2) = x, y
    f01, f12 = (y1 - y0) / (x1 - x0), (y2 - y1) / (x2 - x1)
    f012 = (f12 - f01) / (x2 - x0)
    return 2.0 * f012, (0.5 * (x0 + x1) - f01 / (2.0 * f012) if f012 != 0 else math.nan)


def _interval(g: _KGrid, sigma, best: float, S_best: float, curvature: float = math.nan,
              rounds: int = 4) -> Tuple[float, float]:
    """The 95 % interval in theta around the minimum ``best``: where S crosses S_best + chi2 on
    each side, interpolated linearly in the bracket the evaluated points give (see INTERVAL_WIDTH
    and INTERVAL_REL). A wider bracket gets a batch: the INTERVAL_GUESSES it holds, else BATCH / 2
    points evenly inside. A side that never crosses reaches its limit (-inf: k = 0, inf: k = inf);
    with the optimum at k = inf, a crossing between it and the grid's top is reported at the top
    (a conservative, wider interval: larger finite k need RK4 steps ~ 1/k)."""
    threshold = S_best + CHI2_95
    width, guesses = INTERVAL_WIDTH, np.array([])
    if math.isfinite(best) and curvature > 0:
        dq = math.sqrt(2.0 * CHI2_95 / curvature)
        width, guesses = min(width, INTERVAL_REL * dq), np.linspace(0.7, 1.3, INTERVAL_GUESSES) * dq
    ends = {}
    for round_ in range(rounds + 1):
        ts, S = g.cost(sigma)
        todo = []
        for side in (s for s in (-1, 1) if s not in ends):
            end, (a, b, ya, yb) = _crossing(ts, S - threshold, best, side)
            if end is None and (round_ == rounds or abs(b - a) < width or not np.isfinite(ya)):
                end = float(a - ya * (b - a) / (yb - ya)) if np.isfinite(ya) else b
            if end is not None:
                ends[side] = end
                continue
            inside = [best + side * q for q in guesses if min(a, b) < best + side * q < max(a, b)]
            todo += inside or list(np.linspace(a, b, BATCH // 2 + 2)[1:-1])
        if not todo:
            break
        g.run(todo)
    return ends.get(-1, -math.inf), ends.get(1, math.inf)


def _crossing(ts, y, best, side) -> Tuple[Optional[float], Tuple[float, float, float, float]]:
    """The first evaluated point where ``y`` (S - threshold) is >= 0 going from ``best`` towards
    ``side``, and the one before it: (end, (a, b, y_a, y_b)), ``end`` the interval's end where
    the points settle it (no crossing: the limit; a crossing next to k = inf: see
    :func:`_interval`), else None and the crossing's bracket, the chord through (a, y_a) and (b,
    y_b) its linear interpolation (next to k = 0, a is the grid's bottom - 1: cheap to refine)."""
    order = np.argsort(side * ts)
    t_side, y_side = ts[order], y[order]
    start = int(np.flatnonzero(t_side == best)[0])
    above = [j for j in range(start + 1, len(t_side)) if y_side[j] >= 0]
    if not above:
        return side * math.inf, (math.nan,) * 4
    a, b = float(t_side[above[0] - 1]), float(t_side[above[0]])
    bracket = (a, b, float(y_side[above[0] - 1]), float(y_side[above[0]]))
    if math.isinf(b):
        return a, bracket
    if math.isinf(a) and a > 0:     # from k = inf down to the grid's top: k above 10^THETA_HI costs
        return b, bracket           # RK4 steps ~ 1/k; the interval is at least [10^THETA_HI, inf]
    if math.isinf(a):               # from k = 0 up to the grid's bottom: cheap to refine
        return None, (b - 1.0, *bracket[1:])
    return None, bracket


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
