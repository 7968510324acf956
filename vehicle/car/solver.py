"""The car's solver: implicit generalized-alpha driven macro-step by macro-step, its Newton
Jacobian kept across them while it serves (:class:`CarSolver`; why and when it is kept:
:mod:`vehicle.car`, "Solver")."""
from __future__ import annotations

import math
from typing import Callable

import exudyn as exu

from .options import SolverSettings


class CarSolver:
    """The generalized-alpha solver of one system, driven step by step, its Jacobian kept while
    it serves. ``pre_step(mbs, t) -> bool`` is the system's PreStep user function; the owner
    calls :meth:`keep_jacobian` from it while :attr:`jacobian_may_skip` and keeps
    :attr:`heading_rad` at the track's heading. ``refresh_after_turn``: renew the Jacobian at
    the end of an advance through which the track turned (contact guidance)."""

    #: the stored Newton Jacobian is renewed at the next macro-step once the track heading has
    #: changed by more than this since it was computed [rad] (see :meth:`solve`; with contact
    #: guidance at the end of the macro-step that turned past it, see :meth:`_refresh_jacobian`)
    JACOBIAN_HEADING_TOL_RAD = 0.01
    #: ... and once the car's speed has changed by more than this since [m/s] (a speed profile
    #: that stops and starts: the Jacobian holds terms that follow the speed (the spinning
    #: wheelsets' gyroscopic terms are the candidates; not isolated), so one
    #: computed at line speed and kept at a stand, or the other way round, slows modified Newton:
    #: measured on a car standing after a curve, 5.3 iterations per step with the Jacobian of the
    #: curve at speed, 1.4 with a fresh one every iteration)
    JACOBIAN_SPEED_TOL_M_PER_S = 1.0
    #: ... and once the carbody's mass has changed by more than this fraction since (passengers
    #: boarding or alighting: the Jacobian holds the mass matrix, M / (beta h^2) its largest
    #: term, and modified Newton contracts by ~ the relative error of its mass per iteration:
    #: measured on the shipped line's car standing at its first station while 60 passengers
    #: board, 3.7-4.8 iterations per step (contractivity 0.16) with the Jacobian of t = 0, 2.2
    #: with one renewed every 100 kg (0.5 % of that carbody), 1.6-1.7 every 10 kg at 8 times the
    #: Jacobians; benchmarks/line_segments.py)
    JACOBIAN_MASS_TOL = 0.005
    #: Newton's residual cannot be brought below a floor that grows with the car's distance from
    #: the origin: a coordinate x is only known to one unit in the last place, ulp(x) (3.6e-12 m
    #: at 17 km), and a stiff spring whose elongation is a difference of two such coordinates
    #: turns that into force. Measured on the shipped line's car running (5 ms steps,
    #: benchmarks/line_segments.py): <= 9e-5, ~1e-4 and 1.8-6e-4 N at 4.5, 8.5 and 17.5 km,
    #: ~1.0-1.7e8 N/m x ulp(x), the axlebox springs' longitudinal stiffness summed (8 x 17.5 MN/m
    #: = 1.4e8 N/m): at 17 km their stiffness x 0.1 took the stalled car from 12.7 to 2.3
    #: iterations per step, x 0.5 to 2.7, the lateral and vertical ones x 0.1 changed nothing.
    #: Below that floor Newton cannot converge: with the absolute tolerance of 1e-4 N under it,
    #: the line's car renewed its Jacobian up to 58 000 times per 25 s. So the absolute tolerance
    #: is never set below this factor times that stiffness (``roundoff_stiffness_N_per_m``) times
    #: ulp(x) at the car's furthest wheelset. It stays under 1e-4 N below 4096 m for axleboxes up
    #: to 18 MN/m longitudinally (the metro cars, 17.5 MN/m), below 2048 m up to 36 MN/m (every
    #: shipped car), and a car there runs to the bit as before. 7.6e-4 N at 17 km for the metro
    #: car is ~2e-9 of its weight, against ~3e-2 N that moved the contact car's forces by 0.05 N
    #: (vehicle.car.options.CONTACT_NEWTON_REL_TOL).
    ROUNDOFF_SAFETY = 1.5

    def __init__(self, mbs, settings: SolverSettings, newton_rel_tol: float,
                 pre_step: Callable[..., bool], refresh_after_turn: bool,
                 roundoff_stiffness_N_per_m: float = 0.0):
        self._mbs = mbs
        self.step_s = settings.step_s
        s = exu.SimulationSettings()
        s.solution.file.write = False
        s.solution.sensors.active = False
        s.linearSolver.solverType = exu.LinearSolverType.EigenDense  # fastest at this size
        ti = s.timeIntegration
        ti.verboseMode = 0
        ti.numberOfSteps = 1
        ti.startTime = 0.0
        ti.endTime = self.step_s
        ti.adaptiveStep = True  # lets SolveSteps clamp a step to the macro-step end
        ti.generalizedAlpha.spectralRadius = settings.spectral_radius
        ti.newton.useModifiedNewton = True
        ti.newton.absoluteTolerance = settings.newton_abs_tol
        ti.newton.relativeTolerance = newton_rel_tol
        self._settings = s
        self._abs_tol = settings.newton_abs_tol
        self._roundoff_N_per_m = float(roundoff_stiffness_N_per_m)
        self._reuse = settings.reuse_jacobian
        self._refresh_after_turn = refresh_after_turn and self._reuse
        mbs.SetPreStepUserFunction(pre_step)
        if self._reuse:
            # a second solver on the same system computes fresh Jacobians on demand (calling the
            # main solver's ComputeNewtonJacobian from its own user function would recurse)
            self._jac_solver = exu.MainSolverImplicitSecondOrder()
            if not self._jac_solver.InitializeSolver(mbs, s):
                raise RuntimeError("exudyn: InitializeSolver failed")
        #: the exudyn solver (``MainSolverImplicitSecondOrder``)
        self.main = exu.MainSolverImplicitSecondOrder()
        if not self.main.InitializeSolver(mbs, s):
            raise RuntimeError("exudyn: InitializeSolver failed")
        if self._reuse:
            self.main.SetUserFunctionComputeNewtonJacobian(mbs, self._jacobian)
        self._ti = s.timeIntegration  # handles (references into the C++ objects)
        self._newton = self.main.newton  # the solver's own copy of the Newton settings, read by every step
        self._it = self.main.it
        self._conv = self.main.conv
        self._jac_h = None  # step size of the stored Jacobian
        self._jac_heading = 0.0  # track heading under wheelset 1 when it was computed [rad]
        #: track heading under wheelset 1 at the last step end [rad] (set by the owner)
        self.heading_rad = 0.0
        #: the car's speed at the last step end [m/s] (set by the owner)
        self.speed_m_per_s = 0.0
        self._jac_speed = 0.0  # the car's speed when the stored Jacobian was computed [m/s]
        #: the carbody's mass at the last step end [kg] (set by the owner; 0: it does not change)
        self.carbody_mass_kg = 0.0
        self._jac_mass = 0.0  # the carbody's mass when the stored Jacobian was computed [kg]
        #: the stored Jacobian may serve the coming step (the first of an advance)
        self.jacobian_may_skip = False
        self._jac_unfactorised = False  # the stored Jacobian awaits its factorisation
        #: fresh Jacobians computed (diagnostics)
        self.jacobian_count = 0
        #: current simulation time [s]
        self.t_s = 0.0
        #: advances solved (a state's identity with :attr:`t_s`)
        self.advance_count = 0

    def solve(self, t_end_s: float, reach_m: float = 0.0) -> bool:
        """Integrate from :attr:`t_s` to ``t_end_s`` in equal steps <= ``step_s``; :attr:`t_s`
        is then where the integration stopped. False: it failed or a PreStep stopped it.
        ``reach_m``: the furthest the car's points get from the origin in this advance [m]
        (Newton's absolute tolerance follows its round-off, see :attr:`ROUNDOFF_SAFETY`)."""
        span = t_end_s - self.t_s
        n = max(1, math.ceil(span / self.step_s - 1e-9))
        it = self._it
        floor = self.ROUNDOFF_SAFETY * self._roundoff_N_per_m * math.ulp(reach_m)
        self._newton.absoluteTolerance = max(self._abs_tol, floor)
        self._ti.endTime = t_end_s
        it.endTime = t_end_s
        it.maxStepSize = span / n
        # keep the stored Jacobian unless the car has turned (the constraint directions and
        # the rotational mass matrix follow the heading; normally renewed already at the end
        # of the previous advance, see _refresh_jacobian), changed its speed (terms of the
        # Jacobian follow it) or its carbody's mass (passengers)
        turned = abs(self.heading_rad - self._jac_heading)
        sped = abs(self.speed_m_per_s - self._jac_speed) > self.JACOBIAN_SPEED_TOL_M_PER_S
        massed = abs(self.carbody_mass_kg - self._jac_mass) > self.JACOBIAN_MASS_TOL * self._jac_mass
        self.jacobian_may_skip = turned <= self.JACOBIAN_HEADING_TOL_RAD and not sped and not massed
        ok = self.main.SolveSteps(self._mbs, self._settings)
        self.t_s = float(it.currentTime)
        self.advance_count += 1
        return ok

    def reached(self, t_end_s: float) -> None:
        """The advance reached ``t_end_s``: the time is that; the Jacobian is renewed there if
        the track turned past :attr:`JACOBIAN_HEADING_TOL_RAD` (``refresh_after_turn``)."""
        self.t_s = float(t_end_s)
        if self._refresh_after_turn and \
                abs(self.heading_rad - self._jac_heading) > self.JACOBIAN_HEADING_TOL_RAD:
            self._refresh_jacobian()  # at the converged state, for the next advance

    def keep_jacobian(self) -> None:
        """At the first step of an advance (SolveSteps has just requested a Jacobian):
        when :meth:`_jacobian` would answer that request with the stored Jacobian, withdraw the
        request instead, so that Newton goes on with the factorisation of that very matrix,
        which the solver still holds, rather than factorising it again (the same LU, bit for
        bit). Later requests (Newton's own) reach :meth:`_jacobian` and get a fresh one. A
        Jacobian stored by :meth:`_refresh_jacobian` has no factorisation yet: the request
        stays, and :meth:`_jacobian` answers it with that matrix."""
        if self._jac_unfactorised:
            return
        self.jacobian_may_skip = False
        conv = self._conv
        h = self._it.currentStepSize
        if conv.jacobianUpdateRequested and self._jac_h is not None and abs(h - self._jac_h) <= 1e-9 * h:
            conv.jacobianUpdateRequested = False

    def _jacobian(self, solver, mbs, settings) -> bool:
        """Newton Jacobian user function of the main solver (see :mod:`vehicle.car`)."""
        h = solver.it.currentStepSize
        if self.jacobian_may_skip and self._jac_h is not None and abs(h - self._jac_h) <= 1e-9 * h:
            self.jacobian_may_skip = False  # later requests in this advance come from Newton
            self._jac_unfactorised = False  # Newton factorises it now
            return True  # keep the stored (already factorizable) Jacobian
        self.jacobian_may_skip = False
        self._store_jacobian(solver, h)
        return True

    def _store_jacobian(self, solver, h: float) -> None:
        """Compute a fresh Newton Jacobian for the step size h at the system's current state
        (with the second solver) and hand it to ``solver``."""
        js = self._jac_solver
        js.it.currentStepSize = h
        # ComputeNewtonJacobian adds the solver's own stored mass matrix: the second solver's
        # would stay the one of t = 0, but the Rxyz mass matrix changes with the rotation (yaw
        # in a curve: 10 % off at 0.1 rad, and Newton diverges)
        js.ComputeMassMatrix(self._mbs)
        js.ComputeNewtonJacobian(self._mbs, self._settings)
        solver.SetSystemJacobian(js.GetSystemJacobian())
        self._jac_h = h
        self._jac_heading = self.heading_rad
        self._jac_speed = self.speed_m_per_s
        self._jac_mass = self.carbody_mass_kg
        self._jac_unfactorised = False
        self.jacobian_count += 1

    def _refresh_jacobian(self) -> None:
        """After an advance through which the track has turned by more than
        :attr:`JACOBIAN_HEADING_TOL_RAD` since the stored Jacobian was computed: a fresh one
        at the converged end state, for the next advance (which factorises it at its first
        request, see :meth:`keep_jacobian`).

        Why there rather than at the next step's first Newton iteration: that iteration starts
        from exudyn's predictor (zero new accelerations); in a curve it is off the solution by
        h^2 beta a in position and h gamma a in velocity (a ~ V^2/R), which with the stiff,
        load-dependent contact law (contact guidance) is far enough for a Jacobian taken
        there to slow the following modified-Newton iterations (contraction ~0.2-0.3 per
        iteration instead of ~0.01 with one taken at a converged state). Contact guidance
        only: with kinematic guidance the predictor's Jacobian serves as well (measured: 3.29
        instead of 3.19 Newton iterations per step on the curve entry when taken here)."""
        self._store_jacobian(self.main, self._it.currentStepSize)
        self._jac_unfactorised = True
