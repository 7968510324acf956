"""A single free wheelset running on track with wheel-rail contact forces: an exudyn model.
The force law is :mod:`vehicle.wheelrail.contact_law`.

Model
-----
* **Moving reference frame**: all coordinates are relative to the track frame, which runs along
  the track centre line at the constant speed V (and on a curve turns at kappa V). The forward
  motion is carried by the frame: the wheelset's x coordinate is held at 0 by a coordinate
  constraint (its reaction is the longitudinal force needed to keep V). The frame's inertial
  effects (the centrifugal force; its turn rate kappa V in the creepages and the gyroscopic
  moment) are in the force law. Curvature may vary with the distance run (a transition): it
  enters only through these terms, the frame is not a track geometry.
* **Wheelset**: an exudyn rigid body with a ``RotationRxyz`` node, coordinates (x, y, z, roll,
  pitch, yaw), that does not spin: pitch is held at 0 by a coordinate constraint, so the body is
  the non-rotating frame the contact acts on. The rotation about the axle is a separate
  one-coordinate node (``NodeGenericODE2``, angle beta) with the spin inertia; the creep forces'
  moment about the axle drives it, and the gyroscopic moments of the spin act on the body.
  Gravity and the axle load (the bogie's share, a constant vertical force) are ordinary loads.
* **Contact**: one ``ObjectGenericODE2`` on the body node and the spin node (no mass of its
  own) whose force user function is the contact law of both wheels: Hertz normal force along
  the contact normal, Kalker linear creep forces with Shen-Hedrick-Elkins saturation.
* **Table lookup**: the law's table (:class:`~vehicle.wheelrail.contact_law.ContactLawTable`:
  the contact table smoothed over 0.1 mm, 2401 rows every 0.01 mm) enters piecewise linearly
  in y: before every step (PreStep user function) the table interval holding the wheelset's
  current y is looked up and its start value and slope handed to the law (only when the interval
  changed: ~450 times per simulated second at 10 m/s and 3 mm amplitude); inside the step the
  law uses value + slope (y - y_i), exact on that interval and extrapolated beyond it for the
  rest of the step (y moves up to ~0.04 mm per 2 ms step at 3 mm amplitude, across a few
  intervals of the smoothed table, whose slope changes little between them). exudyn's symbolic
  expressions cannot index a table by a state; this way they need not. A wheelset leaving the
  table stops the run with an error.
* **Force law as user function**: ``force_law="python"`` (default) calls
  :func:`~vehicle.wheelrail.contact_law.generalized_forces` with float math as a Python user
  function; ``"symbolic"`` records the same function as an exudyn symbolic user function (an
  expression tree evaluated in C++), with the table interval and the curvature as named
  symbolic variables. Measured (``benchmarks/bench_wheelset.py``): one call costs 30 us in
  Python and 140 us symbolic. exudyn 1.13's symbolic trees have no shared subexpressions: every
  use of N, the creepages or the saturation factor is evaluated again. Assembled the natural way
  (forces, moments, then their projections) one symbolic call took 9 ms; the coefficient form
  of ``generalized_forces`` (every expensive quantity once per coordinate) brought it to 140 us,
  still 4-5 times the Python function, whose ~200 float operations cost less than the tree walk.

Units SI; frames and signs as in :mod:`vehicle.wheelrail.contact_law` (x forward, y left, z up).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Callable

import exudyn as exu
import numpy as np
from exudyn.rigidBodyUtilities import RigidBodyInertia
from scipy.optimize import fsolve

from .contact_law import (
    GEOMETRY_COLUMNS,
    NUMPY,
    SCALAR,
    ContactLawTable,
    WheelContact,
    WheelsetParams,
    WheelsetState,
    generalized_forces,
    wheelset_forces,
)
from .geometry import ContactTable

__all__ = ["FreeWheelset", "WheelsetRun", "symbolic_ops"]

esym = exu.symbolic
_OUT = exu.OutputVariableType


class _SymbolicOps:
    """exudyn symbolic operations for the contact law (see contact_law's ``ops``)."""

    sqrt = staticmethod(esym.sqrt)
    sin = staticmethod(esym.sin)
    cos = staticmethod(esym.cos)
    pow = staticmethod(esym.pow)
    where = staticmethod(esym.IfThenElse)
    max = staticmethod(esym.max)
    min = staticmethod(esym.min)

    @staticmethod
    def const(x):
        return esym.Real(float(x))


symbolic_ops = _SymbolicOps()


@dataclass
class WheelsetRun:
    """Time series of a run (track-frame coordinates, see contact_law.WheelsetState)."""

    t: np.ndarray
    y: np.ndarray
    z: np.ndarray
    roll: np.ndarray
    yaw: np.ndarray
    y_t: np.ndarray
    z_t: np.ndarray
    roll_t: np.ndarray
    yaw_t: np.ndarray
    spin_t: np.ndarray
    kappa: np.ndarray
    speed_m_per_s: float
    wall_s: float  # wall time of the time integration
    steps: int

    def state(self) -> WheelsetState:
        return WheelsetState(self.y, self.z, self.roll, self.yaw, self.y_t, self.z_t,
                             self.roll_t, self.yaw_t, self.spin_t)

    @property
    def distance_m(self) -> np.ndarray:
        return self.speed_m_per_s * self.t


class FreeWheelset:
    """A free wheelset (no suspension) on track; see the module docstring.

    Args:
        table: the contact geometry (:class:`ContactTable`, e.g. ``ContactTable.default()`` or
            ``ContactTable.cone(0.05)``) or a prepared :class:`ContactLawTable`.
        params: wheelset and contact parameters.
        speed_m_per_s: V > 0 (the creepages are relative to it).
        curvature_per_m: track curvature (1/m, > 0 turns left), constant or a function of the
            distance run s = V t (e.g. a transition); no cant.
        y0_m, yaw0_rad: initial lateral displacement and yaw; the wheelset starts at rest
            laterally, at its static vertical/roll equilibrium on the contact, rolling freely.
        step_s: time step of the implicit integrator (generalized-alpha).
        spectral_radius: its numerical damping at high frequency (the wheelset-on-contact
            bounce/roll modes at ~250 Hz and the creep relaxation, ~1e-4 s at low speed).
        force_law: "python" (Python user function, the faster here) or "symbolic" (exudyn
            symbolic user function; the same law, see the module docstring).
        newton_abs_tol: Newton's absolute tolerance on the residual (N).

    A prepared :class:`ContactLawTable` must have been built with the same ``params`` (its creep
    coefficients use their G and nu).
    """

    def __init__(self, table: ContactTable | ContactLawTable, params: WheelsetParams | None = None,
                 *, speed_m_per_s: float = 5.0,
                 curvature_per_m: float | Callable[[float], float] = 0.0,
                 y0_m: float = 0.0, yaw0_rad: float = 0.0, step_s: float = 2e-3,
                 spectral_radius: float = 0.5, force_law: str = "python",
                 newton_abs_tol: float = 1e-2):
        self.params = p = params or WheelsetParams()
        self.law_table = (table if isinstance(table, ContactLawTable)
                          else ContactLawTable(table, p))
        self.N_ref = self.law_table.reference_load_N
        if not (math.isfinite(speed_m_per_s) and speed_m_per_s > 0):
            raise ValueError("speed_m_per_s must be positive (creepages are relative to V)")
        if force_law not in ("symbolic", "python"):
            raise ValueError("force_law must be 'symbolic' or 'python'")
        if not step_s > 0:
            raise ValueError("step_s must be positive")
        self.V = float(speed_m_per_s)
        self._kappa_fn = (curvature_per_m if callable(curvature_per_m)
                          else (lambda s, k=float(curvature_per_m): k))
        self.step_s = float(step_s)
        self.force_law = force_law
        self.rho = float(spectral_radius)
        self.newton_abs_tol = float(newton_abs_tol)
        t = self.law_table.table
        self.r0 = t.r0
        self.b = t.contact_half_spacing
        lo, hi = self.law_table.y_range_m
        if not lo < y0_m < hi:
            raise ValueError("y0_m outside the contact table")
        self.segment_changes = 0
        self._ran = False
        self._build(float(y0_m), float(yaw0_rad))

    # ------------------------------------------------------------------ model
    def static_state(self, y: float, yaw: float = 0.0, kappa: float = 0.0) -> WheelsetState:
        """Vertical and roll equilibrium on the contact at lateral y (at rest laterally, rolling
        freely): solves the force law's z and roll balance against gravity and axle load."""
        p, V = self.params, self.V
        geo = self.law_table.geometry(y)
        spin = V * (2.0 - kappa * (geo["yc_L"] + geo["yc_R"])) / (geo["r_L"] + geo["r_R"])
        W = p.axle_load_N + p.mass_kg * p.gravity_m_per_s2
        delta0 = (0.5 * W / p.hertz_constant_N_per_m1_5) ** (2.0 / 3.0)

        def state(x):
            return WheelsetState(y, geo["dz0"] - delta0 + x[0] * 1e-6, geo["roll0"] + x[1] * 1e-6,
                                 yaw, 0.0, 0.0, 0.0, 0.0, spin)

        def residual(x):
            Q = generalized_forces(SCALAR, state(x), geo, V, kappa, p, self.N_ref)
            return [(Q[2] - W) / W, Q[3] / (W * self.b)]

        x, _, ok, msg = fsolve(residual, [0.0, 0.0], xtol=1e-10, full_output=True)
        if ok != 1:
            raise RuntimeError(f"static contact equilibrium not found: {msg}")
        return state(x)

    def _build(self, y0: float, yaw0: float) -> None:
        p = self.params
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        self.SC, self.mbs = SC, mbs
        st0 = self.static_state(y0, yaw0, self._kappa_fn(0.0))
        self.initial_state = st0
        body = mbs.CreateRigidBody(
            inertia=RigidBodyInertia(mass=p.mass_kg,
                                     inertiaTensor=np.diag([p.roll_inertia_kg_m2,
                                                            p.spin_inertia_kg_m2,
                                                            p.yaw_inertia_kg_m2]),
                                     inertiaTensorAtCOM=True),
            referencePosition=[0.0, 0.0, self.r0], gravity=[0.0, 0.0, -p.gravity_m_per_s2],
            nodeType=exu.NodeType.RotationRxyz)
        nb = mbs.GetObject(body)["nodeNumber"]
        mbs.SetNodeParameter(nb, "initialCoordinates",
                             [0.0, st0.y, st0.z, st0.roll, 0.0, st0.yaw])
        ns = mbs.AddNode(exu.itemInterface.NodeGenericODE2(
            referenceCoordinates=[0.0], initialCoordinates=[0.0],
            initialCoordinates_t=[float(st0.spin_t)], numberOfODE2Coordinates=1))
        mbs.AddObject(exu.itemInterface.ObjectGenericODE2(
            nodeNumbers=[ns], massMatrix=np.array([[p.spin_inertia_kg_m2]])))
        # x (forward, carried by the frame) and pitch (the body does not spin) held at 0
        ng = mbs.AddNode(exu.itemInterface.NodePointGround())
        mg = mbs.AddMarker(exu.itemInterface.MarkerNodeCoordinate(nodeNumber=ng, coordinate=0))
        for k in (0, 4):
            mk = mbs.AddMarker(exu.itemInterface.MarkerNodeCoordinate(nodeNumber=nb,
                                                                      coordinate=k))
            mbs.AddObject(exu.itemInterface.ObjectConnectorCoordinate(markerNumbers=[mg, mk]))
        mbs.CreateForce(itemNumber=body, loadVector=[0.0, 0.0, -p.axle_load_N])
        self.body, self.node, self.spin_node = body, nb, ns
        self.contact = mbs.AddObject(exu.itemInterface.ObjectGenericODE2(nodeNumbers=[nb, ns]))
        # geometry segment and curvature: the PreStep function sets these
        i, yi, v, s = self.law_table.segment(st0.y)
        self._seg = i
        self._kappa_now = float(self._kappa_fn(0.0))
        if self.force_law == "symbolic":
            self._build_symbolic(yi, v, s)
        else:
            self._py_state = {"yi": yi, "v": v.copy(), "s": s.copy(), "kappa": self._kappa_now}
            mbs.SetObjectParameter(self.contact, "forceUserFunction", self._python_force)
        mbs.SetPreStepUserFunction(self._pre_step)
        self._sensors = [
            mbs.AddSensor(exu.itemInterface.SensorNode(nodeNumber=nb, storeInternal=True,
                                                       outputVariableType=_OUT.Coordinates)),
            mbs.AddSensor(exu.itemInterface.SensorNode(nodeNumber=nb, storeInternal=True,
                                                       outputVariableType=_OUT.Coordinates_t)),
            mbs.AddSensor(exu.itemInterface.SensorNode(nodeNumber=ns, storeInternal=True,
                                                       outputVariableType=_OUT.Coordinates_t)),
        ]
        mbs.Assemble()

    def _build_symbolic(self, yi: float, v: np.ndarray, s: np.ndarray) -> None:
        mbs = self.mbs
        self._sym_yi = esym.Real("y_seg", yi)
        self._sym_v = [esym.Real(f"{n}_0", float(v[j])) for j, n in enumerate(GEOMETRY_COLUMNS)]
        self._sym_s = [esym.Real(f"{n}_s", float(s[j])) for j, n in enumerate(GEOMETRY_COLUMNS)]
        self._sym_kappa = esym.Real("kappa", self._kappa_now)
        rec = esym.GetRecording()
        esym.SetRecording(True)
        try:
            t = esym.Real("t", 0.0)
            item = esym.Real("itemNumber", 0)
            q = esym.Vector("q", [0.0] * 7)
            q_t = esym.Vector("q_t", [0.0] * 7)
            st = WheelsetState(q[1], q[2], q[3], q[5], q_t[1], q_t[2], q_t[3], q_t[5], q_t[6])
            dy = st.y - self._sym_yi
            geo = {n: self._sym_v[j] + self._sym_s[j] * dy for j, n in enumerate(GEOMETRY_COLUMNS)}
            geo["droll0"] = self._sym_s[GEOMETRY_COLUMNS.index("roll0")]
            geo["ddz0"] = self._sym_s[GEOMETRY_COLUMNS.index("dz0")]
            Q = generalized_forces(symbolic_ops, st, geo, self.V, self._sym_kappa, self.params,
                                   self.N_ref)
            ret = esym.Vector([v if isinstance(v, esym.Real) else esym.Real(float(v)) for v in Q])
        finally:
            esym.SetRecording(rec)
        fn_dict = {"functionName": "wheelset_contact_force",
                   "argList": [mbs, t, item, q, q_t],
                   "argTypeList": ["MainSystem", "Real", "Index", "StdVector", "StdVector"],
                   "returnValue": ret, "returnType": "StdVector"}
        fn = esym.UserFunction()
        # exudyn's CreateSymbolicUserFunction records StdVector arguments with length 0, which
        # cannot be indexed: the dict is built here with q, q_t of the element's 7 coordinates
        fn.SetUserFunctionFromDict(mbs, fn_dict, "forceUserFunction", self.contact, "None")
        mbs.SetObjectParameter(self.contact, "forceUserFunction", fn)
        self._sym_keep = [fn, ret, q, q_t, t, item]  # expression trees must outlive the system

    def _python_force(self, mbs, t, itemNumber, q, q_t):
        d = self._py_state
        dy = q[1] - d["yi"]
        vals = d["v"] + d["s"] * dy
        geo = dict(zip(GEOMETRY_COLUMNS, vals.tolist()))
        geo["droll0"] = float(d["s"][GEOMETRY_COLUMNS.index("roll0")])
        geo["ddz0"] = float(d["s"][GEOMETRY_COLUMNS.index("dz0")])
        st = WheelsetState(q[1], q[2], q[3], q[5], q_t[1], q_t[2], q_t[3], q_t[5], q_t[6])
        return generalized_forces(SCALAR, st, geo, self.V, d["kappa"], self.params, self.N_ref)

    def _pre_step(self, mbs, t: float) -> bool:
        """Table interval of the wheelset's current y and the curvature at the step end."""
        y = mbs.systemData.GetODE2Coordinates()[self._y_index]
        lo, hi = self.law_table.y_range_m
        if not lo <= y <= hi:
            self._left_table_at = (t, y)
            return False  # stops the integration; run() raises
        kappa = float(self._kappa_fn(self.V * t))
        i = int(np.searchsorted(self.law_table.y, y, side="right")) - 1
        i = min(max(i, 0), self.law_table.y.size - 2)
        if self.force_law == "symbolic":
            if i != self._seg:
                _, yi, v, s = self.law_table.segment(y)
                self._sym_yi.SetValue(yi)
                for var, val in zip(self._sym_v, v.tolist()):
                    var.SetValue(val)
                for var, val in zip(self._sym_s, s.tolist()):
                    var.SetValue(val)
            if kappa != self._kappa_now:
                self._sym_kappa.SetValue(kappa)
        else:
            if i != self._seg:
                _, yi, v, s = self.law_table.segment(y)
                self._py_state.update(yi=yi, v=v.copy(), s=s.copy())
            self._py_state["kappa"] = kappa
        if i != self._seg:
            self.segment_changes += 1
            self._seg = i
        self._kappa_now = kappa
        return True

    # ------------------------------------------------------------------ run
    def run(self, t_end_s: float, output_step_s: float | None = None) -> WheelsetRun:
        """Integrate from t = 0 to ``t_end_s``; returns the time series (every step, or every
        ``output_step_s``). Once per model: it starts from the initial state."""
        if self._ran:
            raise RuntimeError("FreeWheelset.run() runs once; build a new model for another run")
        self._ran = True
        mbs = self.mbs
        s = exu.SimulationSettings()
        s.solution.file.write = False
        s.solution.sensors.writePeriod = output_step_s or self.step_s
        s.linearSolver.solverType = exu.LinearSolverType.EigenDense
        ti = s.timeIntegration
        ti.verboseMode = 0
        ti.startTime = 0.0
        ti.endTime = float(t_end_s)
        ti.numberOfSteps = max(1, int(round(t_end_s / self.step_s)))
        ti.generalizedAlpha.spectralRadius = self.rho
        ti.newton.useModifiedNewton = True
        ti.newton.absoluteTolerance = self.newton_abs_tol
        ti.newton.relativeTolerance = 1e-8
        # the body's y coordinate in the system vector (for the PreStep lookup)
        self._y_index = int(mbs.GetNodeODE2Index(self.node)) + 1
        self._left_table_at = None
        t0 = time.perf_counter()
        ok = mbs.SolveDynamic(s, solverType=exu.DynamicSolverType.GeneralizedAlpha)
        wall = time.perf_counter() - t0
        if self._left_table_at is not None:
            t_out, y_out = self._left_table_at
            raise RuntimeError(f"the wheelset left the contact table (y = {1e3 * y_out:.2f} mm "
                               f"at t = {t_out:.3f} s); the table covers "
                               f"{1e3 * self.law_table.y_range_m[0]:g} .. "
                               f"{1e3 * self.law_table.y_range_m[1]:g} mm")
        if ok is False:
            raise RuntimeError("exudyn: time integration failed")
        c = mbs.GetSensorStoredData(self._sensors[0])
        v = mbs.GetSensorStoredData(self._sensors[1])
        w = mbs.GetSensorStoredData(self._sensors[2])
        tt = c[:, 0]
        kap = np.array([self._kappa_fn(self.V * ti_) for ti_ in tt])
        return WheelsetRun(t=tt, y=c[:, 2], z=c[:, 3], roll=c[:, 4], yaw=c[:, 6],
                           y_t=v[:, 2], z_t=v[:, 3], roll_t=v[:, 4], yaw_t=v[:, 6],
                           spin_t=w[:, 1], kappa=kap, speed_m_per_s=self.V, wall_s=wall,
                           steps=ti.numberOfSteps)

    def contact_forces(self, run: WheelsetRun) -> tuple[WheelContact, WheelContact]:
        """The force law (left, right :class:`~vehicle.wheelrail.contact_law.WheelContact` of
        arrays) evaluated along a run, with the full table interpolation."""
        geo = self.law_table.geometry(run.y)
        return wheelset_forces(NUMPY, run.state(), geo, self.V, run.kappa, self.params,
                               self.N_ref)
