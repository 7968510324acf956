"""Building the secondary suspension between the bogie frames and the carbody: the airsprings
(:func:`add_airsprings`), the lateral bumpstops (:func:`add_lateral_bumpstops`) and the optional
components, anti-roll bars, traction rods and dampers (:func:`add_optional_components`); the
model is described in :mod:`vehicle.car`."""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import exudyn as exu
import numpy as np
from exudyn.advancedUtilities import CreateSymbolicUserFunction

from ..params import BELLOWS, VehicleParams
from ..suspension import (
    airspring_series_force_N,
    arb_roll_stiffness_N_m_per_rad,
    bilinear_damper_force_N,
    maxwell_force_N,
)
from .statics import StaticReference

esym = exu.symbolic


class _SymbolicOps:
    """The operations of the :mod:`vehicle.suspension` force laws, on exudyn symbolic
    expressions (the laws then compile into the connectors' C++ user functions)."""

    @staticmethod
    def where(condition, if_true, if_false):
        real = esym.Real
        return esym.IfThenElse(condition, *(v if isinstance(v, real) else real(float(v))
                                            for v in (if_true, if_false)))

    abs = staticmethod(esym.abs)
    sign = staticmethod(esym.sign)
    max = staticmethod(esym.max)
    min = staticmethod(esym.min)


#: the ``ops`` of the :mod:`vehicle.suspension` laws on exudyn symbolic expressions
SYMBOLIC_OPS = _SymbolicOps()


class SecondaryDamper:
    """One secondary damper: its connector, law and (Maxwell element) internal state."""

    def __init__(self, name: str, axis: int, c1: float, c2: float, v_b: float, k_s: float):
        self.name, self.axis = name, axis
        self.c1, self.c2, self.v_b, self.k_s = c1, c2, v_b, k_s
        self.maxwell = math.isfinite(k_s)
        self.connector = None
        # Maxwell state at the start of the current step: damper elongation y [m] and rate
        # [m/s] (Python values and the symbolic variables the force law reads), force [N]
        self.y = self.ydot = self.force = 0.0
        self.y_sym = self.ydot_sym = None


def check_components(p: VehicleParams) -> None:
    """ValueError naming the field when an optional component's parameters are inconsistent."""
    nonnegative = ("arb_roll_stiffness_N_m_per_rad", "arb_torsion_stiffness_N_m_per_rad",
                   "secondary_yaw_stiffness_N_m_per_rad",
                   "traction_rod_stiffness_N_per_m", "traction_rod_damping_N_s_per_m",
                   "vertical_bumpstop_clearance_m", "vertical_bumpstop_stiffness_N_per_m")
    for kind in ("secondary_vertical", "secondary_lateral", "yaw"):
        nonnegative += (f"{kind}_damping_N_s_per_m", f"{kind}_damper_blowoff_damping_N_s_per_m")
    positive = ("emergency_spring_stiffness_N_per_m",) + tuple(
        f"{kind}_damper_{what}" for kind in ("secondary_vertical", "secondary_lateral", "yaw")
        for what in ("series_stiffness_N_per_m", "blowoff_velocity_m_per_s"))
    for name in nonnegative:
        value = getattr(p, name)
        if not (value >= 0.0 and math.isfinite(value)):
            raise ValueError(f"{name} must be finite and >= 0, got {value}")
    for name in positive:
        value = getattr(p, name)
        if not value > 0.0:
            raise ValueError(f"{name} must be > 0 (inf: rigid / linear), got {value}")
    if p.arb_roll_stiffness_N_m_per_rad > 0.0 and p.arb_torsion_stiffness_N_m_per_rad > 0.0:
        raise ValueError("give the anti-roll bar either as arb_roll_stiffness_N_m_per_rad or as "
                         "arb_torsion_stiffness_N_m_per_rad with its lever and link geometry, "
                         "not both")
    arb_roll_stiffness_N_m_per_rad(p.arb_torsion_stiffness_N_m_per_rad, p.arb_lever_arm_m,
                                   p.arb_link_spacing_m)  # raises on a bad geometry


@dataclass(frozen=True)
class Mounts:
    """The bogie frames and the carbody of a system being built, where the secondary suspension
    attaches."""

    mbs: Any
    params: VehicleParams
    carbody: int
    bogies: list
    #: bogie centre x [m], front then rear
    bogie_x_m: np.ndarray
    #: symbolic variables and functions that must live as long as the system (appended to)
    keep_alive: list

    def between(self, ib: int, x: float, y: float, h: float) -> dict:
        """Local positions, on bogie frame ``ib`` and on the carbody, of the point at (x, y)
        from the bogie centre and height h above rail at static equilibrium (coincident markers:
        a component's deflection is 0 there)."""
        p = self.params
        return dict(itemNumbers=[self.bogies[ib], self.carbody],
                    localPosition0=[x, y, h - p.bogie_cog_height_m],
                    localPosition1=[float(self.bogie_x_m[ib]) + x, y, h - p.carbody_cog_height_m],
                    useIntrinsicFormulation=True, show=False)

    def set_spring_function(self, co, function, *keep) -> None:
        """``function`` as the symbolic springForceTorqueUserFunction of connector ``co``."""
        fn = CreateSymbolicUserFunction(self.mbs, function, "springForceTorqueUserFunction", co)
        self.mbs.SetObjectParameter(co, "springForceTorqueUserFunction", fn)
        self.keep_alive.extend([fn, *keep])


@dataclass(frozen=True)
class AirspringConnectors:
    """The airsprings as built."""

    #: connector per bellow, :data:`~vehicle.params.BELLOWS` order
    connectors: list
    #: per bellow the symbolic variables of its force law: (F_n [N], dF/dz [N/m], dF/dt [N/s],
    #: z_n [m]) (see :func:`add_airsprings`)
    law_vars: list
    #: symbolic variable: the time t_n [s] the laws were set at
    law_time: Any


def _bellow_plates(m: Mounts, k: int) -> tuple[list[float], list[float]]:
    """Local positions of bellow ``k``'s lower plate (bogie) and upper plate (carbody)."""
    p = m.params
    ib = k // 2
    y = p.airspring_lateral_spacing_m / 2.0 * (1.0 if BELLOWS[k][1] == "L" else -1.0)
    lower = [0.0, y, p.airspring_lower_height_m - p.bogie_cog_height_m]
    upper = [float(m.bogie_x_m[ib]), y, p.airspring_upper_height_m - p.carbody_cog_height_m]
    return lower, upper


def add_airsprings(m: Mounts, static: StaticReference) -> AirspringConnectors:
    """Per bellow one intrinsic ``RigidBodySpringDamper`` between the lower plate (bogie) and the
    upper plate (carbody) carrying the axial force law and the shear stiffness.

    Intrinsic formulation: the displacement d = p_upper - p_lower is measured in the mid-frame J
    between bogie frame and carbody, and the force is applied at the midpoint of the two plate
    centres on both bodies, so the pair is collinear at every instant (no end moments to add).
    In J the crushing is z = h0 - d_z (h0: nominal bellow height), the axial force
    F(t, z) = F_n + dF/dt (t - t_n) + dF/dz (z - z_n) pushes the carbody up along J's z axis (the
    bellow axis: the mean of the two plates' normals), and the shear springs act on d_x, d_y.
    The connector force f enters the left-hand side like K u: it acts as -f on the carbody
    (marker 1) and +f on the bogie, hence f = (k_s d_x, k_s d_y, -F).

    With an emergency spring and/or a vertical bumpstop (``airspring_in_series``), z is the
    crushing of the whole airspring and the axial force is that of the bellow law in parallel
    with the stop, in series with the emergency spring, solved in closed form by
    :func:`~vehicle.suspension.airspring_series_force_N` (the massless node between bellow and
    emergency spring needs no coordinate); the bellow law stays a law of the bellow's own
    crushing z_b (:meth:`~vehicle.car.MetroCar.bellow_crushing`)."""
    connectors, law_vars = [], []
    tn = None
    for k in range(4):
        F = esym.Real(f"F{k}", static.bellow_force_N)  # force at t_n and z_n [N]
        K = esym.Real(f"K{k}", 0.0)  # dF/dz [N/m]
        Fdot = esym.Real(f"Fdot{k}", 0.0)  # dF/dt at constant crushing [N/s]
        z0 = esym.Real(f"z0_{k}", 0.0)  # crushing z_n at the last set_bellow_forces [m]
        if k == 0:
            tn = esym.Real("t_n", 0.0)  # time t_n of the last set_bellow_forces [s]
        connectors.append(_add_airspring(m, static, k, (F, K, Fdot, z0), tn))
        law_vars.append((F, K, Fdot, z0))
    return AirspringConnectors(connectors, law_vars, tn)


def _add_airspring(m: Mounts, static: StaticReference, k: int, law_vars: tuple, tn) -> int:
    """Bellow ``k`` (see :func:`add_airsprings`) with the symbolic variables ``law_vars`` of its
    law, (F_n, dF/dz, dF/dt, z_n), and ``tn``; returns its connector."""
    p, mbs = m.params, m.mbs
    F, K, Fdot, z0 = law_vars
    bogie = m.bogies[k // 2]
    lower, upper = _bellow_plates(m, k)
    h0 = esym.Real(static.bellow_height_m)
    ks = esym.Real(p.bellow_shear_stiffness_N_per_m)
    zero = esym.Real(0.0)

    def bellow_force(mbs, t, itemNumber, displacement, rotation, velocity, angularVelocity,
                     stiffness, damping, rotJ0, rotJ1, offset):
        z = h0 - displacement[2]
        f = F + Fdot * (t - tn) + K * (z - z0)
        return [ks * displacement[0], ks * displacement[1], -f, zero, zero, zero]

    F_static = static.bellow_force_N
    k_e, k_stop = p.emergency_spring_stiffness_N_per_m, p.vertical_bumpstop_stiffness_N_per_m
    clearance = p.vertical_bumpstop_clearance_m

    def airspring_force(mbs, t, itemNumber, displacement, rotation, velocity,
                        angularVelocity, stiffness, damping, rotJ0, rotJ1, offset):
        z = h0 - displacement[2]  # crushing of bellow + emergency spring
        f = airspring_series_force_N(z, F + Fdot * (t - tn) - K * z0, K, F_static, k_e,
                                     k_stop, clearance, SYMBOLIC_OPS)
        return [ks * displacement[0], ks * displacement[1], -f, zero, zero, zero]

    co = mbs.CreateRigidBodySpringDamper(
        itemNumbers=[bogie, m.carbody], localPosition0=lower, localPosition1=upper,
        useIntrinsicFormulation=True, show=False)
    m.set_spring_function(co, airspring_force if static.airspring_in_series else bellow_force,
                          h0, ks, zero)
    return co


def add_lateral_bumpstops(m: Mounts) -> list:
    """The lateral bumpstops, front then rear bogie (:func:`_add_bumpstop`): their connectors."""
    return [_add_bumpstop(m, ib) for ib in range(2)]


def _add_bumpstop(m: Mounts, ib: int) -> int:
    """Lateral bumpstop of bogie ``ib`` (see :mod:`vehicle.car`): lateral force beyond the
    clearance (y of the mid-frame between bogie and carbody), between the bogie centre at the
    lower-plate height and the carbody point that coincides with it at static equilibrium."""
    p, mbs = m.params, m.mbs
    clearance = esym.Real(p.lateral_bumpstop_clearance_m)
    k = esym.Real(p.lateral_bumpstop_stiffness_N_per_m)
    zero = esym.Real(0.0)

    # displacement = carbody point relative to the bogie point in the mid-frame between
    # bogie and carbody (intrinsic formulation); the returned connector force f enters the
    # left-hand side like K u: it acts as -f on the carbody (marker 1), +f on the bogie
    # frame, both at the markers' midpoint
    def bumpstop_force(mbs, t, itemNumber, displacement, rotation, velocity, angularVelocity,
                       stiffness, damping, rotJ0, rotJ1, offset):
        d = displacement[1]
        f = k * (esym.max(d - clearance, zero) + esym.min(d + clearance, zero))
        return [zero, f, zero, zero, zero, zero]

    h = p.airspring_lower_height_m
    co = mbs.CreateRigidBodySpringDamper(
        itemNumbers=[m.bogies[ib], m.carbody],
        localPosition0=[0.0, 0.0, h - p.bogie_cog_height_m],
        localPosition1=[float(m.bogie_x_m[ib]), 0.0, h - p.carbody_cog_height_m],
        useIntrinsicFormulation=True, show=False)
    m.set_spring_function(co, bumpstop_force, clearance, k, zero)
    return co


@dataclass(frozen=True)
class OptionalComponents:
    """The optional secondary components as built (each list empty when the component is off:
    then nothing is built, the same model bit for bit)."""

    #: anti-roll bar connectors, per bogie
    anti_roll_bars: list
    #: traction rod connectors, per bogie
    traction_rods: list
    #: the secondary dampers that have damping
    dampers: list
    #: symbolic variable: the internal step size [s] the Maxwell laws read (None without any)
    maxwell_step: Any
    #: secondary yaw springs, per bogie
    yaw_springs: list = dataclasses.field(default_factory=list)

    @property
    def maxwell(self) -> list:
        """The dampers that are Maxwell elements (finite series stiffness)."""
        return [d for d in self.dampers if d.maxwell]


def add_optional_components(m: Mounts, step_s: float) -> OptionalComponents:
    """Per bogie the anti-roll bar, the traction rod and the dampers that the parameters ask
    for, then the Maxwell elements' force laws (they read the step size)."""
    p = m.params
    arbs, rods, dampers, yaw_springs = [], [], [], []
    k_arb = p.arb_roll_stiffness_N_m_per_rad + arb_roll_stiffness_N_m_per_rad(
        p.arb_torsion_stiffness_N_m_per_rad, p.arb_lever_arm_m, p.arb_link_spacing_m)
    for ib in range(2):
        if k_arb > 0.0:
            arbs.append(_add_anti_roll_bar(m, ib, k_arb))
        if p.traction_rod_stiffness_N_per_m > 0.0 or p.traction_rod_damping_N_s_per_m > 0.0:
            rods.append(_add_traction_rod(m, ib))
        if p.secondary_yaw_stiffness_N_m_per_rad > 0.0:
            yaw_springs.append(_add_yaw_spring(m, ib, p.secondary_yaw_stiffness_N_m_per_rad))
        dampers += _add_dampers(m, ib)
    maxwell = [d for d in dampers if d.maxwell]
    h_step = None
    if maxwell:
        h_step = esym.Real("h_step", step_s)  # internal step size [s]
        m.keep_alive.append(h_step)
        for d in maxwell:
            _set_maxwell_function(m, d, h_step)
    return OptionalComponents(arbs, rods, dampers, h_step, yaw_springs)


def _add_anti_roll_bar(m: Mounts, ib: int, k_roll: float) -> int:
    """Anti-roll bar of bogie ``ib``: a roll couple k_roll (phi_carbody - phi_frame) between
    bogie frame and carbody (see :mod:`vehicle.car`). Intrinsic ``RigidBodySpringDamper`` with only
    the rotational x stiffness: the torque is k_roll times the x component of the relative
    rotation vector in the mid-frame; no force, no other stiffness. The couple is free
    (no point of application); the markers sit at the bogie centre, lower-plate height."""
    K = np.zeros((6, 6))
    K[3, 3] = k_roll
    return m.mbs.CreateRigidBodySpringDamper(
        stiffness=K, **m.between(ib, 0.0, 0.0, m.params.airspring_lower_height_m))


def _add_yaw_spring(m: Mounts, ib: int, k_yaw: float) -> int:
    """Secondary yaw spring of bogie ``ib``: a yaw couple k_yaw (psi_carbody - psi_frame) between
    bogie frame and carbody, built as the anti-roll bar is (:func:`_add_anti_roll_bar`) with the
    rotational z stiffness alone: a free couple, no force."""
    K = np.zeros((6, 6))
    K[5, 5] = k_yaw
    return m.mbs.CreateRigidBodySpringDamper(
        stiffness=K, **m.between(ib, 0.0, 0.0, m.params.airspring_lower_height_m))


def _add_traction_rod(m: Mounts, ib: int) -> int:
    """Traction rod (or centre pivot) of bogie ``ib``: longitudinal spring-damper between the
    bogie centre and the carbody at ``traction_rod_height_m`` (intrinsic
    ``RigidBodySpringDamper``, x stiffness and damping only: it carries the longitudinal
    force and leaves the bogie free to yaw, roll and bounce)."""
    p = m.params
    K, D = np.zeros((6, 6)), np.zeros((6, 6))
    K[0, 0], D[0, 0] = p.traction_rod_stiffness_N_per_m, p.traction_rod_damping_N_s_per_m
    return m.mbs.CreateRigidBodySpringDamper(
        stiffness=K, damping=D, **m.between(ib, 0.0, 0.0, p.traction_rod_height_m))


def _add_dampers(m: Mounts, ib: int) -> list:
    """Secondary dampers of bogie ``ib`` that have damping: vertical (left, right; at the
    bellow mid-height), lateral (bogie centre) and yaw (left, right; longitudinal)."""
    p = m.params
    side = "FR"[ib]
    h_mid = 0.5 * (p.airspring_lower_height_m + p.airspring_upper_height_m)
    kinds = (("secondary_vertical", 2, [(f"vertical_{side}{lr}", 0.0, y, h_mid) for lr, y in
                                        (("L", 0.5), ("R", -0.5))]),
             ("secondary_lateral", 1, [(f"lateral_{side}", 0.0, 0.0,
                                        p.secondary_lateral_damper_height_m)]),
             ("yaw", 0, [(f"yaw_{side}{lr}", 0.0, y, p.yaw_damper_height_m) for lr, y in
                         (("L", 0.5), ("R", -0.5))]))
    spacing = {"secondary_vertical": p.secondary_vertical_damper_lateral_spacing_m,
               "secondary_lateral": 0.0, "yaw": p.yaw_damper_lateral_spacing_m}
    dampers = []
    for kind, axis, places in kinds:
        c1 = getattr(p, f"{kind}_damping_N_s_per_m")
        if c1 == 0.0:
            continue
        for name, x, y, h in places:
            d = SecondaryDamper(name, axis, c1, getattr(p, f"{kind}_damper_blowoff_damping_N_s_per_m"),
                                getattr(p, f"{kind}_damper_blowoff_velocity_m_per_s"),
                                getattr(p, f"{kind}_damper_series_stiffness_N_per_m"))
            _add_damper(m, d, ib, x, y * spacing[kind], h)
            dampers.append(d)
    return dampers


def _add_damper(m: Mounts, d: SecondaryDamper, ib: int, x: float, y: float, h: float) -> None:
    """Damper ``d`` between bogie frame ``ib`` and the carbody at (x, y, h) (see
    :meth:`Mounts.between`), acting along the mid-frame axis ``d.axis`` (intrinsic
    ``RigidBodySpringDamper``; force f = F along that axis, -F on the carbody).

    Rigid mounting (series stiffness ``inf``): a linear damper is the connector's damping
    matrix; a bilinear one a symbolic user function of the relative velocity.

    Maxwell element (finite series stiffness k_s): the damper's elongation y is an internal
    state. exudyn 1.13 has no connector that couples a generic first-order state (ODE1
    coordinates, ``NodeGenericODE1``) to body motion (only the hydraulic actuator does), and
    a massless intermediate body would make the mass matrix singular (a small mass, a stiff
    spurious mode). So the state is integrated inside the force law, as an internal variable
    (as in plasticity's return mapping): the symbolic user function gives the force at the
    end of the step as a closed-form function of the deflection there, the step size and the
    state (y, dy/dt) at the start of the step (trapezoidal rule, :func:`maxwell_force_N`).
    The force law is thus an ordinary, deflection-dependent spring law for the implicit
    solver: Newton sees its exact tangent k_s c / (c + k_s h/2) (numerical Jacobian), the
    generalized-alpha step stays implicit in y, and no Python runs inside Newton. After every
    accepted step a PostStep function (:meth:`.maxwell.MaxwellDampers.post_step`) commits the
    state from the converged deflection (in C++ exudyn would do the same with ODE1 coordinates:
    its implicit solver integrates them with the trapezoidal rule too).
    """
    K = np.zeros((6, 6))
    D = np.zeros((6, 6))
    rigid_linear = not d.maxwell and math.isinf(d.v_b)
    if rigid_linear:
        D[d.axis, d.axis] = d.c1
    d.connector = m.mbs.CreateRigidBodySpringDamper(stiffness=K, damping=D, **m.between(ib, x, y, h))
    if rigid_linear or d.maxwell:
        return  # the Maxwell function needs the step-size variable: _set_maxwell_function
    zero = esym.Real(0.0)
    axis, c1, c2, vb = d.axis, d.c1, d.c2, d.v_b

    def damper_force(mbs, t, itemNumber, displacement, rotation, velocity, angularVelocity,
                     stiffness, damping, rotJ0, rotJ1, offset):
        f = [zero] * 6
        f[axis] = bilinear_damper_force_N(velocity[axis], c1, c2, vb, SYMBOLIC_OPS)
        return f

    m.set_spring_function(d.connector, damper_force, zero)


def _set_maxwell_function(m: Mounts, d: SecondaryDamper, h_step) -> None:
    """Symbolic force law of Maxwell damper ``d`` (see :func:`_add_damper`), reading the step
    size ``h_step``."""
    zero = esym.Real(0.0)
    d.y_sym = esym.Real(f"y_{d.name}", 0.0)  # damper elongation at the step start [m]
    d.ydot_sym = esym.Real(f"ydot_{d.name}", 0.0)  # its rate [m/s]
    axis, y, ydot, h = d.axis, d.y_sym, d.ydot_sym, h_step
    k_s, c1, c2, vb = d.k_s, d.c1, d.c2, d.v_b

    def maxwell_force(mbs, t, itemNumber, displacement, rotation, velocity, angularVelocity,
                      stiffness, damping, rotJ0, rotJ1, offset):
        f = [zero] * 6
        f[axis] = maxwell_force_N(displacement[axis], y, ydot, h, k_s, c1, c2, vb, SYMBOLIC_OPS)
        return f

    m.set_spring_function(d.connector, maxwell_force, zero, y, ydot)
