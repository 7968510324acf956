"""A monolithic reference for the co-simulation: the car and its pneumatic circuit integrated
together, inside exudyn, by one integrator with one step.

Model. The car is the co-simulation's own (its kind's ``make_car``, e.g. ``cosim.kinds.twist.make_car``,
built, with the circuit and its initial state, by :func:`cosim.engine.cases.build_cosimulation`), with
two changes:

* the pneumatic state x of one case (one k) becomes exudyn first-order coordinates: a
  ``NodeGenericODE1`` with an ``ObjectGenericODE1`` whose right-hand side user function returns
  ``circuit.derivatives(x, z, zdot)``, z and zdot the bellow crushings of the current (Newton
  iterate) mechanical state: z = h0 - d_z as ``MetroCar.bellow_crushing`` (d the connector's
  intrinsic displacement), zdot its exact time derivative (see :meth:`MonolithicCar.crushing`);
* each bellow connector's ``springForceTorqueUserFunction`` (the co-simulation's force law
  F(t, z) = F_s + (F_e - F_s)(t - t_n)/H + K (z - z_n)) is replaced by a Python function with the
  same geometry that returns [k_s d_x, k_s d_y, -F, 0, 0, 0] with F = circuit.bellow_forces_N(x, z),
  x the current first-order coordinates and z = h0 - d_z (see ``vehicle.car.secondary.add_airsprings``).

Nothing is exchanged at macro-step boundaries: the force the car feels and the state of the air
are evaluated together, at every Newton iterate of every step.

Solver: exudyn's implicit generalized-alpha (``MainSolverImplicitSecondOrder``, the car's own
integrator, the scenario's spectral radius), fixed step h, one ``SolveSteps`` call. Why not an explicit
Runge-Kutta solver (RK44 ...):

* exudyn's explicit solvers ignore algebraic constraints (``CSolverExplicit.cpp``; tried:
  "SolverExplicit: number of algebraic equations (nAE) != 0: explicit INTEGRATOR WILL IGNORE
  CONSTRAINTS", and the wheelsets drift off the guidance), and with ``eliminateConstraints`` accept
  only ``CoordinateConstraint`` objects that pin an ODE2 coordinate of a node to ground at zero;
  the car's ``GenericJoint`` guidance aborts the solver ("detected object 8 which contains
  constraints that cannot be solved"). In the curve the guidance follows the track in time
  (offset user functions): no explicit solver can integrate that car. Standing (the twist),
  three of the four guidance constraints are coordinate constraints of the Rxyz wheelset nodes
  (x, and the rotations about y and z), but the lateral one locks the rail-level point,
  y + z_w sin(roll) = 0 (12 mm of difference at the twisted wheelsets' 27 mrad), which is not:
  an explicit reference would be a different car (a lateral penalty spring), and would also need
  the rail heights as functions of the stage time (the car sets them at the step end, exact only
  for an implicit step);
* the stiff Hertz contacts (~1e9 N/m per wheel, ~250 Hz wheelset modes) bound an explicit step
  to ~1.8 ms (RK4: |h lambda| < 2.8).

The note that generalized-alpha treats ODE1 coordinates "only to first order" is a start-up
artefact, not the method: exudyn's generalized-alpha (Arnold & Bruls) integrates ODE1
coordinates with the trapezoidal rule, x_{n+1} = x_n + h/2 (xdot_n + xdot_{n+1}) with
xdot_{n+1} = f(x_{n+1}, q_{n+1}, qdot_{n+1}) at the converged iterate (``CSolverImplicitSecondOrder
.cpp``, ``ComputeNewtonUpdate``), second order; xdot_{n+1} is kept for the next step, also across
``SolveSteps`` calls. But it starts from xdot_0 = 0, not f(x_0): a global O(h) error whenever
f(x_0) != 0. Measured on m q'' = -k q + c y, y' = -a y + b q' + sin 5t: with y(0) = 0 the errors
fall by 4.0 per halving; with y(0) = 1 by ~2 (first order: 2.5, 2.3, 2.1 on q') unless xdot_0 is
set to f(x_0), after which by 4.0 again. Here f(x_0) = 0 (circuit at rest, car in equilibrium; 1.5e-8 in scaled
units, round-off) and :class:`MonolithicCar` sets xdot_0 = f(x_0) anyway. Measured order of the
reference itself (``benchmarks/monolithic.py``): 1.9-2.1 on the twist metrics, 2.0-2.4 on the
curve's (1.4 on the curve's final roll, whose last halving changes it by 4e-5 mrad).

Newton. exudyn's Newton stops on the 2-norm of the whole residual (forces in N for the ODE2 rows,
f(x) - xdot for the ODE1 rows) below max(1e-4, 1e-8 x initial). In SI units 1e-4 kg/s on an air
mass would be far from converged, so the first-order coordinates are x in scaled units
(:data:`STATE_SCALE`: masses in mg, temperatures in mK, ...): converged steps leave f(x) - xdot
below ~1e-6 mK/s and mg/s. The energy accumulators (heat, work, enthalpy; outputs only, nothing
depends on them) stay in J: in mJ their residual, fed by the ~5e-13 m/s round-off of the crushing
rate times p dV/dz, floored the norm at 7e-5, so Newton met its tolerance on noise. With these
scales tolerances of 1e-4 / 1e-8 and 1e-6 / 1e-10 give the same twist to 10 digits (1e-7 / 1e-12
is below the round-off floor: Newton fails, the step is halved, and the run takes 250 x longer).
The coupling terms dF/dx and d(f)/d(z, zdot) pass through Python, so exudyn's numerical Jacobian
does not see them: the modified Newton iteration converges on them anyway, at ~0.05 per iteration
(the residual alternates between the ODE2 and ODE1 rows, apparent contractivity 0.005 and ~1.5 on
alternate iterations), 5-8 iterations per step. exudyn's default renews the Jacobian whenever
the contractivity exceeds 0.5, i.e. nearly every step, for nothing (55 Jacobians in 50 steps,
3.6 x the wall time); here only when it exceeds 4 or after 12 iterations.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable, Optional

import exudyn as exu
import numpy as np
from exudyn.itemInterface import NodeGenericODE1, ObjectGenericODE1

from cosim.engine.cases import build_cosimulation
from cosim.engine.master import Record
from cosim.scenario.model import Scenario

_OUT = exu.OutputVariableType

#: units of the first-order coordinates per state group (state = scale x coordinate): mg for
#: masses, mK for temperatures, mg/s for pipe flows and cumulative mg through the links, J for the
#: energy accumulators, ms for valve open times, um for valve signals -- see the module docstring
#: (Newton)
STATE_SCALE = {"m": 1e-6, "T": 1e-3, "q": 1e-6, "mass_through": 1e-6, "energy": 1.0, "open_time": 1e-3,
               "valve_signal": 1e-6}


def _make_car(scenario: Scenario):
    """The car factory of the scenario's kind (a car kind: :mod:`cosim.kinds`)."""
    from cosim.kinds import KINDS
    kind = KINDS[scenario.kind]
    if not kind.car:
        raise ValueError(f"the monolithic reference runs car scenarios, not {scenario.kind!r}")
    return kind.make_car


def state_scale(circuit) -> np.ndarray:
    """Scale of each first-order coordinate (pneumatic state = scale x coordinate)."""
    lay = circuit.layout
    s = np.ones(lay.size)
    s[lay.m] = STATE_SCALE["m"]
    s[lay.T] = STATE_SCALE["T"]
    s[lay.q] = STATE_SCALE["q"]
    s[lay.mass_through] = STATE_SCALE["mass_through"]
    s[lay.heat_in:lay.heat_in + 3] = STATE_SCALE["energy"]
    s[lay.open_time] = STATE_SCALE["open_time"]
    s[lay.valve_signal] = STATE_SCALE["valve_signal"]
    return s


class MonolithicRecord(Record):
    """The co-simulation's :class:`~cosim.engine.master.Record` (one case), plus ``monolithic``: the
    :class:`MonolithicCar` that produced it (statistics, wall time)."""

    monolithic: Optional["MonolithicCar"] = None


@dataclass
class MonolithicStats:
    wall_s: float = 0.0
    steps: int = 0
    newton_iterations: int = 0
    jacobians: int = 0
    step_s: float = 0.0


class MonolithicCar:
    """The car of ``scenario`` with the circuit of one heat-transfer coefficient ``k`` as exudyn
    first-order coordinates (see the module docstring), integrated with a fixed step ``step_s``.

    ``spectral_radius``: the integrator's (default: the scenario's ``solver.spectral_radius``);
    ``newton_abs_tol``/``newton_rel_tol``: Newton tolerances (default: the car's)."""

    def __init__(self, scenario: Scenario, k: float, step_s: float, *, spectral_radius: Optional[float] = None,
                 newton_abs_tol: float = 1e-4, newton_rel_tol: float = 1e-8):
        if not step_s > 0:
            raise ValueError(f"step_s must be > 0, got {step_s}")
        if any(f.t_s > 0.0 for f in getattr(scenario.circuit, "faults", ())):
            raise ValueError("the monolithic reference integrates one circuit throughout: faults that happen "
                             "during the run (t_s > 0) are not modelled in it")
        cosim = build_cosimulation(scenario, [float(k)], _make_car(scenario))
        self.scenario, self.k, self.step_s = scenario, float(k), float(step_s)
        self._cosim = cosim           # its sample() records the monolithic state (see sample)
        self.car = car = cosim.cars[0]
        self.circuit = c = cosim.circuit
        self.mbs = mbs = car.mbs
        self.scale = state_scale(c)
        x0 = cosim.x[:, 0].copy()

        # the bellows, as vehicle.car.secondary.add_airsprings builds them
        self._h0 = car.bellow_height_m
        self._ks = car.params.bellow_shear_stiffness_N_per_m
        self._bellows = list(car._bellows)

        # first-order coordinates: the pneumatic state, scaled
        y0 = x0 / self.scale
        self._node = mbs.AddNode(NodeGenericODE1(referenceCoordinates=[0.0] * len(y0),
                                                 initialCoordinates=y0.tolist(),
                                                 numberOfODE1Coordinates=len(y0)))
        self._ode1 = mbs.AddObject(ObjectGenericODE1(nodeNumbers=[self._node], rhsUserFunction=self._rhs))
        for i, co in enumerate(self._bellows):
            mbs.SetObjectParameter(co, "springForceTorqueUserFunction", self._bellow_function(i))
        mbs.Assemble()
        self.rhs_calls = 0

        # consistent initial rate of the first-order coordinates (exudyn would start from 0)
        z0, zd0 = self.crushing()
        f0 = c.derivatives(x0, z0, zd0) / self.scale
        mbs.systemData.SetODE1Coordinates_t(f0.tolist(), configuration=exu.ConfigurationType.Initial)
        self.initial_rate_norm = float(np.abs(f0).max())  # 0 when the circuit starts at rest

        s = exu.SimulationSettings()
        s.solution.file.write = False
        s.solution.sensors.active = False
        s.linearSolver.solverType = exu.LinearSolverType.EigenDense
        ti = s.timeIntegration
        ti.verboseMode = 0
        ti.numberOfSteps = 1
        ti.startTime = 0.0
        ti.endTime = self.step_s
        ti.adaptiveStep = True   # a step Newton fails on is halved and retried: run() then raises
        ti.generalizedAlpha.spectralRadius = (scenario.solver.spectral_radius if spectral_radius is None
                                              else spectral_radius)
        ti.generalizedAlpha.computeInitialAccelerations = True
        ti.newton.useModifiedNewton = True
        # the coupling terms are not in the Jacobian (module docstring): renew it only when the
        # apparent contractivity exceeds 4 (default 0.5: nearly every step, for nothing)
        ti.newton.modifiedNewtonContractivity = 4.0
        ti.newton.maxModifiedNewtonIterations = 12
        ti.newton.maxIterations = 40
        ti.newton.absoluteTolerance = newton_abs_tol
        ti.newton.relativeTolerance = newton_rel_tol
        self._settings = s
        self._solver = exu.MainSolverImplicitSecondOrder()
        if not self._solver.InitializeSolver(mbs, s):
            raise RuntimeError("exudyn: InitializeSolver failed")
        self._ti, self._it = s.timeIntegration, self._solver.it
        self.t_s = 0.0
        self.stats = MonolithicStats(step_s=self.step_s)

    # ---------------------------------------------------------------- coupling functions
    def crushing(self):
        """Bellow crushing z [m] and its rate dz/dt [m/s] at the current (iterate) state.

        z = h0 - d_z, d the connector's DisplacementLocal, exactly as the force law and
        ``MetroCar.bellow_crushing``. Its rate is the exact time derivative of that z: the
        directional derivative of z(q) along the velocity, (z(q + e qdot) - z(q - e qdot)) / 2e
        (z depends on the positions only). ``vehicle.car.bellows.BellowLaws``'s closed form (relative
        velocity in the mid-frame minus w x d) is the derivative of d expressed in the mid-frame,
        but exudyn's intrinsic d is the translation of the SE(3) logarithm of the relative motion,
        which differs from it at second order in the relative rotation (-[theta]x^2 d / 24):
        integrated over the twist ramp the closed form overstated the crushing change by
        2.7 um of 17 mm (1.6e-4), and the adiabatic bellows ended 2 mK warmer than the
        co-simulation's limit, which integrates the volume consistently (its Hermite interpolant
        of z integrates to the change of z whatever its end slopes)."""
        sd = self.mbs.systemData
        q = sd.GetODE2Coordinates()
        v = sd.GetODE2Coordinates_t()
        z = self._h0 - self._displacement_z()
        e = self.RATE_PROBE_S
        sd.SetODE2Coordinates(q + e * v)
        plus = self._displacement_z()
        sd.SetODE2Coordinates(q - e * v)
        minus = self._displacement_z()
        sd.SetODE2Coordinates(q)
        return z, (minus - plus) / (2.0 * e)

    #: time probe of the directional derivative in :meth:`crushing` [s]: the plates move by ~5e-5 m,
    #: the rate's round-off is ~5e-13 m/s (1e-4 s: 3e-12) and its truncation error
    #: (probe^2 / 6 times the third derivative of z along qdot) far below that
    RATE_PROBE_S = 1e-3

    def _displacement_z(self) -> np.ndarray:
        get = self.mbs.GetObjectOutput
        return np.array([get(co, _OUT.DisplacementLocal)[2] for co in self._bellows])

    def state(self) -> np.ndarray:
        """Pneumatic state x (SI) of the current configuration."""
        return np.asarray(self.mbs.systemData.GetODE1Coordinates()) * self.scale

    def _rhs(self, mbs, t, itemNumber, q):
        self.rhs_calls += 1
        z, zd = self.crushing()
        return (self.circuit.derivatives(np.asarray(q) * self.scale, z, zd) / self.scale).tolist()

    def _bellow_function(self, i: int):
        h0, ks, circuit, sysdata, scale = self._h0, self._ks, self.circuit, self.mbs.systemData, self.scale

        def bellow_force(mbs, t, itemNumber, displacement, rotation, velocity, angularVelocity,
                         stiffness, damping, rotJ0, rotJ1, offset):
            zv = np.zeros(4)
            zv[i] = h0 - displacement[2]
            x = np.asarray(sysdata.GetODE1Coordinates()) * scale
            F = float(circuit.bellow_forces_N(x, zv)[i])
            return [ks * displacement[0], ks * displacement[1], -F, 0.0, 0.0, 0.0]
        return bellow_force

    # ---------------------------------------------------------------- running
    def sample(self, record: Record) -> None:
        """Append the current state to ``record``: the co-simulation's own sampling
        (``CoSimulation.sample``: the same quantities, shapes and conventions), fed with the
        monolithic state (x, z and t of the current configuration)."""
        cosim = self._cosim
        cosim.x = self.state()[:, None]
        cosim.z = (self._h0 - self._displacement_z())[:, None]
        cosim.t = float(self.mbs.systemData.GetTime())
        cosim.sample(record)

    def run(self, t_end_s: float, output_interval_s: float,
            on_step: Optional[Callable[[float], None]] = None) -> "MonolithicRecord":
        """Integrate from t = 0 to ``t_end_s``, sampling every ``output_interval_s`` (both whole
        numbers of steps), in one SolveSteps call (one Jacobian, renewed when Newton asks).
        ``on_step(t)`` is called after every step. Raises RuntimeError if the integration fails
        or if Newton had to halve a step (the reference would no longer have the step h)."""
        n = round(t_end_s / self.step_s)
        every = round(output_interval_s / self.step_s)
        if n < 1 or abs(n * self.step_s - t_end_s) > 1e-9 * max(1.0, t_end_s):
            raise ValueError(f"the duration {t_end_s:g} s must be a whole number of steps ({self.step_s:g} s)")
        if every < 1 or abs(every * self.step_s - output_interval_s) > 1e-9:
            raise ValueError(f"the output interval {output_interval_s:g} s must be a whole number of steps "
                             f"({self.step_s:g} s)")
        if self.t_s != 0.0:
            raise RuntimeError("MonolithicCar.run integrates from t = 0 once")
        if t_end_s > self.car.t_end_max_s + 1e-9:
            raise ValueError(f"at {t_end_s:g} s the front wheelset would have left the track "
                             f"(t_end_max_s = {self.car.t_end_max_s:g} s)")
        record = MonolithicRecord()
        self.sample(record)
        outputs = {"next": 1}

        def post_step(mbs, t):
            if on_step is not None:
                on_step(t)
            if t >= outputs["next"] * output_interval_s - 1e-6 * self.step_s:
                self.sample(record)
                outputs["next"] += 1
            return True
        self.mbs.SetPostStepUserFunction(post_step)
        t0 = time.perf_counter()
        self._ti.endTime = t_end_s
        self._it.endTime = t_end_s
        self._it.maxStepSize = self.step_s
        try:
            ok = self._solver.SolveSteps(self.mbs, self._settings)
        finally:
            self.mbs.SetPostStepUserFunction(0)
        self.stats.wall_s += time.perf_counter() - t0
        self.t_s = float(self._it.currentTime)
        self.stats.steps = int(self._it.currentStepIndex) - 1
        self.stats.newton_iterations = int(self._it.newtonStepsCount)
        self.stats.jacobians = int(self._it.newtonJacobiCount)
        if not ok or self.t_s < t_end_s - 1e-9:
            raise RuntimeError(f"exudyn: the monolithic integration failed at t = {self.t_s:g} s")
        if self.stats.steps != n:
            raise RuntimeError(f"Newton failed on some steps, which exudyn halved: {self.stats.steps} steps "
                               f"instead of {n} of {self.step_s:g} s; the result is not the fixed-step reference")
        return record


def run_monolithic(scenario: Scenario, k: float, duration_s: float, step_s: float,
                   output_interval_s: Optional[float] = None, **options) -> MonolithicRecord:
    """The car of ``scenario`` (a car kind; for the curve with the valves connected pass
    ``scenario.with_valves(True)``) and its circuit for one ``k``, integrated
    monolithically with the fixed step ``step_s`` for ``duration_s``: the co-simulation's record
    (one case; ``record.arrays()`` as ``CoSimulation.run`` gives it), with ``record.monolithic``
    the :class:`MonolithicCar` (statistics, wall time). ``output_interval_s``: default the
    scenario's. ``options``: :class:`MonolithicCar` keywords."""
    car = MonolithicCar(scenario, k, step_s, **options)
    record = car.run(duration_s, output_interval_s or scenario.solver.output_interval_s)
    record.monolithic = car
    return record
