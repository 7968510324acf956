"""Building the car's exudyn model: bodies, primary suspension, airsprings, bumpstops, the
optional secondary components (anti-roll bar, traction rods, dampers), the wheelset guidance and the
drive, the wheel-rail contacts and the flexible track's bodies (:class:`CarBuild`, a part of
:class:`~vehicle.car.MetroCar`; the model itself is described in :mod:`vehicle.car`)."""
from __future__ import annotations

import functools
import math

import exudyn as exu
import numpy as np
from exudyn.advancedUtilities import CreateSymbolicUserFunction
from exudyn.rigidBodyUtilities import RigidBodyInertia

from ..params import BELLOWS, WHEELS, VehicleParams
from ..suspension import (
    airspring_series_force_N,
    arb_roll_stiffness_N_m_per_rad,
    bilinear_damper_force_N,
    maxwell_force_N,
)
from ..wheelrail.geometry import ContactTable, table_path

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


_SYMBOLIC_OPS = _SymbolicOps()


class _Damper:
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


def _check_components(p: VehicleParams) -> None:
    """ValueError naming the field when an optional component's parameters are inconsistent."""
    nonnegative = ("arb_roll_stiffness_N_m_per_rad", "arb_torsion_stiffness_N_m_per_rad",
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


@functools.lru_cache(maxsize=8)
def _contact_table(table_csv: str, wheel_radius_m: float) -> ContactTable:
    """The contact table of :class:`ContactParams` ``table_csv``, or for an empty one the S1002 /
    UIC60 1:40 / 1435 mm table for the wheel radius: shipped, else derived (~2 s, cached)."""
    if table_csv:
        return ContactTable.from_csv(table_csv)
    path = table_path(wheel_radius_m)
    if path.exists():
        return ContactTable.from_csv(path)
    from .wheelrail.derive_table import derive_default
    return derive_default(wheel_radius_m)


class CarBuild:
    """The model's construction (called once, from ``MetroCar.__init__``)."""

    def _build(self, rail0: np.ndarray) -> None:
        p, mbs = self.params, self.mbs
        gravity = [0.0, 0.0, -p.gravity_m_per_s2]

        def body(m, ixx, iyy, izz, pos):
            return mbs.CreateRigidBody(
                inertia=RigidBodyInertia(mass=m, inertiaTensor=np.diag([ixx, iyy, izz]),
                                         inertiaTensorAtCOM=True),
                referencePosition=[pos[0] + self._x0_m, pos[1], pos[2]],
                initialVelocity=[self.speed_m_per_s, 0.0, 0.0], gravity=gravity,
                nodeType=exu.NodeType.RotationRxyz)

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
        if self._contact_mode and self._guided:
            self._add_drive()
        for k in range(4):
            self._add_airspring(k)
        for ib in range(2):
            self._add_bumpstop(ib)
        if self._contact_mode:
            self._add_wheel_rail_contact()
        else:
            self._track_bodies = [self._add_track_body(iw) for iw in range(4)] \
                if self._flexible else None
            for j in range(8):
                self._add_contact(j, rail0[j])
        # optional components (nothing is built when they are off: the same model, bit for bit)
        self._arbs, self._traction_rods, self._dampers = [], [], []
        k_arb = p.arb_roll_stiffness_N_m_per_rad + arb_roll_stiffness_N_m_per_rad(
            p.arb_torsion_stiffness_N_m_per_rad, p.arb_lever_arm_m, p.arb_link_spacing_m)
        for ib in range(2):
            if k_arb > 0.0:
                self._add_anti_roll_bar(ib, k_arb)
            if p.traction_rod_stiffness_N_per_m > 0.0 or p.traction_rod_damping_N_s_per_m > 0.0:
                self._add_traction_rod(ib)
            self._add_dampers(ib)
        self._maxwell = [d for d in self._dampers if d.maxwell]
        if self._maxwell:
            self._h_step = esym.Real("h_step", self.step_s)  # internal step size [s]
            self._sym.append(self._h_step)
            for d in self._maxwell:
                self._set_maxwell_function(d)
        if self._carbody_load:
            self._load_force = mbs.CreateForce(itemNumber=self._carbody, show=False)
            self._load_torque = mbs.CreateTorque(itemNumber=self._carbody, show=False)

    def _add_wheelset_guidance(self, iw: int) -> None:
        """Track guidance of wheelset ``iw`` (see module doc).

        ``GenericJoint`` between ground and the wheelset at rail level: both markers at the
        point midway between the wheel-rail contacts, on the track centre line, at t = 0 (p0).
        The joint frame is ground's rotated by the offset rotation A = Rz(psi) Rx(-cant) (track
        heading, and the roll of the canted track plane; given to exudyn as Tait-Bryan xyz
        angles); in that frame the constraints read
            t . (p - p0) = xi(t),  l . (p - p0) = eta(t)  (t: tangent, l: lateral in the plane)
            t . e_y = 0,  t . e_z = 0  (e_y axle, e_z: wheelset axes),
        with p the wheelset's rail-level point and (xi, eta) the position, relative to p0 in
        that frame, of the track centre line. Motion along the track plane's normal and roll
        about t stay free. The joint's lateral reaction acts where the rails apply it, at rail
        level, at every instant: no couple needs adding.

        Contact guidance locks only the pitch, t . e_z = 0 (the wheelset body does not spin; its
        rotation about the axle is a separate coordinate): the position along the track, lateral
        motion, yaw and roll are left to the primary suspension and the wheel-rail contact
        forces (the car is driven at its centre, :meth:`_add_drive`)."""
        mbs = self.mbs
        xi = esym.Real(f"xi{iw}", 0.0)  # [m]
        eta = esym.Real(f"eta{iw}", 0.0)  # [m]
        rx = esym.Real(f"rx{iw}", 0.0)  # Tait-Bryan angles of Rz(psi) Rx(-cant) [rad]
        ry = esym.Real(f"ry{iw}", 0.0)
        rz = esym.Real(f"rz{iw}", 0.0)
        zero = esym.Real(0.0)

        def offset(mbs, t, itemNumber, offsetUserFunctionParameters):
            return [xi, eta, zero, rx, ry, rz]

        pos = [float(self.wheelset_x_m[iw]) + self._x0_m, 0.0, 0.0]
        # contact guidance: only the pitch stays prescribed (the body does not spin)
        axes = [0, 0, 0, 0, 1, 0] if self._contact_mode else [1, 1, 0, 0, 1, 1]
        joint = mbs.CreateGenericJoint(itemNumbers=[self._ground, self._wheelsets[iw]],
                                       position=pos, constrainedAxes=axes, show=False)
        if self._guided:
            fn = CreateSymbolicUserFunction(mbs, offset, "offsetUserFunction", joint)
            mbs.SetObjectParameter(joint, "offsetUserFunction", fn)
            self._sym += [fn, zero]
        if iw == 0:
            self._guidance_vars = []
        self._guidance_vars.append((xi, eta, rx, ry, rz))

    def _add_drive(self) -> None:
        """Contact guidance: the car is driven at its centre. A ``GenericJoint`` between ground
        and the carbody's centre of gravity locks only its position along the track tangent at
        the car centre's arc length s_c(t) = start_s + v t, t . (p - p0) = xi_c(t) (the joint
        frame turns with the heading there, through a symbolic offset user function like the
        wheelsets' guidance): the carbody is free laterally, vertically and in every rotation,
        and the wheelsets, each held only in pitch, roll along behind it on their creep forces,
        where the bogie frames and the primary suspension put them. Its reaction is the force
        along the track that keeps the speed (the curving resistance of the creep forces),
        along the tangent at the car centre: no force across the track.

        (Driving each wheelset at its own s_i(t) = s0_i + v t, as an earlier version did,
        over-constrains the car: on canted track the wheelset centres run on a radius smaller by
        r0 sin(cant) than the rail-level line whose arc lengths were prescribed, so the two
        wheelsets of a bogie were held ~0.9 mm too far apart on R = 100 m at balanced cant; the
        primary suspensions carried +-15 kN between them, and those forces, along tangents up to
        0.06 rad apart, took ~3 % of M g sin(cant) of the lateral load off the rails.)"""
        mbs, p = self.mbs, self.params
        xi = esym.Real("xi_drive", 0.0)  # [m]
        rz = esym.Real("rz_drive", 0.0)  # heading at the car centre [rad]
        zero = esym.Real(0.0)

        def offset(mbs, t, itemNumber, offsetUserFunctionParameters):
            return [xi, zero, zero, zero, zero, rz]

        joint = mbs.CreateGenericJoint(itemNumbers=[self._ground, self._carbody],
                                       position=[self._x0_m, 0.0, p.carbody_cog_height_m],
                                       constrainedAxes=[1, 0, 0, 0, 0, 0], show=False)
        fn = CreateSymbolicUserFunction(mbs, offset, "offsetUserFunction", joint)
        mbs.SetObjectParameter(joint, "offsetUserFunction", fn)
        self._sym += [fn, zero]
        self._drive = joint
        self._drive_vars = (xi, rz)

    def _add_primary(self, iw: int) -> None:
        """Left and right axlebox springs between bogie frame and wheelset ``iw``.

        Displacement u = 0 at the static position; the z offset carries the static axlebox load
        P (force on the wheelset -K (u - offset) = -P e_z). Intrinsic formulation (axes of the
        mid-frame between bogie and wheelset, force applied at the midpoint of the two markers
        on both bodies): no spurious couple P x (relative displacement), see module doc."""
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
                useIntrinsicFormulation=True, show=False)

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
        """Bellow ``k``: one intrinsic ``RigidBodySpringDamper`` between the lower plate (bogie)
        and the upper plate (carbody) carrying the axial force law and the shear stiffness.

        Intrinsic formulation: the displacement d = p_upper - p_lower is measured in the
        mid-frame J between bogie frame and carbody, and the force is applied at the midpoint of
        the two plate centres on both bodies, so the pair is collinear at every instant (no end
        moments to add). In J the crushing is z = h0 - d_z (h0: nominal bellow height), the
        axial force F(t, z) = F_n + dF/dt (t - t_n) + dF/dz (z - z_n) pushes the carbody up along
        J's z axis (the bellow axis: the mean of the two plates' normals), and the shear springs
        act on d_x, d_y. The connector force f enters the left-hand side like K u: it acts as
        -f on the carbody (marker 1) and +f on the bogie, hence f = (k_s d_x, k_s d_y, -F).

        With an emergency spring and/or a vertical bumpstop (:attr:`airspring_in_series`), z is
        the crushing of the whole airspring and the axial force is that of the bellow law in
        parallel with the stop, in series with the emergency spring, solved in closed form by
        :func:`~vehicle.suspension.airspring_series_force_N` (the massless node between bellow
        and emergency spring needs no coordinate); the bellow law stays a law of the bellow's
        own crushing z_b (:meth:`bellow_crushing`)."""
        p, mbs = self.params, self.mbs
        bogie = self._bogies[k // 2]
        lower, upper = self._bellow_plates(k)
        F = esym.Real(f"F{k}", self._F_static_N)  # force at t_n and z_n [N]
        K = esym.Real(f"K{k}", 0.0)  # dF/dz [N/m]
        Fdot = esym.Real(f"Fdot{k}", 0.0)  # dF/dt at constant crushing [N/s]
        z0 = esym.Real(f"z0_{k}", 0.0)  # crushing z_n at the last set_bellow_forces [m]
        if k == 0:
            self._t_set = esym.Real("t_n", 0.0)  # time t_n of the last set_bellow_forces [s]
        tn = self._t_set
        h0 = esym.Real(self._bellow_height_m)
        ks = esym.Real(p.bellow_shear_stiffness_N_per_m)
        zero = esym.Real(0.0)

        def bellow_force(mbs, t, itemNumber, displacement, rotation, velocity, angularVelocity,
                         stiffness, damping, rotJ0, rotJ1, offset):
            z = h0 - displacement[2]
            f = F + Fdot * (t - tn) + K * (z - z0)
            return [ks * displacement[0], ks * displacement[1], -f, zero, zero, zero]

        F_static = self._F_static_N
        k_e, k_stop = p.emergency_spring_stiffness_N_per_m, p.vertical_bumpstop_stiffness_N_per_m
        clearance = p.vertical_bumpstop_clearance_m

        def airspring_force(mbs, t, itemNumber, displacement, rotation, velocity,
                            angularVelocity, stiffness, damping, rotJ0, rotJ1, offset):
            z = h0 - displacement[2]  # crushing of bellow + emergency spring
            f = airspring_series_force_N(z, F + Fdot * (t - tn) - K * z0, K, F_static, k_e,
                                         k_stop, clearance, _SYMBOLIC_OPS)
            return [ks * displacement[0], ks * displacement[1], -f, zero, zero, zero]

        co = mbs.CreateRigidBodySpringDamper(
            itemNumbers=[bogie, self._carbody], localPosition0=lower, localPosition1=upper,
            useIntrinsicFormulation=True, show=False)
        law = airspring_force if self.airspring_in_series else bellow_force
        fn = CreateSymbolicUserFunction(mbs, law, "springForceTorqueUserFunction", co)
        mbs.SetObjectParameter(co, "springForceTorqueUserFunction", fn)
        if k == 0:
            self._bellows, self._bellow_vars, self._bellow_law = [], [], []
            self._t_set_s = 0.0
        self._bellows.append(co)
        self._bellow_vars.append((F, K, Fdot, z0))
        self._bellow_law.append((self._F_static_N, 0.0, 0.0, 0.0))  # Python copy: F, K, Fdot, z0
        self._sym += [fn, h0, ks, zero]

    def _add_bumpstop(self, ib: int) -> None:
        """Lateral bumpstop of bogie ``ib`` (see module doc): lateral force beyond the
        clearance (y of the mid-frame between bogie and carbody), between the bogie centre at
        the lower-plate height and the carbody point that coincides with it at static
        equilibrium."""
        p, mbs = self.params, self.mbs
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
            itemNumbers=[self._bogies[ib], self._carbody],
            localPosition0=[0.0, 0.0, h - p.bogie_cog_height_m],
            localPosition1=[float(self.bogie_x_m[ib]), 0.0, h - p.carbody_cog_height_m],
            useIntrinsicFormulation=True, show=False)
        fn = CreateSymbolicUserFunction(mbs, bumpstop_force, "springForceTorqueUserFunction", co)
        mbs.SetObjectParameter(co, "springForceTorqueUserFunction", fn)
        if ib == 0:
            self._bumpstops = []
        self._bumpstops.append(co)
        self._sym += [fn, clearance, k, zero]

    def _between_bogie_and_carbody(self, ib: int, x: float, y: float, h: float) -> dict:
        """Local positions, on bogie frame ``ib`` and on the carbody, of the point at (x, y)
        from the bogie centre and height h above rail at static equilibrium (coincident markers:
        a component's deflection is 0 there)."""
        p = self.params
        return dict(itemNumbers=[self._bogies[ib], self._carbody],
                    localPosition0=[x, y, h - p.bogie_cog_height_m],
                    localPosition1=[float(self.bogie_x_m[ib]) + x, y, h - p.carbody_cog_height_m],
                    useIntrinsicFormulation=True, show=False)

    def _add_anti_roll_bar(self, ib: int, k_roll: float) -> None:
        """Anti-roll bar of bogie ``ib``: a roll couple k_roll (phi_carbody - phi_frame) between
        bogie frame and carbody (see module doc). Intrinsic ``RigidBodySpringDamper`` with only
        the rotational x stiffness: the torque is k_roll times the x component of the relative
        rotation vector in the mid-frame; no force, no other stiffness. The couple is free
        (no point of application); the markers sit at the bogie centre, lower-plate height."""
        K = np.zeros((6, 6))
        K[3, 3] = k_roll
        co = self.mbs.CreateRigidBodySpringDamper(
            stiffness=K, **self._between_bogie_and_carbody(ib, 0.0, 0.0,
                                                           self.params.airspring_lower_height_m))
        self._arbs.append(co)

    def _add_traction_rod(self, ib: int) -> None:
        """Traction rod (or centre pivot) of bogie ``ib``: longitudinal spring-damper between the
        bogie centre and the carbody at ``traction_rod_height_m`` (intrinsic
        ``RigidBodySpringDamper``, x stiffness and damping only: it carries the longitudinal
        force and leaves the bogie free to yaw, roll and bounce)."""
        p = self.params
        K, D = np.zeros((6, 6)), np.zeros((6, 6))
        K[0, 0], D[0, 0] = p.traction_rod_stiffness_N_per_m, p.traction_rod_damping_N_s_per_m
        co = self.mbs.CreateRigidBodySpringDamper(
            stiffness=K, damping=D,
            **self._between_bogie_and_carbody(ib, 0.0, 0.0, p.traction_rod_height_m))
        self._traction_rods.append(co)

    def _add_dampers(self, ib: int) -> None:
        """Secondary dampers of bogie ``ib`` that have damping: vertical (left, right; at the
        bellow mid-height), lateral (bogie centre) and yaw (left, right; longitudinal)."""
        p = self.params
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
        for kind, axis, places in kinds:
            c1 = getattr(p, f"{kind}_damping_N_s_per_m")
            if c1 == 0.0:
                continue
            for name, x, y, h in places:
                d = _Damper(name, axis, c1, getattr(p, f"{kind}_damper_blowoff_damping_N_s_per_m"),
                            getattr(p, f"{kind}_damper_blowoff_velocity_m_per_s"),
                            getattr(p, f"{kind}_damper_series_stiffness_N_per_m"))
                self._add_damper(d, ib, x, y * spacing[kind], h)

    def _add_damper(self, d: _Damper, ib: int, x: float, y: float, h: float) -> None:
        """Damper ``d`` between bogie frame ``ib`` and the carbody at (x, y, h) (see
        :meth:`_between_bogie_and_carbody`), acting along the mid-frame axis ``d.axis`` (intrinsic
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
        accepted step a PostStep function (:meth:`_post_step`) commits the state from the
        converged deflection (in C++ exudyn would do the same with ODE1 coordinates: its
        implicit solver integrates them with the trapezoidal rule too).
        """
        K = np.zeros((6, 6))
        D = np.zeros((6, 6))
        rigid_linear = not d.maxwell and math.isinf(d.v_b)
        if rigid_linear:
            D[d.axis, d.axis] = d.c1
        d.connector = self.mbs.CreateRigidBodySpringDamper(
            stiffness=K, damping=D, **self._between_bogie_and_carbody(ib, x, y, h))
        self._dampers.append(d)
        if rigid_linear or d.maxwell:
            return  # the Maxwell function needs the step-size variable: _set_maxwell_function
        zero = esym.Real(0.0)
        axis, c1, c2, vb = d.axis, d.c1, d.c2, d.v_b

        def damper_force(mbs, t, itemNumber, displacement, rotation, velocity, angularVelocity,
                         stiffness, damping, rotJ0, rotJ1, offset):
            f = [zero] * 6
            f[axis] = bilinear_damper_force_N(velocity[axis], c1, c2, vb, _SYMBOLIC_OPS)
            return f

        self._set_user_function(d.connector, damper_force, zero)

    def _set_maxwell_function(self, d: _Damper) -> None:
        """Symbolic force law of Maxwell damper ``d`` (see :meth:`_add_damper`)."""
        zero = esym.Real(0.0)
        d.y_sym = esym.Real(f"y_{d.name}", 0.0)  # damper elongation at the step start [m]
        d.ydot_sym = esym.Real(f"ydot_{d.name}", 0.0)  # its rate [m/s]
        axis, y, ydot, h = d.axis, d.y_sym, d.ydot_sym, self._h_step
        k_s, c1, c2, vb = d.k_s, d.c1, d.c2, d.v_b

        def maxwell_force(mbs, t, itemNumber, displacement, rotation, velocity, angularVelocity,
                          stiffness, damping, rotJ0, rotJ1, offset):
            f = [zero] * 6
            f[axis] = maxwell_force_N(displacement[axis], y, ydot, h, k_s, c1, c2, vb,
                                      _SYMBOLIC_OPS)
            return f

        self._set_user_function(d.connector, maxwell_force, zero, y, ydot)

    def _set_user_function(self, co, function, *keep) -> None:
        """``function`` as the symbolic springForceTorqueUserFunction of connector ``co``."""
        fn = CreateSymbolicUserFunction(self.mbs, function, "springForceTorqueUserFunction", co)
        self.mbs.SetObjectParameter(co, "springForceTorqueUserFunction", fn)
        self._sym += [fn, *keep]

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

        # the rail: a point of the ground, or of the wheelset's track body on a flexible track
        rail = ([self._track_bodies[iw], [0.0, y, 0.0]] if self._flexible else
                [self._ground, [float(self.wheelset_x_m[iw]) + self._x0_m, y, 0.0]])
        co = self.mbs.CreateCartesianSpringDamper(
            itemNumbers=[rail[0], self._wheelsets[iw]], localPosition0=rail[1],
            localPosition1=[0.0, y, -p.wheel_radius_m], show=False)
        fn = CreateSymbolicUserFunction(self.mbs, contact_force, "springForceUserFunction", co)
        self.mbs.SetObjectParameter(co, "springForceUserFunction", fn)
        if j == 0:
            self._contacts, self._rail_vars = [], []
        self._contacts.append(co)
        self._rail_vars.append((rz, rv))
        self._sym += [fn, zero]

    def _add_wheel_rail_contact(self) -> None:
        """Contact guidance (``guidance="contact"``): a spin node per wheelset and one
        ``ObjectGenericODE2`` on all four wheelset bodies and spin nodes (28 coordinates, per
        wheelset the body's 6 and its spin) whose force user function is the contact law of
        the 8 wheels (:class:`~vehicle.wheelrail.track_contact.WheelsetTrackContact`: one call
        per residual evaluation for the whole car) and whose Jacobian user function
        differentiates the same law (forward differences); both run compiled kernels.

        Spin nodes: one coordinate each, the rotation about the axle relative to the
        non-rotating wheelset body, with the wheelsets' spin inertia (``wheelset_inertia_yy``;
        the body keeps its own, which only meets the held pitch); they start rolling freely at
        v / r0."""
        mbs, p = self.mbs, self.params
        Is = p.wheelset_inertia_yy_kg_m2
        spin0 = self.speed_m_per_s / self._wr.r0
        self._spin_nodes = [mbs.AddNode(exu.itemInterface.NodeGenericODE2(
            referenceCoordinates=[0.0], initialCoordinates=[0.0], initialCoordinates_t=[spin0],
            numberOfODE2Coordinates=1)) for _ in range(4)]
        mbs.AddObject(exu.itemInterface.ObjectGenericODE2(nodeNumbers=self._spin_nodes,
                                                          massMatrix=np.diag([Is] * 4)))
        self._ws_nodes = [mbs.GetObject(b)["nodeNumber"] for b in self._wheelsets]
        nodes = [n for pair in zip(self._ws_nodes, self._spin_nodes) for n in pair]
        self._track_nodes = []
        if self._flexible:
            self._track_nodes = self._add_track_nodes()
            nodes = [n for trio in zip(self._ws_nodes, self._spin_nodes, self._track_nodes)
                     for n in trio]
        wr = self._wr

        def forces(mbs, t, itemNumber, q, q_t):
            return wr.forces(q, q_t)

        def jacobian(mbs, t, itemNumber, q, q_t, fODE2, fODE2_t):
            return wr.jacobian(q, q_t, fODE2, fODE2_t)

        self._wr_object = mbs.AddObject(exu.itemInterface.ObjectGenericODE2(
            nodeNumbers=nodes, forceUserFunction=forces, jacobianUserFunction=jacobian))

    def _add_track_nodes(self) -> list:
        """Flexible track, contact guidance: per wheelset a node of three coordinates, the
        track's lateral displacement (along the track plane), vertical displacement and roll
        about the tangent through the track centre at rail level, under that wheelset, with the
        track's mass, stiffness and damping to the ground on them (one ``ObjectGenericODE2``;
        the contact's reaction is in the contact law, :mod:`vehicle.wheelrail.track_contact`).
        The track mass moves with the wheelset along the track but carries no inertia of that
        travel: it stands for the rails and sleepers under the wheel at each instant."""
        mbs, ts = self.mbs, self.track_structure
        nodes = [mbs.AddNode(exu.itemInterface.NodeGenericODE2(
            referenceCoordinates=[0.0] * 3, initialCoordinates=[0.0] * 3,
            initialCoordinates_t=[0.0] * 3, numberOfODE2Coordinates=3)) for _ in range(4)]

        def per_node(values):
            return np.diag(list(values) * 4)

        mbs.AddObject(exu.itemInterface.ObjectGenericODE2(
            nodeNumbers=nodes,
            massMatrix=per_node((ts.mass_kg, ts.mass_kg, ts.roll_inertia_kg_m2)),
            stiffnessMatrix=per_node((ts.lateral_stiffness_N_per_m, ts.vertical_stiffness_N_per_m,
                                      ts.roll_stiffness_N_m_per_rad)),
            dampingMatrix=per_node((ts.lateral_damping_N_s_per_m, ts.vertical_damping_N_s_per_m,
                                    ts.roll_damping_N_m_s_per_rad))))
        return nodes

    def _add_track_body(self, iw: int) -> int:
        """Flexible track, kinematic guidance: the track under wheelset ``iw`` as a body free to
        move vertically and to roll about its centre at rail level (a ``GenericJoint`` locks the
        rest), on a vertical spring-damper and a roll spring-damper to the ground; both wheels'
        vertical contacts act on it (:meth:`_add_contact`), so it carries the wheelset's load
        and the load difference between its wheels. It stays where the wheelset started: with
        vertical contact forces only, where it stands does not matter, and it carries no inertia
        of the wheelset's travel (see :meth:`_add_track_nodes`). The vertical spring's offset
        carries the static load of the wheelset on its rails: the track starts at rest at 0."""
        mbs, ts = self.mbs, self.track_structure
        pos = [float(self.wheelset_x_m[iw]) + self._x0_m, 0.0, 0.0]
        inertia = ts.roll_inertia_kg_m2
        body = mbs.CreateRigidBody(
            inertia=RigidBodyInertia(mass=ts.mass_kg, inertiaTensor=np.diag([inertia] * 3),
                                     inertiaTensorAtCOM=True),
            referencePosition=pos, nodeType=exu.NodeType.RotationRxyz)
        mbs.CreateGenericJoint(itemNumbers=[self._ground, body], position=pos,
                               constrainedAxes=[1, 1, 0, 0, 1, 1], show=False)
        K, D = np.zeros((6, 6)), np.zeros((6, 6))
        K[2, 2], K[3, 3] = ts.vertical_stiffness_N_per_m, ts.roll_stiffness_N_m_per_rad
        D[2, 2], D[3, 3] = ts.vertical_damping_N_s_per_m, ts.roll_damping_N_m_s_per_rad
        preload_m = 2.0 * self.Q_static_N / ts.vertical_stiffness_N_per_m
        mbs.CreateRigidBodySpringDamper(itemNumbers=[self._ground, body], localPosition0=pos,
                                        localPosition1=[0.0, 0.0, 0.0], stiffness=K, damping=D,
                                        offset=[0.0, 0.0, preload_m, 0.0, 0.0, 0.0], show=False)
        return body

    def _offset_wheelsets(self, offsets) -> None:
        """Initial lateral displacements of the wheelsets (see ``wheelset_lateral_offset_m``)."""
        if not self._contact_mode:
            raise ValueError("wheelset_lateral_offset_m needs guidance='contact'")
        y0 = np.asarray(offsets, dtype=float).reshape(4)
        lo, hi = self._wr.table.y_range_m
        if not np.all((y0 > lo) & (y0 < hi)):
            raise ValueError(f"wheelset_lateral_offset_m must lie inside the contact table "
                             f"({lo} .. {hi} m), got {y0}")
        geo = self._wr.table.geometry(y0)
        for body, y, dz, roll in zip(self._wheelsets, y0, geo["dz0"], geo["roll0"]):
            node = self.mbs.GetObject(body)["nodeNumber"]
            self.mbs.SetNodeParameter(node, "initialCoordinates",
                                      [0.0, float(y), float(dz), float(roll), 0.0, 0.0])

    def _init_contact_state(self) -> None:
        """After Assemble: the object's coordinate indices in the system vectors and the track
        frames at t = 0."""
        idx = []
        for i, (nb, ns) in enumerate(zip(self._ws_nodes, self._spin_nodes)):
            i0 = int(self.mbs.GetNodeODE2Index(nb))
            idx += list(range(i0, i0 + 6)) + [int(self.mbs.GetNodeODE2Index(ns))]
            if self._flexible:
                it = int(self.mbs.GetNodeODE2Index(self._track_nodes[i]))
                idx += [it, it + 1, it + 2]
        self._wr_index = np.array(idx)
        self._set_contact_track(0.0)
