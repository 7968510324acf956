"""Running stability (kind ``stability``, section ``stability``, :class:`StabilityTest`): the car with
wheel-rail contact on straight, ideal track, linearised together with its air circuit about steady
running (:mod:`cosim.stability`), at a list of speeds, for each k and valve setting.

Per case (k x valve setting x airspring model) a summary row: the linear critical speed (where
the least damped mode's damping ratio crosses zero, bisection to ``resolution_m_per_s``), the mode
that loses its damping and its frequency there, the least damping ratio over the speeds, and the
carbody modes' frequencies and damping ratios at ``reference_speed_m_per_s``. Two airspring
models: ``circuit`` (the air's states in the eigenvalue problem) and ``static`` (each airspring a
spring of its static stiffness, the usual reduced model; its k decides isothermal or adiabatic).
The table ``modes.csv`` lists every mode below ``max_frequency_Hz`` at every speed. Figures: the
root locus with speed as the parameter and the damping ratio of each mode family against speed.

The wheel-rail contact: the S1002 / UIC60 1:40 table (default), a cone of ``equivalent_conicity``
on knife-edge rails (:meth:`~vehicle.wheelrail.geometry.ContactTable.cone`), or ``wheel_profile``, a
wheel profile file (SIMPACK .prw or two columns) on the UIC60 rail, the table derived as for the
default pair. The car free on its suspension (default), or its carbody held (with one bogie or
both): the Cooperrider configuration of running-stability studies.
"""
from __future__ import annotations

import dataclasses
import functools
import hashlib
import math
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from cosim.errors import ScenarioError
from cosim.kinds.base import CarKind
from cosim.limits.checks import CaseMetrics
from cosim.results.io import Progress, atomic_write
from cosim.results.outcome import Computed, Outcome, warn
from cosim.results.plots import Curve, Figure, Panel, k_legend
from cosim.scenario.model import Scenario
from cosim.scenario.schema import build, check_valve_settings
from pneumorail.quantities import Range, plausible, positive, ranged
from vehicle.params import TABLE_SMOOTHING, ContactParams, VehicleParams

#: the carbody's modes reported per case, as the mode labels name them
BODY_MODES = ("carbody bounce", "carbody pitch", "carbody yaw", "carbody lower sway", "carbody upper sway")
#: the carbody of a stability analysis: free on its suspension, or held (the Cooperrider
#: configuration: running at constant speed without lateral, roll or yaw motion)
HELD = ("free", "held")
#: the bogies that run free: both, or the front one alone (the rear one held; with the carbody held)
BOGIES = ("both", "front")
#: a cone's contact angles: atan(lambda) and the roll (tilted), or 0 (level: an experiment,
#: :meth:`vehicle.wheelrail.geometry.ContactTable.cone`)
CONE_CONTACT = ("tilted", "level")
#: airspring models of a case: the air in the eigenvalue problem, or each airspring its static stiffness
AIRSPRINGS = ("circuit", "static")
#: the brute force's growth rate is fitted to the peaks up to this many times the disturbance: small
#: motion, before the flange or creep saturation bends it into a limit cycle
SMALL_AMPLITUDE_FACTOR = 4.0
#: the frequency at which the static stiffness is read [rad/s]: far below every thermal and flow
#: time constant of the circuits (hours), far above the neutral air-mass mode (0)
STATIC_OMEGA_RAD_PER_S = 1e-6


#: ranges of :class:`StabilityTest`'s fields (metadata): a speed the scan may report at, and a
#: lateral offset of the wheelsets inside the flangeway
_SPEED = plausible(0.0, 150.0, "m/s", low_inclusive=False)
#: an equivalent conicity (a cone's: ``conicity`` or ``equivalent_conicity``)
_CONICITY = plausible(0.0, 0.8, "", "equivalent conicities of wheels in service: 0.01-0.6", low_inclusive=False)
_DISTURBANCE = Range(0.0, 0.008, False, True, "m", "a lateral offset inside the flangeway (~8 mm)")


@dataclass(frozen=True)
class StabilityTest:
    """Linear running stability on straight, ideal track at each of ``speeds_m_per_s``.
    ``resolution_m_per_s``: the bisection's final bracket of the critical speed.
    ``reference_speed_m_per_s``: where the carbody modes are reported (default: the first speed).
    ``max_frequency_Hz``: modes above it (the wheelsets on their contacts, ~30-300 Hz) are left
    out of ``modes.csv`` and the figures, not out of the critical speed. ``equivalent_conicity``
    (a cone on knife-edge rails at +-contact_spacing_m/2 whose rolling radii differ by 2 lambda y:
    the equivalent conicity, not the cone's slope; ``conicity`` is its older name and means the
    same) or ``wheel_profile`` (a file, relative to the scenario, on the UIC60 rail): the
    wheel-rail pair instead of S1002 / UIC60 1:40. ``contact_smoothing_mm``: the contact table's
    smoothing (null: 0.1 mm). ``valve_settings``: as a curve's.

    The Cooperrider configuration (docs/validation.md): ``carbody: held`` runs the carbody at
    constant speed without lateral, roll or yaw motion (vertical and pitch stay on the
    airsprings); ``bogies: front`` holds the rear bogie too (its frame without lateral, roll and
    yaw motion, its wheelsets without lateral and yaw motion; needs the carbody held). ``f11_N``,
    ``f22_N``, ``f23_N_m``, ``f33_N_m2``: Kalker's linear creep coefficients per wheel given (all
    four or none; the same at every normal force), instead of the contact law's (Hertz ellipse,
    Kalker's table, scaled with the load). Experiments, to switch one term off: ``frame_roll:
    held`` (the frames without roll), ``roll_rate_creepage: false`` (the lateral creepage without
    r roll'/V), ``cone_contact: level`` (the cone's contact angles 0: no gravitational stiffness,
    spin creepage or lateral share of the load transfer), ``friction_coefficient`` (null: 0.36;
    large: the steady creep forces off saturation).

    Brute force (the nonlinear critical speed; none without ``nonlinear_speeds_m_per_s``): at
    each of those speeds and for each of ``disturbances_m`` (every wheelset released at that
    lateral offset, at rest), a co-simulated run of ``nonlinear_s`` on the contact; the car hunts
    when the leading wheelset's oscillation is still there at the end (its amplitude over the last
    second, the bifurcation diagram's point, at least half the disturbance); the growth rate of its
    small oscillation places the onset between the speeds.

    Ramp-down (none without ``ramp_from_m_per_s``): the car released at ``ramp_disturbance_m``
    runs ``ramp_hold_s`` at ``ramp_from_m_per_s`` (above the critical speed: it settles on its
    hunting limit cycle), then slows down at each of ``ramp_decelerations_m_per_s2`` (halve it to
    show the result does not depend on it) to ``ramp_to_m_per_s``; the speed at which the limit
    cycle dies is where the leading wheelset's amplitude falls below 5 % of the limit cycle's at the
    start speed (it collapses there, or has faded into the decay of a stable car)."""

    speeds_m_per_s: Tuple[float, ...] = field(default=tuple(float(v) for v in range(5, 101, 5)), metadata=plausible(
        0.0, 150.0, "m/s", "540 km/h at most (a bogie on a low conicity hunts above service speeds, "
        "scenarios/cooperrider.yaml); > 0 (creepages are relative to V)", low_inclusive=False, non_empty=True, unique=True))
    resolution_m_per_s: float = field(default=0.1, metadata=plausible(1e-3, 10.0, "m/s", "the bisection's final bracket"))
    reference_speed_m_per_s: Optional[float] = field(default=None, metadata=_SPEED)
    max_frequency_Hz: float = field(default=20.0, metadata=ranged(positive("Hz")))
    conicity: Optional[float] = field(default=None, metadata=_CONICITY)
    equivalent_conicity: Optional[float] = field(default=None, metadata=_CONICITY)
    wheel_profile: Optional[str] = None
    contact_smoothing_mm: Optional[float] = field(default=None, metadata=TABLE_SMOOTHING)
    carbody: str = "free"
    bogies: str = "both"
    frame_roll: str = "free"
    roll_rate_creepage: bool = True
    cone_contact: str = "tilted"
    friction_coefficient: Optional[float] = field(default=None, metadata=plausible(
        0.0, 100.0, "", "0.36 by default; a large value keeps the steady creep forces off saturation (an experiment)",
        low_inclusive=False))
    f11_N: Optional[float] = field(default=None, metadata=plausible(
        0.0, 1e9, "N", "Kalker's f11 of a wheel: ~1e7 N under ~60 kN", low_inclusive=False))
    f22_N: Optional[float] = field(default=None, metadata=plausible(
        0.0, 1e9, "N", "Kalker's f22 of a wheel: ~1e7 N under ~60 kN", low_inclusive=False))
    f23_N_m: Optional[float] = field(default=None, metadata=plausible(
        0.0, 1e7, "N m", "Kalker's f23 of a wheel: ~1e4-1e5 N m; 0: no spin creep force"))
    f33_N_m2: Optional[float] = field(default=None, metadata=plausible(
        0.0, 1e6, "N m^2", "Kalker's f33 of a wheel: ~10-1e3 N m^2; 0: no spin moment"))
    valve_settings: Tuple[bool, ...] = field(default=(False,), metadata=ranged(non_empty=True, unique=True))
    nonlinear_speeds_m_per_s: Tuple[float, ...] = field(default=(), metadata=plausible(
        0.0, 100.0, "m/s", "360 km/h at most", low_inclusive=False, unique=True))
    disturbances_m: Tuple[float, ...] = field(default=(0.0005,), metadata=ranged(_DISTURBANCE, non_empty=True, unique=True))
    nonlinear_s: float = field(default=10.0, metadata=plausible(1.0, 600.0, "s", "long enough for several hunting cycles"))
    ramp_from_m_per_s: Optional[float] = field(default=None, metadata=plausible(
        0.0, 100.0, "m/s", "360 km/h at most", low_inclusive=False))
    ramp_to_m_per_s: float = field(default=20.0, metadata=plausible(
        0.0, 100.0, "m/s", "> 0: the creepages are relative to the speed", low_inclusive=False))
    ramp_decelerations_m_per_s2: Tuple[float, ...] = field(default=(0.2, 0.1), metadata=plausible(
        1e-3, 2.0, "m/s^2", "slow: the limit cycle must follow the speed", non_empty=True, unique=True))
    ramp_hold_s: float = field(default=5.0, metadata=plausible(
        1.0, 600.0, "s", "the time to settle on the limit cycle; its last second gives the limit cycle's amplitude"))
    ramp_disturbance_m: float = field(default=0.003, metadata=ranged(_DISTURBANCE))

    def ramp_duration_s(self, deceleration_m_per_s2: float) -> float:
        """How long a ramp-down at that deceleration runs [s]."""
        return self.ramp_hold_s + (self.ramp_from_m_per_s - self.ramp_to_m_per_s) / deceleration_m_per_s2

    @property
    def cone(self) -> Optional[float]:
        """The cone's equivalent conicity (``equivalent_conicity``, or ``conicity``, its older
        name), None: no cone."""
        return self.equivalent_conicity if self.equivalent_conicity is not None else self.conicity

    @property
    def creep_coefficients(self) -> Tuple[float, ...]:
        """(f11, f22, f23, f33) given, () = from the contact law."""
        given = (self.f11_N, self.f22_N, self.f23_N_m, self.f33_N_m2)
        return () if self.f11_N is None else tuple(float(f) for f in given)

    @property
    def held(self) -> Tuple[str, ...]:
        """What the car holds (:data:`vehicle.car.options.HOLDS`)."""
        return ((("carbody",) if self.carbody == "held" else ()) + (("rear bogie",) if self.bogies == "front" else ())
                + (("bogie roll",) if self.frame_roll == "held" else ()))

    @property
    def reference_speed(self) -> float:
        return self.reference_speed_m_per_s if self.reference_speed_m_per_s is not None else self.speeds_m_per_s[0]


def parse(data, vehicle: VehicleParams, path: Path) -> StabilityTest:
    test = build(StabilityTest, data, path, ["stability"])
    check_valve_settings(test.valve_settings, path, ["stability", "valve_settings"])
    if test.conicity is not None and test.equivalent_conicity is not None:
        raise ScenarioError(path, ["stability", "conicity"], "conicity is the older name of equivalent_conicity: "
                                                              "give one of them")
    if test.cone is not None and test.wheel_profile is not None:
        raise ScenarioError(path, ["stability", "wheel_profile"], "give either equivalent_conicity (a cone) or "
                                                                   "wheel_profile (a profile file), not both")
    for key, allowed in (("carbody", HELD), ("bogies", BOGIES), ("frame_roll", HELD), ("cone_contact", CONE_CONTACT)):
        if getattr(test, key) not in allowed:
            raise ScenarioError(path, ["stability", key], f"expected one of {', '.join(allowed)}, got "
                                                          f"{getattr(test, key)!r}")
    if test.cone_contact != "tilted" and test.cone is None:
        raise ScenarioError(path, ["stability", "cone_contact"], "a cone's contact angles: give equivalent_conicity")
    if test.bogies == "front" and test.carbody != "held":
        raise ScenarioError(path, ["stability", "bogies"], "one bogie alone needs the carbody held (carbody: held): "
                                                            "a free carbody couples the two bogies")
    creep = (test.f11_N, test.f22_N, test.f23_N_m, test.f33_N_m2)
    if any(f is not None for f in creep) and any(f is None for f in creep):
        raise ScenarioError(path, ["stability", "f11_N"], "give all four creep coefficients (f11_N, f22_N, f23_N_m, "
                                                           "f33_N_m2; 0 switches a term off) or none (from the "
                                                           "contact law)")
    if test.ramp_from_m_per_s is not None and not test.ramp_to_m_per_s < test.ramp_from_m_per_s:
        raise ScenarioError(path, ["stability", "ramp_to_m_per_s"], f"the ramp slows down: expected below "
                                                                     f"ramp_from_m_per_s ({test.ramp_from_m_per_s:g} "
                                                                     f"m/s), got {test.ramp_to_m_per_s:g}")
    if test.wheel_profile is not None:
        file = Path(path).parent / test.wheel_profile
        if not file.is_file():
            raise ScenarioError(path, ["stability", "wheel_profile"], f"the wheel profile {str(file)!r} does not exist")
        _read_wheel_profile(file, path)
        test = dataclasses.replace(test, wheel_profile=str(file))
    return test


def _read_wheel_profile(file: Path, path: Path) -> None:
    """Read the wheel profile now, as the run will (garbage, a profile in metres or a rail profile
    refused at load, not after the run started), the error at its key."""
    from vehicle.wheelrail.profiles import read_profile
    try:
        read_profile(file, "wheel")
    except ValueError as exc:                      # InputError among them: the profile file named
        raise ScenarioError(path, ["stability", "wheel_profile"], f"cannot use the wheel profile: {exc}") from None


def _run_durations_s(test: StabilityTest) -> List[float]:
    """The durations of the time-domain runs (brute force, each ramp-down)."""
    runs = [test.nonlinear_s] if test.nonlinear_speeds_m_per_s else []
    if test.ramp_from_m_per_s is not None:
        runs += [test.ramp_duration_s(a) for a in test.ramp_decelerations_m_per_s2]
    return runs


def duration_s(test: StabilityTest) -> float:
    """The longest time-domain run; without one the analysis integrates nothing (a nominal second,
    so that the solver's steps pass their checks)."""
    return max(_run_durations_s(test), default=1.0)


def shortest_duration_s(test: StabilityTest) -> float:
    """The shortest time-domain run (faults must happen within every run)."""
    return min(_run_durations_s(test), default=1.0)


def valve_settings(test: StabilityTest, valves: bool) -> Tuple[bool, ...]:
    return test.valve_settings


def extra_files(test: StabilityTest) -> Tuple[Path, ...]:
    return (Path(test.wheel_profile),) if test.wheel_profile else ()


def refuse_payload(test: StabilityTest) -> Optional[str]:
    """A stability analysis linearises the car about steady running: passengers boarding over
    time have no place in it. Refused rather than ignored."""
    return ("a stability analysis linearises the car about steady running and does not honour payload events; "
            "give the loaded car's carbody as vehicle.carbody_mass_kg (and its inertias), or run the loaded car on "
            "track (kind curve_entry or ride)")


def refuse_faults(test: StabilityTest) -> Optional[str]:
    """A stability analysis linearises the intact car and circuit about steady running: a fault
    (an event in time) has no place in it, and a brute force or ramp-down with one would be judged
    against the intact car's linear critical speed. Refused rather than ignored (it had been run
    as the intact car, its rows labelled with the fault)."""
    return ("a stability analysis linearises the intact car and circuit about steady running and does not "
            "honour faults; run the faulted car on track (kind curve_entry or ride) instead")


def refuse_imported_circuit(test: StabilityTest) -> Optional[str]:
    """A stability analysis linearises the circuit's equations, which an FMU does not give."""
    return ("a stability analysis linearises the circuit's own equations, which an FMU does not give (no "
            "directional derivatives); run the car with the FMU on track (kind curve_entry or ride) instead")


def refuse_check(metric: str, test: StabilityTest) -> Optional[str]:
    if metric == "nonlinear_critical_speed_m_per_s" and not test.nonlinear_speeds_m_per_s \
            and test.ramp_from_m_per_s is None:
        return ("the scenario runs no time-domain analysis: give stability.ramp_from_m_per_s (a ramp-down) or "
                "stability.nonlinear_speeds_m_per_s (brute force)")
    return None


def refuse_limit(metric: str, op: str, limit: float, test: StabilityTest) -> Optional[str]:
    """A lower limit on the critical speed above the scan's last speed cannot be shown (a car stable
    over the whole scan reports inf, which would pass it)."""
    last = max(*test.speeds_m_per_s, test.reference_speed)
    if metric.endswith("critical_speed_m_per_s") and op in (">=", ">") and limit > last:
        return (f"the scan ends at {last:g} m/s (stability.speeds_m_per_s): a critical speed above it cannot be "
                f"shown; extend the speeds to {limit:g} m/s or beyond")
    return None


def contact_table_csv(test: StabilityTest, vehicle: VehicleParams) -> str:
    """The contact table the test asks for, as a CSV file (kept in the temporary folder under its
    content's hash); "" for the default S1002 / UIC60 table. Derived once per process and input
    (every car of a run asks for it; a wheel profile's table takes ~1.5 s to derive)."""
    if test.cone is None and test.wheel_profile is None:
        return ""
    profile = test.wheel_profile
    stamp = os.stat(profile).st_mtime_ns if profile is not None else None   # a profile edited since: anew
    return _table_file(test.cone, profile, stamp, float(vehicle.wheel_radius_m), 0.5 * float(vehicle.contact_spacing_m),
                       test.cone_contact == "level")


@functools.lru_cache(maxsize=16)
def _table_file(conicity: Optional[float], wheel_profile: Optional[str], _stamp, r0: float, e: float,
                level: bool = False) -> str:
    """A cone's table: knife-edge rails at +-e, the car's contact spacing / 2 (0.75 m for the metro
    car, the cone's default); ``level``: its contact angles 0 (an experiment)."""
    from vehicle.wheelrail.derive_table import derive_default  # exudyn-free, but heavy
    from vehicle.wheelrail.geometry import ContactTable
    table = (ContactTable.cone(conicity, r0_m=r0, half_spacing_m=e, level_contact=level) if conicity is not None
             else derive_default(r0, wheel_file=wheel_profile))
    text = table.to_csv()
    file = Path(tempfile.gettempdir()) / "pneumorail_tables" / f"{hashlib.sha256(text.encode()).hexdigest()[:16]}.csv"
    if not file.exists():                                  # whole or not at all (a killed write leaves no table)
        with atomic_write(file) as fh:
            fh.write(text)
    return str(file)


def contact_params(test: StabilityTest, vehicle: VehicleParams) -> ContactParams:
    given = {} if test.contact_smoothing_mm is None else {"table_smoothing_mm": test.contact_smoothing_mm}
    if test.friction_coefficient is not None:
        given["friction_coefficient"] = test.friction_coefficient
    return ContactParams(table_csv=contact_table_csv(test, vehicle), creep_coefficients=test.creep_coefficients,
                         roll_rate_creepage=test.roll_rate_creepage, **given)


def make_car(scenario: Scenario, speed_m_per_s: Optional[float] = None, contact: Optional[ContactParams] = None):
    """The car running on straight, ideal track with wheel-rail contact at ``speed_m_per_s``
    (default: the first speed)."""
    from vehicle.car import MetroCar  # exudyn: imported when a car is built, not to read a scenario
    test = scenario.experiment
    v = test.speeds_m_per_s[0] if speed_m_per_s is None else speed_m_per_s
    return MetroCar(scenario.vehicle, step_s=scenario.solver.mechanics_step_s, speed_m_per_s=float(v),
                    guidance="contact", contact=contact or contact_params(test, scenario.vehicle),
                    track_structure=scenario.track, held=test.held)


def disturbed_car(scenario: Scenario):
    """The car of a brute-force run (picklable factory for :mod:`cosim.engine.cases`): running at the
    scenario's first nonlinear speed, every wheelset released at its first disturbance."""
    from vehicle.car import MetroCar
    test = scenario.experiment
    return MetroCar(scenario.vehicle, step_s=scenario.solver.mechanics_step_s,
                    speed_m_per_s=test.nonlinear_speeds_m_per_s[0], guidance="contact",
                    contact=contact_params(test, scenario.vehicle), track_structure=scenario.track,
                    spectral_radius=scenario.solver.spectral_radius,
                    wheelset_lateral_offset_m=[test.disturbances_m[0]] * 4, held=test.held)


def ramping_car(scenario: Scenario):
    """The car of a ramp-down (picklable factory for :mod:`cosim.engine.cases`): released at the ramp's
    disturbance, held at its start speed, then slowing at the first of its decelerations."""
    from vehicle.car import MetroCar
    test = scenario.experiment
    return MetroCar(scenario.vehicle, step_s=scenario.solver.mechanics_step_s,
                    speed_m_per_s=test.ramp_from_m_per_s, guidance="contact",
                    contact=contact_params(test, scenario.vehicle), track_structure=scenario.track,
                    spectral_radius=scenario.solver.spectral_radius,
                    wheelset_lateral_offset_m=[test.ramp_disturbance_m] * 4,
                    deceleration=(test.ramp_hold_s, test.ramp_decelerations_m_per_s2[0]), held=test.held)


def static_stiffness_N_per_m(air) -> np.ndarray:
    """The airsprings' static stiffness matrix [N/m] from the circuit's linearisation (bellow i's
    force per metre of bellow j's crushing): the real part of the dynamic stiffness
    G_z + G_x (i w - A)^-1 (B_z + i w B_zd) at w = :data:`STATIC_OMEGA_RAD_PER_S` (isothermal for
    k > 0, adiabatic for k = 0, with whatever volume stays connected; off the diagonal where
    bellows share their air)."""
    w = STATIC_OMEGA_RAD_PER_S
    n = air.A.shape[0]
    return np.real(air.G_z + air.G_x @ np.linalg.solve(1j * w * np.eye(n) - air.A, air.B_z + 1j * w * air.B_zd))


class _Cars:
    """The car's linearisation at each speed, computed once (it does not depend on k)."""

    def __init__(self, scenario: Scenario, F0, K_b, contact: ContactParams, rail_inputs: bool = False):
        self.scenario, self.F0, self.K_b, self.contact = scenario, F0, np.asarray(K_b, float), contact
        self.rail_inputs = rail_inputs                    # linearise_car's: a ride's level response needs them
        self._done: Dict[float, object] = {}

    def __call__(self, v: float):
        from vehicle.car.linear import linearise_car
        key = round(float(v), 9)
        if key not in self._done:
            car = make_car(self.scenario, key, self.contact)
            self._done[key] = linearise_car(car, self.F0, self.K_b, self.rail_inputs)
        return self._done[key]


def _air(scenario: Scenario, valves: bool, k: float, F0):
    """The circuit of one k and valve setting, linearised about the static state."""
    from pneumatics.layouts import static_pressures
    from pneumatics.linear import linearise_circuit
    variant = scenario.with_valves(valves)
    circuit = variant.circuit.compile(k)
    x0 = circuit.initial_state(static_pressures(variant.circuit.components(), F0, circuit.atmosphere.p_Pa))
    return linearise_circuit(circuit, x0)


def _body_columns(modes) -> Dict[str, float]:
    """Frequency and damping ratio of each carbody mode (the least damped of each label)."""
    out = {}
    for name in BODY_MODES:
        found = [m for m in modes if m.label == name]
        key = name.replace("carbody ", "").replace(" ", "_")
        m = min(found, key=lambda m: m.damping_ratio) if found else None
        out[f"f_{key}_Hz"] = m.frequency_Hz if m else math.nan
        out[f"zeta_{key}"] = m.damping_ratio if m else math.nan
    return out


def run(scenario: Scenario, progress: Progress) -> Computed:
    """The linear analysis (:func:`_linear_rows`), the time-domain ones the scenario asks for
    (:func:`_time_domain`), the verdict of each row (:func:`verdict_columns`)."""
    test = scenario.experiment
    contact = contact_params(test, scenario.vehicle)
    speeds = sorted(set(test.speeds_m_per_s) | {test.reference_speed})
    progress(f"linear stability at {len(speeds)} speeds ({speeds[0]:g}-{speeds[-1]:g} m/s), "
             f"{len(scenario.k_W_per_K)} k values x valves {test.valve_settings}")
    probe = make_car(scenario, speeds[0], contact)
    rows, mode_rows = _linear_rows(scenario, contact, probe.static_bellow_forces_N(), speeds, progress)
    tables = {"modes": mode_rows}
    diagnoses, warnings = _time_domain(scenario, rows, tables, progress)
    for row in rows:
        row.update(verdict_columns(row, tables.get("nonlinear", ())))
    info = {"contact_table": contact.table_csv or "S1002 / UIC60 1:40 (shipped)",
            "conicity_at_centre": _centre_conicity(probe),
            "equivalent_conicity_3mm": float(probe.contact_table.equivalent_conicity(0.003)),
            "speeds_m_per_s": speeds}
    return Computed(rows, _shown(test), {}, tables, diagnoses=diagnoses, warnings=warnings, info=info)


def totals(rows) -> Dict[str, float]:
    """The lowest of each checkable metric over the circuit's cases (a critical speed is as low
    as its worst case; NaN when one case has none)."""
    circuit_rows = [r for r in rows if r["airspring"] == "circuit"]
    return {m: float(np.min([r[m] for r in circuit_rows])) for m in KIND.check_metrics
            if circuit_rows and m in circuit_rows[0]}


def case_metrics(row) -> Optional[CaseMetrics]:
    """The checkable metrics of a case of the circuit (the rows of the reference airspring
    models are for comparison: checks do not judge them)."""
    if row["airspring"] != "circuit":
        return None
    return CaseMetrics(row["k_W_per_K"], row["valves"], {m: row.get(m, math.nan) for m in KIND.check_metrics})


def _linear_rows(scenario: Scenario, contact: ContactParams, F0, speeds: List[float], progress: Progress):
    """(a summary row per valve setting x k x airspring model, every mode below
    ``max_frequency_Hz`` at every speed): the linear critical speed, the mode that loses its
    damping, the carbody modes at the reference speed."""
    from cosim.stability import critical_speed, scan_speeds
    test = scenario.experiment
    rows, mode_rows = [], []
    linearised: Dict[tuple, _Cars] = {}                # the car's linearisations by its bellows' stiffness:
                                                       # frozen air and static (isothermal for k > 0) repeat over k

    def cars_for(K_b: np.ndarray) -> _Cars:
        key = tuple(np.round(K_b, 3))                   # [N/m]
        if key not in linearised:
            linearised[key] = _Cars(scenario, F0, K_b, contact)
        return linearised[key]

    for valves in test.valve_settings:
        for k in scenario.k_W_per_K:
            air = _air(scenario, valves, k, F0)
            K_static = static_stiffness_N_per_m(air)
            for model in AIRSPRINGS:
                cars = cars_for(np.diag(air.G_z) if model == "circuit" else np.diag(K_static))
                coupled_air = air if model == "circuit" else (None, K_static - np.diag(np.diag(K_static)))
                scan = scan_speeds(cars, coupled_air, speeds)
                v_crit, bracket, note = critical_speed(cars, coupled_air, scan, test.resolution_m_per_s)
                progress(f"valves {'on' if valves else 'off'}, k = {k:g} W/K, airsprings {model}: {note}")
                key = {"valves": bool(valves), "k_W_per_K": float(k), "airspring": model}
                row = {**key, **_critical_columns(cars, coupled_air, scan, v_crit, bracket, note)}
                row.update(_body_columns(scan.modes[speeds.index(test.reference_speed)]))
                rows.append(row)
                mode_rows += [{**key, "speed_m_per_s": float(v), "mode": m.label, "frequency_Hz": m.frequency_Hz,
                               "damping_ratio": m.damping_ratio, "real_per_s": m.eigenvalue.real,
                               "imag_per_s": m.eigenvalue.imag}
                              for v, ms in zip(scan.speeds_m_per_s, scan.modes) for m in ms
                              if abs(m.eigenvalue) <= 2.0 * math.pi * test.max_frequency_Hz]
    return rows, mode_rows


def _time_domain(scenario: Scenario, rows: List[Dict[str, object]], tables: Dict[str, list], progress: Progress):
    """The brute force and the ramp-down the scenario asks for: their tables (into ``tables``),
    their results in the circuit rows; (diagnoses, warnings): without either, the warning that the
    critical speed is the linear one only."""
    test = scenario.experiment
    diagnoses: List[str] = []
    warnings: List[str] = []
    if test.nonlinear_speeds_m_per_s:
        tables["nonlinear"], diagnoses = _brute_force(scenario, progress)
        _add_onsets(rows, tables["nonlinear"])
    if test.ramp_from_m_per_s is not None:
        tables["ramp"], tables["ramp_envelope"], found = _ramp_down(scenario, progress)
        diagnoses += found
        _add_ramp_ends(rows, tables["ramp"])
    if not test.nonlinear_speeds_m_per_s and test.ramp_from_m_per_s is None:
        warn(warnings, LINEAR_ONLY_WARNING)
    return diagnoses, warnings


def _shown(test: StabilityTest) -> Tuple[str, ...]:
    """The summary columns printed: the verdict and its parts, the carbody's sway and yaw, and
    the time-domain results the scenario asked for."""
    shown = ("valves", "k_W_per_K", "airspring", "critical_speed_m_per_s", "critical_speed_by",
             "linear_critical_speed_m_per_s", "critical_mode", "critical_frequency_Hz", "min_damping_ratio",
             "f_lower_sway_Hz", "zeta_lower_sway", "f_yaw_Hz", "zeta_yaw")
    if test.nonlinear_speeds_m_per_s or test.ramp_from_m_per_s is not None:
        shown += ("nonlinear_critical_speed_m_per_s",)
    if test.nonlinear_speeds_m_per_s:
        shown += ("nonlinear_onset_m_per_s",)
    if test.ramp_from_m_per_s is not None:
        shown += ("limit_cycle_ends_m_per_s",)
    return shown


def _brute_force(scenario: Scenario, progress: Progress) -> Tuple[List[Dict[str, object]], List[str]]:
    """Every brute-force run (speed x disturbance x k x valve setting, co-simulated): per run the
    leading wheelset's growth rate and final amplitude (:mod:`cosim.stability.nonlinear`), and the
    diagnoses of runs that stopped (a derailed car: it grew)."""
    from cosim.engine.cases import simulate_scenarios
    from cosim.stability.nonlinear import final_amplitude_m, growth_rate_per_s, hunts
    test = scenario.experiment
    out, diagnoses = [], []
    runs = [(v, d) for d in test.disturbances_m for v in test.nonlinear_speeds_m_per_s]
    progress(f"brute force at {', '.join(f'{v:g}' for v in test.nonlinear_speeds_m_per_s)} m/s, wheelsets released "
             f"at {', '.join(f'{1e3 * d:g}' for d in test.disturbances_m)} mm, {test.nonlinear_s:g} s each")
    variants = [scenario.with_experiment(nonlinear_speeds_m_per_s=(v,), disturbances_m=(d,)) for v, d in runs]
    # on one pool: a run's k values share a process and a circuit where the processes allow
    results = simulate_scenarios(variants, test.valve_settings, disturbed_car, [test.nonlinear_s] * len(runs),
                                 progress, [f"{scenario.name} {v:g} m/s {1e3 * d:g} mm" for v, d in runs])
    for (v, d), (ds, found) in zip(runs, results):
        diagnoses += [f"{v:g} m/s, {1e3 * d:g} mm: {f}" for f in found]
        t = ds["time"].values
        for j in range(ds.sizes["case"]):
            case = ds.isel(case=j)
            y = case["wheelset_lateral_m"].isel(wheelset=0).values
            ran = np.isfinite(y)                 # a run that stopped holds NaN from then on
            stopped = not ran.all()
            rate = growth_rate_per_s(t[ran], y[ran], max_amplitude_m=SMALL_AMPLITUDE_FACTOR * d)
            if math.isnan(rate) and stopped:
                rate = math.inf                   # derailed before it could be measured: it grew
            amplitude = final_amplitude_m(t[ran], y[ran])
            out.append({"valves": bool(case["valves"].item()), "k_W_per_K": float(case["k_W_per_K"].item()),
                        "speed_m_per_s": float(v), "disturbance_m": float(d), "growth_rate_per_s": rate,
                        "final_amplitude_m": amplitude, "hunts": stopped or hunts(amplitude, d),
                        "stopped": stopped})
    return out, diagnoses


def _ramp_down(scenario: Scenario, progress: Progress):
    """Every ramp-down (deceleration x k x valve setting, co-simulated): rows of the limit cycle's
    amplitude at the start speed and the speed at which it died
    (:func:`cosim.stability.nonlinear.limit_cycle_end`); rows of the envelope against speed (the
    figure's trace); the diagnoses."""
    from cosim.engine.cases import simulate_scenarios
    from cosim.stability.nonlinear import envelope, limit_cycle_end
    from vehicle.speed import SpeedProfile
    test = scenario.experiment
    out, traces, diagnoses = [], [], []
    rates = test.ramp_decelerations_m_per_s2
    durations = [test.ramp_duration_s(a) for a in rates]
    progress(f"ramp-down {test.ramp_from_m_per_s:g} -> {test.ramp_to_m_per_s:g} m/s at "
             + ", ".join(f"{a:g} m/s^2 ({duration:g} s)" for a, duration in zip(rates, durations)))
    variants = [scenario.with_experiment(ramp_decelerations_m_per_s2=(a,)) for a in rates]
    results = simulate_scenarios(variants, test.valve_settings, ramping_car, durations, progress,
                                 [f"{scenario.name} ramp {a:g} m/s^2" for a in rates])
    for a, (ds, found) in zip(rates, results):
        diagnoses += [f"ramp at {a:g} m/s^2: {f}" for f in found]
        profile = SpeedProfile(test.ramp_from_m_per_s, test.ramp_hold_s, a)
        t = ds["time"].values
        for j in range(ds.sizes["case"]):
            case = ds.isel(case=j)
            y = case["wheelset_lateral_m"].isel(wheelset=0).values
            ran = np.isfinite(y)
            t_end, amplitude = limit_cycle_end(t[ran], y[ran], test.ramp_hold_s)
            tc, env = envelope(t[ran], y[ran])
            key = {"valves": bool(case["valves"].item()), "k_W_per_K": float(case["k_W_per_K"].item()),
                   "deceleration_m_per_s2": float(a)}
            out.append({**key, "limit_cycle_amplitude_m": amplitude,
                        "limit_cycle_ends_m_per_s": float(profile.speed(t_end)) if math.isfinite(t_end) else math.nan,
                        "stopped": not ran.all()})
            traces += [{**key, "time_s": float(tc_i), "speed_m_per_s": float(profile.speed(tc_i)), "envelope_m": float(e)}
                       for tc_i, e in list(zip(tc, env))[::10]]          # every 0.5 s
    return out, traces, diagnoses


def _add_ramp_ends(rows: List[Dict[str, object]], ramps: List[Dict[str, object]]) -> None:
    """The ramp-down's result in each circuit row: the speed where the limit cycle died at the
    smallest deceleration, and how far the other decelerations' results lie from it."""
    for row in rows:
        if row["airspring"] != "circuit":                # the ramp runs the circuit: no value (not NaN,
            continue                                     # which verify would count as a failure)
        mine = sorted((r["deceleration_m_per_s2"], r["limit_cycle_ends_m_per_s"]) for r in ramps
                      if r["k_W_per_K"] == row["k_W_per_K"] and r["valves"] == row["valves"])
        row["limit_cycle_ends_m_per_s"] = mine[0][1]
        row["limit_cycle_ends_spread_m_per_s"] = (max(v for _, v in mine) - min(v for _, v in mine)
                                                  if len(mine) > 1 else math.nan)


def _add_onsets(rows: List[Dict[str, object]], runs: List[Dict[str, object]]) -> None:
    """The brute-force onset (smallest disturbance) in each circuit row (the static-stiffness rows
    get none: the co-simulation always runs the air circuit): :func:`onset_speed`, NaN when the
    speeds do not bracket it, with how it was found in ``nonlinear_note``."""
    from cosim.stability.nonlinear import onset_speed
    smallest = min(r["disturbance_m"] for r in runs)
    for row in rows:
        if row["airspring"] != "circuit":                # the brute force runs the circuit
            continue
        mine = [r for r in runs if r["disturbance_m"] == smallest and r["k_W_per_K"] == row["k_W_per_K"]
                and r["valves"] == row["valves"]]
        v, note = onset_speed([r["speed_m_per_s"] for r in mine], [r["growth_rate_per_s"] for r in mine],
                              [r["hunts"] for r in mine])
        row["nonlinear_onset_m_per_s"] = math.nan if v is None else v
        row["nonlinear_note"] = note


#: said by a run without a time-domain analysis (its critical speed is the linear one alone)
LINEAR_ONLY_WARNING = ("the critical speed is the linear one only (no stability.nonlinear_speeds_m_per_s or "
                       "stability.ramp_from_m_per_s): where the bifurcation is subcritical, as on S1002 / UIC60, "
                       "the car keeps hunting below it (docs/stability.md: the car with dampers to 28.3 m/s "
                       "against 40.3 m/s linear); add a ramp-down or brute force to assess it")


def verdict_columns(row: Dict[str, object], brute_force: Sequence[Dict[str, object]] = ()) -> Dict[str, object]:
    """The running-stability verdict of a summary row: ``critical_speed_m_per_s``, the lowest speed
    at which the car is shown to hunt by any analysis the row ran, and ``critical_speed_by``, which
    one. The linear critical speed (``linear_critical_speed_m_per_s``) is the verdict only without a
    time-domain analysis; a subcritical car hunts below it on a limit cycle. The time-domain one
    (``nonlinear_critical_speed_m_per_s``) is the lowest of: the brute-force onset (smallest
    disturbance), the lowest brute-force speed at which any disturbance hunts, and the speed where
    the ramp-down's limit cycle died. A ramp-down whose limit cycle never died hunts down to its
    last speed at least: the critical speed lies below the ramp, unknown (NaN: a check on it is
    an ERROR). Rows without a time-domain analysis (the static-stiffness ones) keep the linear
    verdict."""
    linear = float(row["linear_critical_speed_m_per_s"])
    found = {}
    if "nonlinear_onset_m_per_s" in row:
        hunting = [float(r["speed_m_per_s"]) for r in brute_force
                   if r["hunts"] and r["k_W_per_K"] == row["k_W_per_K"] and r["valves"] == row["valves"]]
        found["brute force"] = min((v for v in (row["nonlinear_onset_m_per_s"], *hunting) if not math.isnan(v)),
                                   default=math.nan)
    if "limit_cycle_ends_m_per_s" in row:
        found["ramp-down"] = float(row["limit_cycle_ends_m_per_s"])
        if math.isnan(found["ramp-down"]):
            return {"linear_critical_speed_m_per_s": linear, "nonlinear_critical_speed_m_per_s": math.nan,
                    "critical_speed_m_per_s": math.nan,
                    "critical_speed_by": "ramp-down: the limit cycle did not die (below the ramp's end)"}
    known = {by: v for by, v in found.items() if not math.isnan(v)}
    nonlinear = min(known.values()) if known else math.nan
    out = {"linear_critical_speed_m_per_s": linear}
    if found:
        out["nonlinear_critical_speed_m_per_s"] = nonlinear
    if known and not nonlinear >= linear:          # the time domain shows hunting below the linear speed
        by = min(known, key=known.get)
        out.update(critical_speed_m_per_s=nonlinear, critical_speed_by=by)
    else:
        out.update(critical_speed_m_per_s=linear, critical_speed_by="linear")
    return out


def _centre_conicity(car) -> float:
    """d(r_L - r_R)/dy / 2 of the contact law's (smoothed) table at y = 0, over +-0.01 mm: the
    conicity the linearisation about the centred wheelset sees."""
    y = 1e-5
    plus, minus = car._wr.table.geometry(y), car._wr.table.geometry(-y)
    return float((plus["r_L"] - plus["r_R"] - minus["r_L"] + minus["r_R"]) / (4.0 * y))


def _critical_columns(cars, air, scan, v_crit, bracket, note) -> Dict[str, object]:
    """The critical speed's columns of a summary row (see :func:`run`): the speed (inf: stable over
    the whole scan; NaN when a mode grows already at the lowest speed -- the critical speed lies
    below the scan, unknown, and a check on it is an ERROR), and the least damped mode where it grows (at
    the bracket's growing end, or the lowest speed)."""
    from cosim.stability.critical import least_damped, modes_at
    lowest = min((m.damping_ratio for ms in scan.modes for m in ms), default=math.nan)
    out = {"min_damping_ratio": lowest, "critical_note": note}
    if v_crit is None and not math.isnan(bracket[0]):
        out.update(linear_critical_speed_m_per_s=math.inf, critical_mode="", critical_frequency_Hz=math.nan)
        return out
    m = least_damped(modes_at(cars, air, bracket[1]))
    out.update(linear_critical_speed_m_per_s=math.nan if v_crit is None else v_crit, critical_mode=m.label,
               critical_frequency_Hz=m.frequency_Hz)
    return out


def figures(outcome: Outcome) -> List[Figure]:
    """Per valve setting and airspring model, a row per k: the root locus over the speeds (each
    mode family's least damped mode, frequency against real part, the points at the scan's speeds)
    and the damping ratio of each mode family against speed."""
    from cosim.stability.coupled import family
    rows = outcome.tables.get("modes", [])
    out = []
    for valves in sorted({r["valves"] for r in rows}):
        for model in AIRSPRINGS:
            sel = [r for r in rows if r["valves"] == valves and r["airspring"] == model and r["frequency_Hz"] > 0]
            if not sel:
                continue
            panels = []
            families = sorted({family(r["mode"]) for r in sel})   # one colour per family in every panel
            for k in sorted({r["k_W_per_K"] for r in sel}):
                least: Dict[Tuple[str, float], dict] = {}   # (family, speed) -> its least damped mode
                for r in sel:
                    key = (family(r["mode"]), r["speed_m_per_s"])
                    if r["k_W_per_K"] == k and (key not in least or r["damping_ratio"] < least[key]["damping_ratio"]):
                        least[key] = r
                paths = {f: [least[key] for key in sorted(least) if key[0] == f] for f in families}
                panels.append(Panel([Curve([r["real_per_s"] for r in p], [r["frequency_Hz"] for r in p], f, "o-")
                                     for f, p in paths.items()], "real part σ [1/s] (> 0: growing)", "frequency [Hz]",
                                    f"root locus, speeds {min(r['speed_m_per_s'] for r in sel):g}-"
                                    f"{max(r['speed_m_per_s'] for r in sel):g} m/s, {k_legend(k)}"))
                panels.append(Panel([Curve([r["speed_m_per_s"] for r in p], [r["damping_ratio"] for r in p], f, "o-")
                                     for f, p in paths.items()], "speed V [m/s]", "damping ratio ζ [-]",
                                    f"least damped mode of each family, {k_legend(k)}", hlines=[(0.0, "ζ = 0")]))
            suffix = f"_valves={'on' if valves else 'off'}_{model}"
            out.append(Figure(f"stability{suffix}.png", panels,
                              f"Linear running stability ({'valves on' if valves else 'valves off'}, airsprings: "
                              f"{'air circuit' if model == 'circuit' else 'static stiffness'})", 2))
    return out + _bifurcation_figures(outcome)


def _ramp_traces(outcome: Outcome, valves: bool) -> List[Curve]:
    """The ramp-downs' envelopes against speed [mm], a curve per k and deceleration."""
    rows = [r for r in outcome.tables.get("ramp_envelope", []) if r["valves"] == valves]
    out = []
    for k in sorted({r["k_W_per_K"] for r in rows}):
        for a in sorted({r["deceleration_m_per_s2"] for r in rows}):
            pts = [r for r in rows if r["k_W_per_K"] == k and r["deceleration_m_per_s2"] == a]
            out.append(Curve([r["speed_m_per_s"] for r in pts], [1e3 * r["envelope_m"] for r in pts],
                             f"ramp-down at {a:g} m/s², {k_legend(k)}", "-"))
    return out


def _bifurcation_figures(outcome: Outcome) -> List[Figure]:
    """Per valve setting: the brute force's final amplitude of the leading wheelset against speed
    (the bifurcation diagram) and its growth rate, a curve per k and disturbance, with each k's
    linear critical speed (a vertical line)."""
    runs = outcome.tables.get("nonlinear", [])
    out = []
    for valves in sorted({r["valves"] for r in runs + outcome.tables.get("ramp", [])}):
        mine = [r for r in runs if r["valves"] == valves]
        amplitude, growth = [], []
        for k in sorted({r["k_W_per_K"] for r in mine}):
            for d in sorted({r["disturbance_m"] for r in mine}):
                pts = sorted((r["speed_m_per_s"], r) for r in mine if r["k_W_per_K"] == k and r["disturbance_m"] == d)
                label = f"{k_legend(k)}, released at {1e3 * d:g} mm"
                amplitude.append(Curve([v for v, _ in pts], [1e3 * r["final_amplitude_m"] for _, r in pts], label, "o-"))
                growth.append(Curve([v for v, _ in pts], [r["growth_rate_per_s"] for _, r in pts], label, "o-"))
        for trace in _ramp_traces(outcome, valves):
            amplitude.append(trace)
        top = max([1e3 * r["final_amplitude_m"] for r in mine] + [max(c.y) for c in amplitude if len(c.y)], default=1.0)
        for row in outcome.rows:
            if row["valves"] == valves and row["airspring"] == "circuit" and math.isfinite(row["linear_critical_speed_m_per_s"]):
                v = row["linear_critical_speed_m_per_s"]
                amplitude.append(Curve([v, v], [0.0, top], f"linear critical speed, {k_legend(row['k_W_per_K'])}", ":"))
        panels = [Panel(amplitude, "speed V [m/s]", "leading wheelset amplitude [mm]",
                        "bifurcation diagram: brute force (last second), ramp-down (largest over the next second)")]
        if growth:
            panels.append(Panel(growth, "speed V [m/s]", "growth rate σ [1/s] (> 0: grows)",
                                "brute force: growth of the leading wheelset's oscillation", hlines=[(0.0, "σ = 0")]))
        out.append(Figure(f"bifurcation_valves={'on' if valves else 'off'}.png", panels,
                          f"Nonlinear running stability ({'valves on' if valves else 'valves off'})", 2))
    return out


class StabilityKind(CarKind):
    """Running stability: linear, brute force, ramp-down."""

    name, section, experiment = "stability", "stability", StabilityTest
    check_metrics = ("critical_speed_m_per_s", "linear_critical_speed_m_per_s",
                     "nonlinear_critical_speed_m_per_s", "min_damping_ratio")
    # the time-domain results move with the steps: verify estimates them too
    headline_metrics = ("critical_speed_m_per_s", "linear_critical_speed_m_per_s",
                        "nonlinear_critical_speed_m_per_s", "min_damping_ratio", "nonlinear_onset_m_per_s",
                        "limit_cycle_ends_m_per_s")
    plot_metrics = ("critical_speed_m_per_s", "min_damping_ratio")
    case_columns = ("airspring", "valves", "k_W_per_K")

    totals = staticmethod(totals)
    case_metrics = staticmethod(case_metrics)
    parse = staticmethod(parse)
    duration_s = staticmethod(duration_s)
    shortest_duration_s = staticmethod(shortest_duration_s)
    valve_settings = staticmethod(valve_settings)
    extra_files = staticmethod(extra_files)
    refuse_faults = staticmethod(refuse_faults)
    refuse_payload = staticmethod(refuse_payload)
    refuse_imported_circuit = staticmethod(refuse_imported_circuit)
    refuse_check = staticmethod(refuse_check)
    refuse_limit = staticmethod(refuse_limit)
    make_car = staticmethod(make_car)
    run = staticmethod(run)
    figures = staticmethod(figures)


KIND = StabilityKind()
