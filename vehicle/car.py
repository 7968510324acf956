"""Exudyn multibody model of the metro car (paper section 4, Table 3) on prescribed rail heights.

Bodies: carbody, two bogie frames, four wheelsets (rigid, 6 coordinates each, Tait-Bryan xyz).
Coordinates: x forward (running direction), y to the left, z up; rail top at z = 0 on level track.

* Primary suspension: one spring-damper per axlebox acting in the bogie frame
  (``RigidBodySpringDamper``), x/y/z stiffness and damping from :class:`VehicleParams`.
* Secondary suspension (airsprings), per bellow:
    - a vertical (global z) force pair F(z) = F_N + dF/dz (z - z_call) pushing the carbody up and
      the bogie down at the upper and lower bellow plates: a ``CartesianSpringDamper`` between the
      plates whose force law is a symbolic user function of the crushing z. A point-to-point
      spring would add a negative lateral stiffness -F/L (design notes);
    - shear stiffness in x and y of the bogie frame (``RigidBodySpringDamper``).
* Wheel-rail contact, per wheel: unilateral Hertz law Q = max(0, C_H delta^1.5 + c d(delta)/dt),
  Q = 0 when delta <= 0, vertical only, acting at a point fixed on the (non-spinning) wheelset
  body below the wheel centre, against the rail height prescribed for that wheel.
* Wheelset guidance (stationary test): coordinate constraints lock x, y, spin and yaw of each
  wheelset; z and roll stay free. A running version replaces
  :meth:`MetroCar._add_wheelset_guidance` (e.g. a GenericJoint to a kinematic track body per
  wheelset); the suspension connectors already act in body frames.

Static equilibrium on level track under :meth:`MetroCar.static_bellow_forces_N` is the *reference
configuration*: bodies sit at their static positions, the primary springs carry their static load
through their offsets and each contact point penetrates its rail by the Hertz deflection, so a run
starts without settling transient.

Force laws are exudyn *symbolic* user functions: they run in C++ (a Python user function costs
~1.5 us per call and the numerical Jacobian calls it 13 times per connector); their inputs (rail
height/rate, bellow force/stiffness) are named symbolic variables set from Python.

Solver: implicit generalized-alpha, driven macro-step by macro-step with
``MainSolverImplicitSecondOrder.SolveSteps`` (no restart: state-exact continuation). SolveSteps
asks for a new Newton Jacobian at every call; a Jacobian user function serves that request with
the previous Jacobian when the step size is unchanged (the bellow stiffness is ~1e-4 of the
effective mass stiffness M/(beta h^2), so it never matters) and computes a fresh one, with a
second solver object on the same system, whenever Newton itself asks (e.g. a wheel lifts).
"""
from __future__ import annotations

import math
from typing import Callable

import exudyn as exu
import numpy as np
from exudyn.advancedUtilities import CreateSymbolicUserFunction
from exudyn.rigidBodyUtilities import RigidBodyInertia

from .params import VehicleParams

BELLOWS = ("FL", "FR", "RL", "RR")
WHEELS = ("1L", "1R", "2L", "2R", "3L", "3R", "4L", "4R")

#: exudyn minor version this module was written and measured against (the API changes between
#: minor versions; tests/test_vehicle.py fails loudly on any other)
EXUDYN_TESTED_MINOR = "1.13"

_OUT = exu.OutputVariableType
esym = exu.symbolic


class MetroCar:
    """Metro car standing on rails whose heights are prescribed wheel by wheel.

    Args:
        params: vehicle parameters (SI).
        rail_height_m: ``rail_height_m(t_s) -> (8,)`` vertical rail height [m] under each wheel
            in :data:`WHEELS` order, 0 = level; ``None`` = level track. Evaluated at the end of
            every internal time step (the contact damping uses the mean rail rate over the
            step). It should be 0 at t = 0 for a transient-free start.
        step_s: largest internal time step [s]; every :meth:`advance` is split into equal steps
            not larger than this.
        spectral_radius: generalized-alpha spectral radius at infinite frequency, 0 < rho <= 1
            (numerical damping of the ~250 Hz wheelset-on-contact modes).
        newton_abs_tol: Newton absolute tolerance on the residual (force scale [N]).
        newton_rel_tol: Newton tolerance relative to the initial residual of the step.
        reuse_jacobian: reuse the Newton Jacobian across :meth:`advance` calls (see module doc).
    """

    def __init__(self, params: VehicleParams,
                 rail_height_m: Callable[[float], np.ndarray] | None = None,
                 step_s: float = 5e-3, *, spectral_radius: float = 0.8,
                 newton_abs_tol: float = 1e-4, newton_rel_tol: float = 1e-8,
                 reuse_jacobian: bool = True):
        if not step_s > 0.0:
            raise ValueError(f"step_s must be > 0, got {step_s}")
        self.params = params
        self.step_s = float(step_s)
        self._rail_fn = rail_height_m
        p = params
        g = p.gravity_m_per_s2
        # --- static loads on level track (the car is symmetric) ---
        self._F_static_N = p.carbody_mass_kg * g / 4.0
        self._P_axlebox_N = (p.carbody_mass_kg * g / 2.0 + p.bogie_mass_kg * g) / 4.0
        #: static vertical wheel load on level track [N]
        self.Q_static_N = self._P_axlebox_N + p.wheelset_mass_kg * g / 2.0
        self._delta_static_m = (self.Q_static_N / p.hertz_constant_N_per_m1_5) ** (2.0 / 3.0)
        # --- geometry at static equilibrium ---
        a = p.wheelbase_m / 2.0
        xb = p.bogie_centre_distance_m / 2.0
        #: bogie centre x [m], front then rear
        self.bogie_x_m = np.array([xb, -xb])
        #: wheelset centre x [m], wheelsets 1..4 from the front
        self.wheelset_x_m = np.array([xb + a, xb - a, -xb + a, -xb - a])
        self._z_wheelset_m = p.wheel_radius_m - self._delta_static_m
        self._bellow_height_m = p.airspring_upper_height_m - p.airspring_lower_height_m
        if self._bellow_height_m <= 0.0:
            raise ValueError("airspring_upper_height_m must exceed airspring_lower_height_m")

        rail0 = np.zeros(8) if rail_height_m is None else self._rail_at(0.0)
        self._rail_cache = (0.0, rail0)  # (t, heights) of the last preStep evaluation

        self.SC = exu.SystemContainer()
        self.mbs = self.SC.AddSystem()
        self._build(rail0)
        self.mbs.Assemble()
        self._init_solver(spectral_radius, newton_abs_tol, newton_rel_tol, reuse_jacobian)

        self._bellow_t = None  # time of the cached bellow crushing

    # ================================================================== model
    def _build(self, rail0: np.ndarray) -> None:
        p, mbs = self.params, self.mbs
        gravity = [0.0, 0.0, -p.gravity_m_per_s2]

        def body(m, ixx, iyy, izz, pos):
            return mbs.CreateRigidBody(
                inertia=RigidBodyInertia(mass=m, inertiaTensor=np.diag([ixx, iyy, izz]),
                                         inertiaTensorAtCOM=True),
                referencePosition=pos, gravity=gravity, nodeType=exu.NodeType.RotationRxyz)

        self._ground = mbs.CreateGround()
        self._carbody = body(p.carbody_mass_kg, p.carbody_inertia_xx_kg_m2,
                             p.carbody_inertia_yy_kg_m2, p.carbody_inertia_zz_kg_m2,
                             [0.0, 0.0, p.carbody_cog_height_m])
        self._bogies = [body(p.bogie_mass_kg, p.bogie_inertia_xx_kg_m2, p.bogie_inertia_yy_kg_m2,
                             p.bogie_inertia_zz_kg_m2, [x, 0.0, p.bogie_cog_height_m])
                        for x in self.bogie_x_m]
        self._wheelsets = [body(p.wheelset_mass_kg, p.wheelset_inertia_xx_kg_m2,
                                p.wheelset_inertia_yy_kg_m2, p.wheelset_inertia_zz_kg_m2,
                                [x, 0.0, self._z_wheelset_m])
                           for x in self.wheelset_x_m]
        self._sym = []  # symbolic variables and functions: must live as long as the system
        for iw in range(4):
            self._add_wheelset_guidance(iw)
            self._add_primary(iw)
        for k in range(4):
            self._add_airspring(k)
        for j in range(8):
            self._add_contact(j, rail0[j])

    def _add_wheelset_guidance(self, iw: int) -> None:
        """Stationary guidance of wheelset ``iw``: x, y, spin (ry) and yaw (rz) locked to ground.

        The replacement point for a running vehicle (track-following kinematic body)."""
        node = self.mbs.GetObject(self._wheelsets[iw])["nodeNumber"]
        for coordinate in (0, 1, 4, 5):  # Rxyz node: x, y, z, rx, ry, rz
            self.mbs.CreateCoordinateConstraint(itemNumbers=[None, node],
                                                coordinates=[None, coordinate], show=False)

    def _add_primary(self, iw: int) -> None:
        """Left and right axlebox springs between bogie frame and wheelset ``iw`` (bogie axes).

        Displacement u = 0 at the static position; the z offset carries the static axlebox load
        P (force on the wheelset -K (u - offset) = -P e_z)."""
        p = self.params
        ib = iw // 2
        K = np.diag([p.primary_stiffness_x_N_per_m, p.primary_stiffness_y_N_per_m,
                     p.primary_stiffness_z_N_per_m, 0.0, 0.0, 0.0])
        D = np.diag([p.primary_damping_x_N_s_per_m, p.primary_damping_y_N_s_per_m,
                     p.primary_damping_z_N_s_per_m, 0.0, 0.0, 0.0])
        off_z = -self._P_axlebox_N / p.primary_stiffness_z_N_per_m
        for y in (p.primary_lateral_spacing_m / 2.0, -p.primary_lateral_spacing_m / 2.0):
            self.mbs.CreateRigidBodySpringDamper(
                itemNumbers=[self._bogies[ib], self._wheelsets[iw]],
                localPosition0=[self.wheelset_x_m[iw] - self.bogie_x_m[ib], y,
                                self._z_wheelset_m - p.bogie_cog_height_m],
                localPosition1=[0.0, y, 0.0],
                stiffness=K, damping=D, offset=[0.0, 0.0, off_z, 0.0, 0.0, 0.0],
                useIntrinsicFormulation=False, show=False)

    def _bellow_plates(self, k: int) -> tuple[list[float], list[float]]:
        """Local positions of bellow ``k``'s lower plate (bogie) and upper plate (carbody)."""
        p = self.params
        ib = k // 2
        y = p.airspring_lateral_spacing_m / 2.0 * (1.0 if BELLOWS[k][1] == "L" else -1.0)
        lower = [0.0, y, p.airspring_lower_height_m - p.bogie_cog_height_m]
        upper = [float(self.bogie_x_m[ib]), y,
                 p.airspring_upper_height_m - p.carbody_cog_height_m]
        return lower, upper

    def _add_airspring(self, k: int) -> None:
        """Bellow ``k``: vertical force law (symbolic) and shear stiffness (bogie frame)."""
        p, mbs = self.params, self.mbs
        bogie = self._bogies[k // 2]
        lower, upper = self._bellow_plates(k)
        F = esym.Real(f"F{k}", self._F_static_N)  # force at z = z0 [N]
        K = esym.Real(f"K{k}", 0.0)  # dF/dz [N/m]
        z0 = esym.Real(f"z0_{k}", 0.0)  # crushing at the last set_bellow_forces [m]

        # displacement = p_upper - p_lower - offset, offset = nominal height: crushing z = -d_z;
        # the connector force f acts as -f on the upper plate (carbody), +f on the lower (bogie)
        def bellow_force(mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset):
            return [0.0, 0.0, -(F + K * (-displacement[2] - z0))]

        co = mbs.CreateCartesianSpringDamper(
            itemNumbers=[bogie, self._carbody], localPosition0=lower, localPosition1=upper,
            offset=[0.0, 0.0, self._bellow_height_m], show=False)
        fn = CreateSymbolicUserFunction(mbs, bellow_force, "springForceUserFunction", co)
        mbs.SetObjectParameter(co, "springForceUserFunction", fn)
        ks = p.bellow_shear_stiffness_N_per_m
        mbs.CreateRigidBodySpringDamper(
            itemNumbers=[bogie, self._carbody], localPosition0=lower, localPosition1=upper,
            stiffness=np.diag([ks, ks, 0.0, 0.0, 0.0, 0.0]), damping=np.zeros((6, 6)),
            offset=[0.0, 0.0, self._bellow_height_m, 0.0, 0.0, 0.0],
            useIntrinsicFormulation=False, show=False)
        if k == 0:
            self._bellows, self._bellow_vars = [], []
        self._bellows.append(co)
        self._bellow_vars.append((F, K, z0))
        self._sym.append(fn)

    def _add_contact(self, j: int, rail0_m: float) -> None:
        """Wheel ``WHEELS[j]``: unilateral Hertz contact against its prescribed rail height.

        Connector displacement u = p_contact - p_rail_base (global), rail base at z = 0, so the
        penetration is delta = rail_height - u_z."""
        p = self.params
        C, c = p.hertz_constant_N_per_m1_5, p.contact_damping_N_s_per_m
        name = WHEELS[j]
        iw = int(name[0]) - 1
        y = p.contact_spacing_m / 2.0 * (1.0 if name[1] == "L" else -1.0)
        rz = esym.Real(f"rail_z{j}", float(rail0_m))  # rail height [m]
        rv = esym.Real(f"rail_v{j}", 0.0)  # rail vertical rate [m/s]
        zero = esym.Real(0.0)

        def contact_force(mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset):
            delta = rz - displacement[2]  # IfThenElse evaluates only the selected branch
            q = esym.max(C * delta * esym.sqrt(delta) + c * (rv - velocity[2]), zero)
            return [0.0, 0.0, -esym.IfThenElse(delta > 0.0, q, zero)]  # on the wheel: +Q e_z

        co = self.mbs.CreateCartesianSpringDamper(
            itemNumbers=[self._ground, self._wheelsets[iw]],
            localPosition0=[float(self.wheelset_x_m[iw]), y, 0.0],
            localPosition1=[0.0, y, -p.wheel_radius_m], show=False)
        fn = CreateSymbolicUserFunction(self.mbs, contact_force, "springForceUserFunction", co)
        self.mbs.SetObjectParameter(co, "springForceUserFunction", fn)
        if j == 0:
            self._contacts, self._rail_vars = [], []
        self._contacts.append(co)
        self._rail_vars.append((rz, rv))
        self._sym += [fn, zero]

    # ================================================================== rail
    def _rail_at(self, t: float) -> np.ndarray:
        h = np.asarray(self._rail_fn(t), dtype=float)
        if h.shape != (8,):
            raise ValueError(f"rail_height_m(t) must return shape (8,), got {h.shape}")
        return h

    def _pre_step(self, mbs, t: float) -> bool:
        """PreStep user function: rail heights at the step end t, mean rate over the step."""
        t0 = mbs.systemData.GetTime(exu.ConfigurationType.StartOfStep)
        tc, zc = self._rail_cache
        z0 = zc if t0 == tc else self._rail_at(t0)
        z1 = self._rail_at(t)
        v = (z1 - z0) / (t - t0) if t > t0 else np.zeros(8)
        for (rz, rv), zj, vj in zip(self._rail_vars, z1.tolist(), v.tolist()):
            rz.SetValue(zj)
            rv.SetValue(vj)
        self._rail_cache = (t, z1)
        return True

    # ================================================================== solver
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
        if self._rail_fn is not None:
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
        self._jac_h = None  # step size of the stored Jacobian
        self._jac_may_skip = False
        self.jacobian_count = 0  # fresh Jacobians computed (diagnostics)
        self._t = 0.0

    def _jacobian(self, solver, mbs, settings) -> bool:
        """Newton Jacobian user function of the main solver (see module doc)."""
        h = solver.it.currentStepSize
        if self._jac_may_skip and self._jac_h is not None and abs(h - self._jac_h) <= 1e-9 * h:
            self._jac_may_skip = False  # later requests in this advance come from Newton
            return True  # keep the stored (already factorizable) Jacobian
        self._jac_may_skip = False
        js = self._jac_solver
        js.it.currentStepSize = h
        js.ComputeNewtonJacobian(mbs, settings)
        solver.SetSystemJacobian(js.GetSystemJacobian())
        self._jac_h = h
        self.jacobian_count += 1
        return True

    # ================================================================== interface
    def static_bellow_forces_N(self) -> np.ndarray:
        """(4,) airspring forces [N] carrying the carbody in static equilibrium on level track."""
        return np.full(4, self._F_static_N)

    @property
    def t_s(self) -> float:
        """Current simulation time [s]."""
        return self._t

    def _bellow_state(self) -> None:
        """Crushing and rate of the bellows at the current state (cached per time)."""
        if self._bellow_t == self._t:
            return
        get = self.mbs.GetObjectOutput
        # connector displacement = p_upper - p_lower - nominal height = -z
        self._z = np.array([-get(co, _OUT.Displacement)[2] for co in self._bellows])
        self._zdot = np.array([-get(co, _OUT.Velocity)[2] for co in self._bellows])
        self._bellow_t = self._t

    def bellow_crushing(self) -> tuple[np.ndarray, np.ndarray]:
        """Bellow crushing z [m] and its rate [m/s], each (4,) in :data:`BELLOWS` order.

        z = nominal bellow height - (z_upper_plate - z_lower_plate), global vertical, positive in
        compression, 0 at static equilibrium on level track (bellow at nominal height)."""
        self._bellow_state()
        return self._z.copy(), self._zdot.copy()

    def set_bellow_forces(self, F_N: np.ndarray, dF_dz_N_per_m: np.ndarray | None = None) -> None:
        """Airspring forces [N] for the following :meth:`advance`, (4,) in :data:`BELLOWS` order.

        F(z) = F_N + dF_dz (z - z_now): a vertical force pair pushing the carbody up and the
        bogie down; ``dF_dz`` [N/m] is the instantaneous pneumatic stiffness (linearised
        implicit coupling), ``None`` = 0 (force held constant). z_now is the crushing of
        :meth:`bellow_crushing` at the current state, so pass F_N for the current state.

        Note: a jump of F_N between macro-steps enters generalized-alpha with about half an
        internal step of delay (the step starts from the old acceleration); smooth force
        histories, as from a pneumatic model, are not affected."""
        F = np.asarray(F_N, dtype=float).reshape(4)
        dF = np.zeros(4) if dF_dz_N_per_m is None else np.asarray(dF_dz_N_per_m, float).reshape(4)
        if not (np.all(np.isfinite(F)) and np.all(np.isfinite(dF))):
            raise ValueError(f"non-finite bellow force or stiffness: F={F}, dF/dz={dF}")
        self._bellow_state()
        for (Fv, Kv, z0v), Fk, Kk, zk in zip(self._bellow_vars, F.tolist(), dF.tolist(),
                                             self._z.tolist()):
            Fv.SetValue(Fk)
            Kv.SetValue(Kk)
            z0v.SetValue(zk)

    def advance(self, t_end_s: float) -> None:
        """Integrate from :attr:`t_s` to ``t_end_s`` [s] in equal steps <= ``step_s``."""
        span = t_end_s - self._t
        if span < -1e-12:
            raise ValueError(f"advance: t_end_s={t_end_s} is before t_s={self._t}")
        if span <= 1e-12:
            return
        n = max(1, math.ceil(span / self.step_s - 1e-9))
        it = self._it
        self._ti.endTime = t_end_s
        it.endTime = t_end_s
        it.maxStepSize = span / n
        self._jac_may_skip = True
        ok = self._solver.SolveSteps(self.mbs, self._settings)
        self._t = float(it.currentTime)
        if not ok:
            raise RuntimeError(f"exudyn: time integration failed at t={self._t} s "
                               f"(advance to {t_end_s} s)")
        self._t = float(t_end_s)

    def wheel_loads_N(self) -> np.ndarray:
        """(8,) vertical wheel-rail forces Q >= 0 [N] at the current state, :data:`WHEELS` order."""
        get = self.mbs.GetObjectOutput
        # the contact connector's force f acts as -f = +Q e_z on the wheel
        return np.array([-get(co, _OUT.Force)[2] for co in self._contacts])

    def carbody_roll_rad(self) -> float:
        """Carbody roll angle [rad], right-hand about x (forward): positive = left side up."""
        A = np.asarray(self.mbs.GetObjectOutputBody(self._carbody, _OUT.RotationMatrix))
        A = A.reshape(3, 3)
        return float(math.atan2(A[2, 1], A[2, 2]))
