"""The solver and the reuse of its Newton Jacobian across macro-steps (:class:`JacobianReuse`,
a part of :class:`~vehicle.car.MetroCar`; why and when it is kept: :mod:`vehicle.car`, "Solver")."""
from __future__ import annotations

import exudyn as exu


class JacobianReuse:
    """The generalized-alpha solver driven step by step, its Jacobian kept while it serves."""

    #: the stored Newton Jacobian is renewed at the next macro-step once the track heading has
    #: changed by more than this since it was computed [rad] (see :meth:`advance`; with contact
    #: guidance at the end of the macro-step that turned past it, see :meth:`_refresh_jacobian`)
    JACOBIAN_HEADING_TOL_RAD = 0.01

    def _init_solver(self, rho: float, abs_tol: float, rel_tol: float, reuse: bool) -> None:
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
        ti.generalizedAlpha.spectralRadius = rho
        ti.newton.useModifiedNewton = True
        ti.newton.absoluteTolerance = abs_tol
        ti.newton.relativeTolerance = rel_tol
        self._settings = s
        self._reuse_jacobian = reuse
        self.mbs.SetPreStepUserFunction(self._pre_step)
        if reuse:
            # a second solver on the same system computes fresh Jacobians on demand (calling the
            # main solver's ComputeNewtonJacobian from its own user function would recurse)
            self._jac_solver = exu.MainSolverImplicitSecondOrder()
            if not self._jac_solver.InitializeSolver(self.mbs, s):
                raise RuntimeError("exudyn: InitializeSolver failed")
        self._solver = exu.MainSolverImplicitSecondOrder()
        if not self._solver.InitializeSolver(self.mbs, s):
            raise RuntimeError("exudyn: InitializeSolver failed")
        if reuse:
            self._solver.SetUserFunctionComputeNewtonJacobian(self.mbs, self._jacobian)
        self._ti = s.timeIntegration  # handles (references into the C++ objects)
        self._it = self._solver.it
        self._conv = self._solver.conv
        self._jac_h = None  # step size of the stored Jacobian
        self._jac_heading = 0.0  # track heading under wheelset 1 when it was computed [rad]
        self._heading_now = 0.0  # track heading under wheelset 1 at the last step end [rad]
        self._jac_may_skip = False
        self._jac_unfactorised = False  # the stored Jacobian awaits its factorisation
        self.jacobian_count = 0  # fresh Jacobians computed (diagnostics)
        self._t = 0.0

    def _keep_jacobian(self) -> None:
        """At the first step of an :meth:`advance` (SolveSteps has just requested a Jacobian):
        when :meth:`_jacobian` would answer that request with the stored Jacobian, withdraw the
        request instead, so that Newton goes on with the factorisation of that very matrix,
        which the solver still holds, rather than factorising it again (the same LU, bit for
        bit). Later requests (Newton's own) reach :meth:`_jacobian` and get a fresh one. A
        Jacobian stored by :meth:`_refresh_jacobian` has no factorisation yet: the request
        stays, and :meth:`_jacobian` answers it with that matrix."""
        if self._jac_unfactorised:
            return
        self._jac_may_skip = False
        conv = self._conv
        h = self._it.currentStepSize
        if conv.jacobianUpdateRequested and self._jac_h is not None and abs(h - self._jac_h) <= 1e-9 * h:
            conv.jacobianUpdateRequested = False

    def _jacobian(self, solver, mbs, settings) -> bool:
        """Newton Jacobian user function of the main solver (see module doc)."""
        h = solver.it.currentStepSize
        if self._jac_may_skip and self._jac_h is not None and abs(h - self._jac_h) <= 1e-9 * h:
            self._jac_may_skip = False  # later requests in this advance come from Newton
            self._jac_unfactorised = False  # Newton factorises it now
            return True  # keep the stored (already factorizable) Jacobian
        self._jac_may_skip = False
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
        js.ComputeMassMatrix(self.mbs)
        js.ComputeNewtonJacobian(self.mbs, self._settings)
        solver.SetSystemJacobian(js.GetSystemJacobian())
        self._jac_h = h
        self._jac_heading = self._heading_now
        self._jac_unfactorised = False
        self.jacobian_count += 1

    def _refresh_jacobian(self) -> None:
        """After an :meth:`advance` through which the track has turned by more than
        :attr:`JACOBIAN_HEADING_TOL_RAD` since the stored Jacobian was computed: a fresh one
        at the converged end state, for the next advance (which factorises it at its first
        request, see :meth:`_keep_jacobian`).

        Why there rather than at the next step's first Newton iteration: that iteration starts
        from exudyn's predictor (zero new accelerations); in a curve it is off the solution by
        h^2 beta a in position and h gamma a in velocity (a ~ V^2/R), which with the stiff,
        load-dependent contact law (contact guidance) is far enough for a Jacobian taken
        there to slow the following modified-Newton iterations (contraction ~0.2-0.3 per
        iteration instead of ~0.01 with one taken at a converged state). Contact guidance
        only: with kinematic guidance the predictor's Jacobian serves as well (measured: 3.29
        instead of 3.19 Newton iterations per step on the curve entry when taken here)."""
        self._store_jacobian(self._solver, self._it.currentStepSize)
        self._jac_unfactorised = True
