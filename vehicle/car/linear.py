"""The car linearised about steady running on straight, ideal track (:func:`linearise_car`): its
reduced second-order matrices (:mod:`vehicle.linear`), how the bellow forces enter and how the
bellows' crushing follows, and the secondary dampers' internal states. What the air does is not
here (``vehicle`` knows no pneumatics): the airspring force law is F = F_n + K_b (z_b - z_n) with
the bellows' stiffness K_b at frozen air (given) and F_n the input through which the air's state
acts; ``cosim`` closes the loop.

Steady state (:func:`steady_state`): at a constant speed on straight track every body moves at
V and the wheelsets spin at the rate that leaves no longitudinal creep force (slightly above
V / r0: the wheels' rolling radius is r0 less their Hertz deflection). Newton's method solves the
reduced force balance for the positions and the spin rates together.

Maxwell dampers (a damper in series with its mounting stiffness k_s): the force is
k_s (d - y) with the damper's elongation y an internal state, c1 y' = k_s (d - y) (c1: the
damper's slope below its blow-off velocity, where small motions stay).

This module needs a car with contact guidance (the kinematic guidance prescribes the lateral
motion: nothing to hunt).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import List, Optional, Tuple

import exudyn as exu
import numpy as np

from ..linear import LinearSystem, constraint_jacobian, linearise, ode2_rhs
from ..linear import steady_state as generic_steady_state

__all__ = ["CarLinearisation", "linearise_car", "steady_state", "AXES"]

#: the six coordinates of a rigid body (exudyn RotationRxyz: small rotations about x, y, z)
AXES = ("x", "y", "z", "roll", "pitch", "yaw")

#: force step of the bellow input's central difference [N] (the law is linear in F_n)
FORCE_STEP_N = 1.0


@dataclass(frozen=True)
class CarLinearisation:
    """The car about steady running at ``speed_m_per_s``.

    Attributes
    ----------
    system : LinearSystem
        M eta'' + D eta' + K eta = B u + W w in the independent coordinates eta (the bellow
        stiffness at frozen air included in K).
    coordinates : list of (body, axis)
        What each eta is: body "carbody", "bogie 1", "bogie 2", "wheelset 1" .. "wheelset 4"
        with an axis of :data:`AXES`, or "wheelset i" with axis "spin" (rotation about the axle
        relative to the non-rotating body; nothing depends on it, only on its rate).
    bellow_input : (n, 4) array
        B: generalized force per newton of each bellow's F_n (BELLOWS order) [N/N, N m/N].
    crushing : (4, n) array
        dz_b/deta: each bellow's own crushing (the bellow, not the emergency spring in series).
    crushing_per_force : (4, 4) array
        dz_b/dF_n [m/N]: the emergency spring in series yields (zero without one).
    maxwell_input : (n, m) array
        W: generalized force per metre of each Maxwell damper's internal elongation y.
    maxwell_deflection : (m, n) array
        dd/deta: each Maxwell element's deflection.
    maxwell_rate_per_s : (m,) array
        k_s / c1: y' = k_s / c1 (d - y) [1/s].
    maxwell_names : list of str
    rail_input : (n, 4) array or None
        Generalized force per metre of vertical rail motion under each wheelset (both of its rails
        up: the track's vertical level) [N/m, N m/m]; None unless asked for (``rail_inputs``).
    rail_rate_input : (n, 4) array or None
        Generalized force per m/s of that motion's rate [N s/m, N m s/m]; None unless asked for.
    residual_N : float
        The largest reduced force (moment) left at the steady state [N, N m].
    reaction_N : float
        The largest constraint reaction there (drive and pitch locks; the linearisation leaves
        their geometric stiffness out, exact when this is 0) [N, N m].
    speed_m_per_s : float
    """

    system: LinearSystem
    coordinates: List[Tuple[str, str]]
    bellow_input: np.ndarray
    crushing: np.ndarray
    crushing_per_force: np.ndarray
    maxwell_input: np.ndarray
    maxwell_deflection: np.ndarray
    maxwell_rate_per_s: np.ndarray
    maxwell_names: List[str]
    rail_input: Optional[np.ndarray]
    rail_rate_input: Optional[np.ndarray]
    residual_N: float
    reaction_N: float
    speed_m_per_s: float

    @property
    def spin(self) -> np.ndarray:
        """Indices in eta of the spin coordinates (their positions never matter)."""
        return np.array([i for i, (_, axis) in enumerate(self.coordinates) if axis == "spin"], dtype=int)


def _coordinate_names(car) -> List[Tuple[str, str]]:
    """(body, axis) of every system coordinate."""
    mbs, model = car.mbs, car.model
    names = [None] * car.solver.main.GetODE2size()
    bodies = ([("carbody", model.carbody)] + [(f"bogie {i + 1}", b) for i, b in enumerate(model.bogies)]
              + [(f"wheelset {i + 1}", b) for i, b in enumerate(model.wheelsets)])
    for name, body in bodies:
        i0 = int(mbs.GetNodeODE2Index(mbs.GetObject(body)["nodeNumber"]))
        for k, axis in enumerate(AXES):
            names[i0 + k] = (name, axis)
    for i, node in enumerate(model.spin_nodes):
        names[int(mbs.GetNodeODE2Index(node))] = (f"wheelset {i + 1}", "spin")
    for i, name in enumerate(names):
        if name is None:
            names[i] = ("other", str(i))
    return names


def _set(mbs, q=None, v=None) -> None:
    cfg = exu.ConfigurationType.Current
    if q is not None:
        mbs.systemData.SetODE2Coordinates(q, cfg)
    if v is not None:
        mbs.systemData.SetODE2Coordinates_t(v, cfg)


def steady_state(car, names=None) -> float:
    """Move the car's current state to steady running on straight track (module docstring);
    returns the largest reduced force left [N, N m]. ``names``: :func:`_coordinate_names` of the car."""
    names = names or _coordinate_names(car)
    spins = [i for i, (_, axis) in enumerate(names) if axis == "spin"]
    return generic_steady_state(car.mbs, car.solver.main, spins)


def _reaction(car, N: np.ndarray) -> float:
    """The largest constraint reaction at the current state: f = C_q^T lambda, least squares."""
    C = constraint_jacobian(car.mbs, car.solver.main)
    if C.shape[0] == 0:
        return 0.0
    lam = np.linalg.lstsq(C.T, ode2_rhs(car.mbs, car.solver.main), rcond=None)[0]
    return float(np.max(np.abs(lam)))


def _crushing(car) -> np.ndarray:
    car.bellows.crushing_time_s = None                    # the cache is per time; the state moved
    return car.bellow_crushing()[0]


def linearise_car(car, bellow_force_N, bellow_stiffness_N_per_m, rail_inputs: bool = False) -> CarLinearisation:
    """The car (contact guidance, straight ideal track) linearised about steady running at its
    speed, with each bellow's force F_n = ``bellow_force_N`` (4,) and stiffness at frozen air
    ``bellow_stiffness_N_per_m`` (4,) (see the module docstring). The car's state is moved to the
    steady state; the car serves the analysis only afterwards. ``rail_inputs``: also the rails'
    vertical input (32 more evaluations of the car's forces; a ride's response to the track's
    level needs it, the eigenvalues do not)."""
    if getattr(car, "guidance", "") != "contact":
        raise ValueError("linearise_car needs a car with guidance='contact'")
    mbs, solver = car.mbs, car.solver.main
    F0 = np.asarray(bellow_force_N, dtype=float).reshape(4)
    Kb = np.asarray(bellow_stiffness_N_per_m, dtype=float).reshape(4)
    car.set_bellow_forces(F0, Kb, np.zeros(4))
    if car.maxwell.active:                                # the element's continuous law k_s (d - y)
        car.maxwell.step_size.SetValue(0.0)
        for d in car.maxwell.dampers:
            d.y_sym.SetValue(d.y)
            d.ydot_sym.SetValue(0.0)
    names = _coordinate_names(car)
    residual = steady_state(car, names)
    lin = linearise(mbs, solver)
    N = lin.N
    coordinates = [names[j] for j in lin.independent]

    def force_difference(apply) -> np.ndarray:
        apply(+1.0)
        f_plus = ode2_rhs(mbs, solver)
        apply(-1.0)
        f_minus = ode2_rhs(mbs, solver)
        apply(0.0)
        return N.T @ (f_plus - f_minus)

    B = np.empty((N.shape[1], 4))
    Zu = np.empty((4, 4))
    anchor = [law[3] for law in car.bellows.laws]      # z_n of the law: every variation keeps it
    for k in range(4):
        def apply(sign, k=k):
            F = F0.copy()
            F[k] += sign * FORCE_STEP_N
            car.set_bellow_forces(F, Kb, None, z_anchor_m=anchor)
        apply(+1.0)
        z_plus = _crushing(car)
        apply(-1.0)
        z_minus = _crushing(car)
        apply(0.0)
        Zu[:, k] = (z_plus - z_minus) / (2.0 * FORCE_STEP_N)
        B[:, k] = force_difference(apply) / (2.0 * FORCE_STEP_N)

    q0 = np.array(mbs.systemData.GetODE2Coordinates())
    h = 1e-7                                              # [m, rad]: the crushing is smooth in the positions
    maxwell = list(car.maxwell.dampers)
    get = mbs.GetObjectOutput
    Z = np.empty((4, N.shape[1]))
    Wd = np.empty((len(maxwell), N.shape[1]))
    for j in range(N.shape[1]):
        out = []
        for sign in (1.0, -1.0):
            _set(mbs, q0 + sign * h * N[:, j])
            out.append((_crushing(car), np.array([get(d.connector, exu.OutputVariableType.DisplacementLocal)[d.axis]
                                                  for d in maxwell])))
        _set(mbs, q0)
        Z[:, j] = (out[0][0] - out[1][0]) / (2.0 * h)
        Wd[:, j] = (out[0][1] - out[1][1]) / (2.0 * h)
    _crushing(car)

    W = np.empty((N.shape[1], len(maxwell)))
    for i, d in enumerate(maxwell):
        def apply(sign, d=d):
            d.y_sym.SetValue(d.y + sign * h)
        W[:, i] = force_difference(apply) / (2.0 * h)
    rates = np.array([d.k_s / d.c1 for d in maxwell])
    rail, rail_rate = _rail_inputs(car, force_difference) if rail_inputs else (None, None)
    return CarLinearisation(lin, coordinates, B, Z, Zu, W, Wd, rates, [d.name for d in maxwell], rail, rail_rate,
                            residual, _reaction(car, N), float(car.speed_m_per_s))


#: central-difference steps of the rails' vertical motion [m] and rate [m/s]
RAIL_STEP_M, RAIL_RATE_STEP_M_PER_S = 1e-7, 1e-5


def _rail_inputs(car, force_difference) -> tuple[np.ndarray, np.ndarray]:
    """(n, 4) generalized forces per metre and per m/s of both rails of each wheelset moving up
    (central differences of the contact law through its rails' offsets and rates)."""
    frames = car.track_input.rows(car.t_s)[:4]
    law = car.contact.track_contact
    columns = ([], [])
    for which, h in ((2, RAIL_STEP_M), (3, RAIL_RATE_STEP_M_PER_S)):
        for i in range(4):
            def apply(sign, i=i, which=which, h=h):
                side = [0.0, 0.0, 0.0, 0.0]
                side[which] = sign * h
                law.set_track(frames, [(tuple(side), tuple(side)) if j == i else ((0.0,) * 4, (0.0,) * 4)
                                       for j in range(4)])
            columns[which - 2].append(force_difference(apply) / (2.0 * h))
    return np.array(columns[0]).T, np.array(columns[1]).T
