"""The EN 14363 twist test (paper §4.1, Figs 7-8): ΔQ/Q across heat-transfer coefficients, with
the levelling valves isolated and/or connected. Kind ``twist``, section ``twist``
(:class:`TwistTest`)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np
import xarray as xr

from cosim.engine.cases import simulate_cases
from cosim.errors import ScenarioError
from cosim.kinds.base import CarKind
from cosim.limits.checks import CaseMetrics
from cosim.limits.criteria import DQQ_LIMIT, en14363_twist_limit, static_wheel_loads, wheel_unloading, window_drift, window_mean
from cosim.results.io import Progress
from cosim.results.outcome import Computed, Outcome, warn
from cosim.results.overlay import Selection, case_series, worst_wheels
from cosim.results.plots import Curve, Figure, Panel, Span, save_panels
from cosim.runs.car import add_wheel_unloading, air_columns, bellow_panels, fault_columns, fault_figure, of_setting, per_case
from cosim.scenario.model import DEFAULT_WINDOW_S, Scenario
from cosim.scenario.schema import build, check_valve_settings, k_label
from pneumorail.quantities import Range, plausible, positive, ranged
from vehicle.params import WHEELS, VehicleParams

#: Largest track twist [per mille] a twist test may apply: three times the largest EN 14363 limit
#: (7 per mille, bases <= 4 m). Beyond it the "track" is no track: 100 per mille over a 10 m base
#: raises the rails by 1 m. (The test height is bounded as well: :data:`MAX_RAIL_LIFT_M`.)
MAX_TWIST_PER_MILLE = 21.0
#: Highest rail lift of a twist test [m]: three times the largest EN 14363 test height. The limit
#: twist times its base, (20/2a* + 2) per mille x 2a*, is 20 mm + 2 per mille x 2a*: 60 mm for the
#: longest bogie-centre distance the rule covers (20 m), plus half the bogie twist's 7 per mille x
#: 2a+ (~10 mm); 3 x 70 mm ~ 0.2 m. Beyond it a "track" lifts a wheel off any plausible test bench
#: (100 per mille over a 10 m base: 1 m).
MAX_RAIL_LIFT_M = 0.2
_TWIST = Range(0.0, MAX_TWIST_PER_MILLE, unit="per mille", why="3 x the largest EN 14363 limit; 0: untwisted reference")


@dataclass(frozen=True)
class TwistTest:
    """EN 14363 twist (Fig. 7): the rails under ``raised_wheels`` rise by the test height in
    ``ramp_s`` (smooth cosine ramp), then hold for ``hold_s``.

    Test height = twist x base. The twist limit of the track the car must negotiate depends on the
    base length 2a (here the bogie centre distance): 7 permille for 2a <= 4 m, 20/2a + 2 permille
    for 4 m < 2a <= 20 m, 3 permille above (the rule commonly quoted from EN 14363; set
    ``twist_per_mille`` to override it).

    EN 14363 twists the car over both bases together: the carbody twist g* over the bogie
    centre distance 2a* and the bogie twist g+ over the wheelbase 2a+. ``bogie_base_m`` (2a+,
    the car's wheelbase) switches the bogie twist on: the front bogie's rails on the raised side
    (``raised_wheels`` must then be that side of the front bogie, e.g. [1R, 2R]) are in addition
    twisted by h+ = g+ x 2a+ about the bogie centre, leading wheelset + h+/2, trailing - h+/2
    (``bogie_twist_per_mille``, default the EN 14363 limit for 2a+); see
    :func:`cosim.kinds.twist.rail_heights` for the track geometry. Without it: Fig. 7, the carbody twist
    alone.

    ``start_s``: the ramp starts at this time (default 0): a wait on level track, e.g. for bellows
    that a fault at t = 0 deflates to blow down and the car to settle on its emergency springs.

    ``window_s``: final window over which the quasi-static end values are averaged (default 5 s,
    or the whole hold if that is shorter); ``settle_drift``: the case counts as settled when every
    wheel's ΔQ/Q0 drifts by less than that over the final window: its mean over the final window
    differs from its mean over the window before by less (an undamped ~1 Hz sway left in the
    window moves the mean by at most 4 b / (w W) of its amplitude b).
    ``valve_settings``: run with the levelling valves isolated (false) and/or connected (true);
    null: one run as ``circuit.valves`` says.
    """

    base_m: float = field(default=10.0, metadata=ranged(positive("m", "the base length 2a*")))
    twist_per_mille: Optional[float] = field(default=None, metadata=ranged(_TWIST))
    raised_wheels: Tuple[str, ...] = field(default=("1R", "2R"), metadata=ranged(non_empty=True, unique=True))
    ramp_s: float = 5.0
    hold_s: float = 35.0
    start_s: float = field(default=0.0, metadata=plausible(0.0, 3600.0, "s", "a wait before the ramp, up to an hour"))
    bogie_base_m: Optional[float] = field(default=None, metadata=ranged(positive("m", "the wheelbase 2a+")))
    bogie_twist_per_mille: Optional[float] = field(default=None, metadata=ranged(_TWIST))
    window_s: Optional[float] = None
    settle_drift: float = field(default=1e-3, metadata=ranged(positive(why="a drift of dQ/Q0")))
    valve_settings: Optional[Tuple[bool, ...]] = None

    @property
    def twist(self) -> float:
        if self.twist_per_mille is not None:
            return self.twist_per_mille / 1000.0
        return en14363_twist_limit(self.base_m)

    @property
    def height_m(self) -> float:
        return self.twist * self.base_m

    @property
    def bogie_twist(self) -> float:
        """g+ [-]: 0 without ``bogie_base_m``."""
        if self.bogie_base_m is None:
            return 0.0
        if self.bogie_twist_per_mille is not None:
            return self.bogie_twist_per_mille / 1000.0
        return en14363_twist_limit(self.bogie_base_m)

    @property
    def bogie_height_m(self) -> float:
        """h+ = g+ x 2a+ [m]: the height difference between the front bogie's wheelsets."""
        return self.bogie_twist * (self.bogie_base_m or 0.0)

    @property
    def duration_s(self) -> float:
        return self.start_s + self.ramp_s + self.hold_s

    @property
    def window(self) -> float:
        """The final averaging window [s]."""
        return self.window_s if self.window_s is not None else min(DEFAULT_WINDOW_S, self.hold_s)


def parse(data, vehicle: VehicleParams, path: Path) -> TwistTest:
    """The ``twist`` section, checked against the car (the bases of a bogie twist are the car's)
    and for a plausible rail lift."""
    twist = build(TwistTest, data, path, ["twist"])
    for i, w in enumerate(twist.raised_wheels):
        if w not in WHEELS:
            raise ScenarioError(path, ["twist", f"raised_wheels[{i}]"], f"unknown wheel {w!r} (wheels: {', '.join(WHEELS)})")
    if twist.window_s is not None and twist.window_s > twist.hold_s:
        raise ScenarioError(path, ["twist", "window_s"], f"the final window must lie within the hold "
                                                         f"(hold_s = {twist.hold_s:g} s), got {twist.window_s:g} s")
    check_valve_settings(twist.valve_settings, path, ["twist", "valve_settings"])
    if twist.bogie_twist_per_mille is not None and twist.bogie_base_m is None:
        raise ScenarioError(path, ["twist", "bogie_twist_per_mille"], "a bogie twist needs its base: set bogie_base_m "
                                                                      "(the wheelbase 2a+)")
    if twist.bogie_base_m is not None:
        # the rails are twisted about the real wheel positions: the bases must be the car's
        for key, value, name, actual in (("bogie_base_m", twist.bogie_base_m, "vehicle.wheelbase_m", vehicle.wheelbase_m),
                                         ("base_m", twist.base_m, "vehicle.bogie_centre_distance_m",
                                          vehicle.bogie_centre_distance_m)):
            if abs(value - actual) > 1e-9 * actual:
                raise ScenarioError(path, ["twist", key], f"with a bogie twist the bases are the car's: expected "
                                                          f"{name} = {actual:g} m, got {value:g} m")
        side = twist.raised_wheels[0][-1] if twist.raised_wheels else ""
        if sorted(twist.raised_wheels) != [f"1{side}", f"2{side}"]:
            raise ScenarioError(path, ["twist", "raised_wheels"], "a bogie twist (bogie_base_m) twists one side of the "
                                                                  "front bogie: expected [1R, 2R] or [1L, 2L], got "
                                                                  f"{list(twist.raised_wheels)}")
    # Plausible test height. The twist is bounded by MAX_TWIST_PER_MILLE; the lift
    # of the highest rail, twist x base (+ half the bogie twist's height), by MAX_RAIL_LIFT_M.
    # (The bellow stroke is deliberately not the bound: a bellow driven beyond its stroke is a
    # legitimate study of divergence, which the runs diagnose.)
    lift = twist.height_m + 0.5 * twist.bogie_height_m
    if not lift <= MAX_RAIL_LIFT_M:
        if twist.bogie_base_m is not None and twist.height_m <= MAX_RAIL_LIFT_M:   # the bogie twist tips it over
            key = "bogie_twist_per_mille" if twist.bogie_twist_per_mille is not None else "bogie_base_m"
        else:
            key = "twist_per_mille" if twist.twist_per_mille is not None else "base_m"
        raise ScenarioError(path, ["twist", key], f"the rails rise by {lift * 1e3:.0f} mm (twist {twist.twist * 1e3:g} "
                                                  f"per mille x base {twist.base_m:g} m"
                                                  + (f" + half the bogie twist's {twist.bogie_height_m * 1e3:.0f} mm"
                                                     if twist.bogie_base_m is not None else "")
                                                  + f"): expected at most {MAX_RAIL_LIFT_M * 1e3:.0f} mm, three times "
                                                  f"the largest EN 14363 test height")
    return twist


def duration_s(test: TwistTest) -> float:
    """How long a case runs [s]: the ramp and the hold."""
    return test.duration_s


def valve_settings(test: TwistTest, valves: bool) -> Tuple[bool, ...]:
    """The valve settings the cases run with: ``twist.valve_settings``, else ``circuit.valves``."""
    return test.valve_settings or (valves,)


def make_car(scenario: Scenario):
    """The car standing on rails that follow the twist (picklable factory for cosim.engine.cases)."""
    from vehicle.car import MetroCar  # exudyn: imported when a car is built, not to read a scenario
    return MetroCar(scenario.vehicle, rail_height_m=rail_heights(scenario.experiment), step_s=scenario.solver.mechanics_step_s,
                    spectral_radius=scenario.solver.spectral_radius, track_structure=scenario.track,
                    payload=scenario.car_payload)


def run_settings(scenario: Scenario) -> Sequence[Optional[bool]]:
    """The runs: each of ``twist.valve_settings``, or one (None) as ``circuit.valves`` says."""
    return scenario.experiment.valve_settings or (None,)


#: wheels every twist plot shows (paper Fig. 8); the worst wheels of the run are added
PLOT_WHEELS = ("1L", "1R", "4L", "4R")


def wheelset_x_m(test: TwistTest) -> np.ndarray:
    """(4,) wheelset positions [m] along the track from the car centre, wheelsets 1..4 from the
    front, for the bases of the test (the loader checks that they are the car's)."""
    xb, a = test.base_m / 2.0, (test.bogie_base_m or 0.0) / 2.0
    return np.array([xb + a, xb - a, -xb + a, -xb - a])


def twisted_rail_m(test: TwistTest, x_m) -> np.ndarray:
    """Height [m] of the twisted rail (the raised side) at ``x_m`` along the track (from the car
    centre, forward), fully ramped, for the EN 14363 twist with bogie twist: level under the rear
    bogie (x <= x3), rising linearly to h* - h+/2 at the front bogie's trailing wheelset x2 and on,
    with the bogie twist g+, to h* + h+/2 at its leading wheelset x1 (level beyond), with
    h* = g* 2a* and h+ = g+ 2a+. The front bogie centre then lies h* above the rear one (carbody
    twist g* over 2a*), the front bogie's wheelsets differ by h+ (bogie twist g+ over 2a+), the
    rear bogie is untwisted; between the bogies the rail rises at (h* - h+/2)/(2a* - 2a+)."""
    x1, x2, x3, _ = wheelset_x_m(test)
    h, hb = test.height_m, test.bogie_height_m
    return np.interp(x_m, [x3, x2, x1], [0.0, h - 0.5 * hb, h + 0.5 * hb])


def rail_heights(test: TwistTest):
    """rail_height_m(t) -> (8,): each rail height follows its full value H times the cosine ramp
    0.5 (1 - cos(pi t / ramp)), then holds H.

    Without a bogie twist (``bogie_base_m`` null; the paper's Fig. 7): H = h* = g* 2a* under each
    of ``raised_wheels`` (1R, 2R: the front bogie's right wheels), 0 elsewhere. With it (EN 14363,
    the carbody and the bogie twist together): the raised side's rail follows
    :func:`twisted_rail_m` -- the front bogie's leading wheel at h* + h+/2, its trailing wheel at
    h* - h+/2 -- and the other side stays level. This is the test-bench form of the twisted
    track: one side raised under the front bogie, the other side and the rear bogie level; what
    the car feels is, to first order, the same as on a track whose cross-level changes by g* over
    the bogie centres and by g+ over the front bogie, with both rails moved by half of it: the
    cross-level twists the car, the mean rail height under each wheelset only heaves and pitches
    the carbody and the front bogie frame as rigid bodies (mean heights 0 under the rear bogie,
    h*/2 at the front bogie centre, +-h+/4 across it). Both twists have the same sense, so they
    add up at the leading wheel of the low side (1L for raised right rails), the wheel that
    unloads most.
    """
    raised = np.array([w in test.raised_wheels for w in WHEELS], dtype=float)
    h, ramp, start = test.height_m, test.ramp_s, test.start_s
    if test.bogie_base_m is None:
        def rail(t: float) -> np.ndarray:
            s = min(max((t - start) / ramp, 0.0), 1.0)
            return raised * (h * 0.5 * (1.0 - math.cos(math.pi * s)))
        return rail
    full = raised * np.repeat(twisted_rail_m(test, wheelset_x_m(test)), 2)

    def twisted(t: float) -> np.ndarray:
        s = min(max((t - start) / ramp, 0.0), 1.0)
        return full * (0.5 * (1.0 - math.cos(math.pi * s)))
    return twisted


def simulate(scenario: Scenario, progress: Optional[Progress] = None) -> Tuple[xr.Dataset, List[str]]:
    """Every case (k value x valve setting) of the twist scenario: the labelled time series (see
    :mod:`cosim.results.series`) with the wheel unloading ``dqq`` (ΔQ/Q0, time x wheel x case) added, and
    the divergence diagnoses."""
    ds, diagnoses = simulate_cases(scenario, run_settings(scenario), make_car, scenario.experiment.duration_s, progress)
    add_wheel_unloading(ds, column="dqq_{}")
    return ds, diagnoses


def twist_metrics(t_s: np.ndarray, dqq: np.ndarray, test: TwistTest, j: int) -> Dict[str, object]:
    """Summary of case ``j``: the dynamic maxima of ΔQ/Q0 (over the whole run), the quasi-static
    values (means over the final window), their drift (change of the window mean over one
    window, see :func:`cosim.limits.criteria.window_drift`) and whether it settled: every wheel's drift
    below ``settle_drift``."""
    d = dqq[:, :, j]                                          # (samples, 8)
    worst = np.unravel_index(np.argmax(d), d.shape)
    qs = window_mean(t_s, d, test.window)                     # (8,)
    drift = window_drift(t_s, d, test.window)                 # (8,)
    row: Dict[str, object] = {"dqq_max": float(d.max()), "dqq_max_wheel": WHEELS[worst[1]],
                              "t_dqq_max_s": float(t_s[worst[0]]),
                              "dqq_qs_max": float(qs.max()), "dqq_qs_max_wheel": WHEELS[int(np.argmax(qs))],
                              "dqq_drift": float(drift.max()), "settled": bool(drift.max() < test.settle_drift)}
    if np.isnan(d).any():           # a diverged case: no maximum, so no wheel or time to name
        row.update(dqq_max=math.nan, dqq_max_wheel="", t_dqq_max_s=math.nan)
    if np.isnan(qs).any():
        row.update(dqq_qs_max=math.nan, dqq_qs_max_wheel="")
    row.update({f"dqq_max_{w}": float(d[:, i].max()) for i, w in enumerate(WHEELS)})
    row.update({f"dqq_qs_{w}": float(qs[i]) for i, w in enumerate(WHEELS)})
    row.update({f"dqq_drift_{w}": float(drift[i]) for i, w in enumerate(WHEELS)})
    return row


def run(scenario: Scenario, progress: Progress) -> Computed:
    """The twist test: every case, its summary row (:func:`twist_metrics`, the end roll, the
    bellow temperature range) and checkable metrics."""
    test = scenario.experiment
    settings = run_settings(scenario)
    bogie = (f" + bogie twist {test.bogie_twist * 1e3:g} permille over {test.bogie_base_m:g} m "
             f"({test.bogie_height_m * 1e3:.1f} mm across the front bogie)" if test.bogie_base_m is not None else "")
    valves_text = "" if settings == (None,) else f" x valves {['on' if v else 'off' for v in settings]}"
    progress(f"twist {test.twist * 1e3:g} permille over {test.base_m:g} m -> rail raised {test.height_m * 1e3:.1f} mm under "
             f"{', '.join(test.raised_wheels)}{bogie}; {len(scenario.k_W_per_K)} k values{valves_text}, "
             f"{test.duration_s:g} s simulated")
    ds, diagnoses = simulate(scenario, progress)
    t = ds["time"].values
    dqq = ds["dqq"].transpose("time", "wheel", "case").values
    rows: List[Dict[str, object]] = []
    found: List[str] = []
    named = settings != (None,)
    for j, (k, valves) in enumerate(zip(ds["k_W_per_K"].values, ds["valves"].values)):
        k, valves = float(k), bool(valves)
        row = {"valves": valves, "k_W_per_K": k, **twist_metrics(t, dqq, test, j)}
        row["roll_carbody_mean_end_rad"] = float(window_mean(t, ds["roll_rad"].values[:, j], test.window))
        row.update(air_columns(ds.isel(case=j)))
        row.update(fault_columns(scenario, ds.isel(case=j)))
        T = ds["bellow_T_K"].isel(case=j).values
        row["T_bellow_max_K"], row["T_bellow_min_K"] = float(T.max()), float(T.min())
        rows.append(row)
        if not row["settled"]:
            where = f"valves {'on' if valves else 'off'}, " if named else ""
            warn(found, f"{where}k = {k_label(k)}: not settled, the {test.window:g} s mean of ΔQ/Q0 still moves by "
                        f"{row['dqq_drift']:.2g} from one window to the next (limit {test.settle_drift:g})")
    info = {"twist_height_m": test.height_m, "twist_per_mille": test.twist * 1e3,
            "bogie_twist_height_m": test.bogie_height_m, "bogie_twist_per_mille": test.bogie_twist * 1e3,
            "rail_heights_m": {w: float(h) for w, h in zip(WHEELS, rail_heights(test)(test.duration_s))},
            "window_s": test.window, "settle_drift": test.settle_drift,
            "Q0_N": {w: float(q) for w, q in zip(WHEELS, ds["Q0_N"].values[:, 0])} if ds.sizes["case"] else {}}
    shown = ("valves", "k_W_per_K", "dqq_max", "dqq_max_wheel", "t_dqq_max_s", "dqq_qs_max", "dqq_qs_max_wheel",
             "dqq_drift", "settled", "T_bellow_max_K")
    return Computed(rows, shown, {"twist": ds}, diagnoses=diagnoses, warnings=found, info=info)


def case_metrics(row) -> CaseMetrics:
    """A case's unloading per wheel: its largest dynamic, quasi-static and drift."""
    return CaseMetrics(row["k_W_per_K"], row["valves"],
                       wheels={m: {w: row[f"{prefix}_{w}"] for w in WHEELS} for m, prefix in
                               (("dqq_max", "dqq_max"), ("dqq_qs_max", "dqq_qs"), ("dqq_drift", "dqq_drift"))})


def _dqq_limit(scenario: Scenario) -> float:
    """The limit to draw: the scenario's own ΔQ/Q0 checks, else EN 14363's 0.6."""
    limits = [c.limit for c in scenario.checks if c.metric in ("dqq_max", "dqq_qs_max") and c.op in ("<=", "<")]
    return min(limits) if limits else DQQ_LIMIT


def plot_wheels(rows) -> List[str]:
    """Fig. 8's wheels and the worst ones of the run (largest dynamic and quasi-static ΔQ/Q0 over
    every case), in wheel order."""
    worst = set()
    for prefix in ("dqq_max_", "dqq_qs_"):
        values = {w: max((r[prefix + w] for r in rows), key=lambda v: -math.inf if math.isnan(v) else v) for w in WHEELS}
        worst.add(max(WHEELS, key=lambda w: -math.inf if math.isnan(values[w]) else values[w]))
    return [w for w in WHEELS if w in PLOT_WHEELS or w in worst]


def figures(outcome: Outcome) -> List[Figure]:
    """Per valve setting: the wheel loads (paper Fig. 8), ΔQ/Q0 with its limit, the bellows."""
    if not outcome.rows:
        return []
    test, ds = outcome.scenario.experiment, outcome.series["twist"]
    wheels = plot_wheels(outcome.rows)
    limit = _dqq_limit(outcome.scenario)
    extra = [w for w in wheels if w not in PLOT_WHEELS]
    shown = "wheelsets 1 and 4" + (f" and the worst wheel{'s' if len(extra) > 1 else ''} {', '.join(extra)}" if extra else "")
    height = f"rail raised {test.height_m * 1e3:.0f} mm" + (
        f", bogie twisted {test.bogie_height_m * 1e3:.0f} mm" if test.bogie_base_m is not None else "")
    out = []
    for setting in run_settings(outcome.scenario):
        sub = of_setting(ds, setting)
        suffix = "" if setting is None else f"_valves={'on' if setting else 'off'}"
        valves = "" if setting is None else f", valves {'connected' if setting else 'isolated'}"
        out += [Figure(f"fig8_wheel_loads{suffix}.png",
                       [Panel(per_case(sub["wheel_load_N"].sel(wheel=w), 1e-3), "time t [s]", f"wheel load Q_{w} [kN]",
                              f"wheel {w}") for w in wheels],
                       f"Vertical wheel-rail forces during the twist test, {shown} (paper Fig. 8); {height}{valves}", 2),
                Figure(f"dqq{suffix}.png",
                       [Panel(per_case(sub["dqq"].sel(wheel=w)), "time t [s]", f"ΔQ/Q0 of wheel {w} [-]", f"wheel {w}",
                              hlines=[(limit, f"limit {limit:g}")]) for w in wheels],
                       f"Wheel unloading ΔQ/Q0 (positive: unloaded){valves}", 2),
                Figure(f"bellows{suffix}.png", bellow_panels(sub), f"Bellow pressures and temperatures{valves}", 2)]
        out += fault_figure(outcome.scenario, sub, suffix, valves)
    return out + [track_figure(outcome)]


def track_figure(outcome: Outcome) -> Figure:
    """The car stands still, so along the track is along the car: the rail heights under each
    wheelset at the end of the ramp, and the quasi-static wheel unloading of each wheel at its
    wheelset's position on the car (a line per rail and case), the bogies marked."""
    test, rows = outcome.scenario.experiment, outcome.rows
    x = np.asarray(outcome.scenario.vehicle.wheelset_x_m)
    heights = rail_heights(test)(test.duration_s)
    sides = {"L": "left", "R": "right"}
    rails = [Curve(x, [1e3 * h for h, w in zip(heights, WHEELS) if w[-1] == side], f"{name} rail", "o-")
             for side, name in sides.items()]
    multi = len({r["valves"] for r in rows}) > 1
    unloading = [Curve(x, [r[f"dqq_qs_{w}"] for w in WHEELS if w[-1] == side],
                       f"{name} wheels, " + (f"valves {'on' if r['valves'] else 'off'}, " if multi else "")
                       + f"k = {k_label(r['k_W_per_K'])} W/K", "o-")
               for side, name in sides.items() for r in rows]
    bogies = [Span(x[1], x[0], "front bogie"), Span(x[3], x[2], "rear bogie")]
    limit = _dqq_limit(outcome.scenario)
    along = "position along the track from the car centre x [m] (+ forward)"
    raised = ", ".join(test.raised_wheels)
    return Figure("twist_along_track.png",
                  [Panel(rails, along, "rail height [mm]", f"rails at the end of the ramp (raised under {raised})",
                         spans=bogies),
                   Panel(unloading, along, "quasi-static ΔQ/Q0 [-] (final window mean)", "each wheel at its wheelset",
                         hlines=[(limit, f"limit {limit:g}")],
                         spans=bogies)],
                  f"The twist along the car standing on it: rail heights and wheel unloading (raised under {raised})", 2)


def record_headlines(scenario: Scenario, rec: Dict[str, np.ndarray], j: int = 0) -> Dict[str, object]:
    """Headlines of case ``j`` of raw record arrays (``CoSimulation.run``'s or the monolithic
    reference's: :mod:`cosim.verification.monolithic`): dqq_max (largest ΔQ/Q0 over wheels and
    time) and ΔQ/Q0 at the last sample per wheel (Q0 from the first sample, level track)."""
    Q = rec["wheel_load_N"][:, :, j]
    dqq = wheel_unloading(Q, static_wheel_loads(Q[0]))
    row: Dict[str, object] = {"dqq_max": float(dqq.max())}
    row.update({f"dqq_end_{w}": float(dqq[-1, i]) for i, w in enumerate(WHEELS)})
    return row


def compare(infos, out_dir: Path, select: Selection, label, window: str) -> List[Path]:
    """Overlay the wheel loads and ΔQ/Q0 of several twist runs (Fig. 8's wheels and the worst)."""
    run_dirs = [d for d, _ in infos]
    wheels = select.wheels or tuple(w for w in WHEELS if w in PLOT_WHEELS or w in worst_wheels(run_dirs))
    written = []
    for quantity, scale, unit in (("Q", 1e-3, "kN"), ("dqq", 1.0, "-")):
        panels = []
        for w in wheels:
            column = f"{quantity}_{w}{'_N' if quantity == 'Q' else ''}"
            curves = [Curve(data["t_s"], data[column] * scale, label(d, k))
                      for d in run_dirs for k, data in case_series(d, "twist_", select)]
            name = "wheel load Q" if quantity == "Q" else "ΔQ/Q0"
            panels.append(Panel(curves, "time t [s]", f"{name} of wheel {w} [{unit}]", f"wheel {w}",
                                hlines=[(DQQ_LIMIT, "EN 14363 limit")] if quantity == "dqq" else []))
        written.append(save_panels(out_dir / f"compare_{quantity}.png", panels, f"Twist test comparison{window}", ncols=2))
    return written


class TwistKind(CarKind):
    """The EN 14363 twist test (paper §4.1)."""

    name, section, experiment = "twist", "twist", TwistTest
    check_metrics = ("dqq_max", "dqq_qs_max", "dqq_drift")
    wheel_metrics = ("dqq_max", "dqq_qs_max", "dqq_drift")
    # the dynamic and quasi-static unloading, largest and per wheel
    headline_metrics = ("dqq_max", "dqq_qs_max", *(f"dqq_max_{w}" for w in WHEELS), *(f"dqq_qs_{w}" for w in WHEELS))
    total_metrics = ("dqq_max", "dqq_qs_max", "dqq_drift")
    plot_metrics = ("dqq_max", "dqq_qs_max")

    case_metrics = staticmethod(case_metrics)
    parse = staticmethod(parse)
    duration_s = staticmethod(duration_s)
    valve_settings = staticmethod(valve_settings)
    make_car = staticmethod(make_car)
    run = staticmethod(run)
    figures = staticmethod(figures)
    compare = staticmethod(compare)


KIND = TwistKind()
