"""Building the car's exudyn model (:func:`build_model`): the bodies, the wheelset guidance and
the drive, the primary suspension, the secondary suspension (:mod:`.secondary`), the wheel-rail
contacts and the flexible track's bodies; what it built, as indices and symbolic variables:
:class:`CarModel`. The model itself is described in :mod:`vehicle.car`."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import exudyn as exu
import numpy as np
from exudyn.advancedUtilities import CreateSymbolicUserFunction
from exudyn.rigidBodyUtilities import RigidBodyInertia

from ..params import WHEELS, VehicleParams
from ..payload import CarbodyMass
from .contact import ContactGuidance
from .options import HOLDS, ModelOptions
from .path import CarPath
from .secondary import (
    AirspringConnectors,
    Mounts,
    OptionalComponents,
    add_airsprings,
    add_lateral_bumpstops,
    add_optional_components,
)
from .statics import StaticReference
from .wheel_drive import WheelTorques

esym = exu.symbolic


@dataclass(frozen=True)
class CarModel:
    """The car's exudyn model as built and assembled: the indices of its items and the symbolic
    variables its force laws and joints read (each set from Python before a step)."""

    ground: Any
    carbody: Any
    #: bogie frames, front then rear
    bogies: list
    #: wheelsets 1..4 from the front
    wheelsets: list
    #: per wheelset the guidance joint's offset variables (xi, eta, rx, ry, rz), see
    #: :meth:`_Builder.wheelset_guidance`
    guidance_vars: list
    #: contact guidance on a track: the joint that drives the carbody and its variables (xi, rz)
    drive: Any
    drive_vars: tuple | None
    airsprings: AirspringConnectors
    #: lateral bumpstop connectors, front then rear bogie
    bumpstops: list
    #: kinematic guidance: per wheel (:data:`~vehicle.params.WHEELS` order) the Hertz contact
    #: connector and its variables (rail height [m], rail rate [m/s])
    wheel_contacts: list
    rail_vars: list
    #: kinematic guidance on a flexible track: the track body under each wheelset
    track_bodies: list | None
    #: contact guidance: per wheelset its spin node, its body's node and (flexible track) its
    #: track node; the contact object; the indices of its coordinates in the system vectors
    spin_nodes: list
    wheelset_nodes: list
    track_nodes: list
    contact_object: Any
    contact_index: np.ndarray | None
    optional: OptionalComponents
    #: the carbody's external force and torque (``carbody_load``), else None
    load_force: Any
    load_torque: Any
    #: contact guidance driven through the wheels (``drive``): the torques, else None
    wheel_torques: WheelTorques | None
    #: symbolic variables and functions that must live as long as the system
    keep_alive: list


def build_model(mbs, p: VehicleParams, static: StaticReference, path: CarPath, options: ModelOptions,
                contact: ContactGuidance | None, step_s: float, rail0_m: np.ndarray,
                carbody: CarbodyMass | None = None) -> CarModel:
    """Build the car into the empty system ``mbs`` and assemble it. ``rail0_m``: (8,) rail heights
    at t = 0 (kinematic guidance); ``step_s``: the internal step (the Maxwell laws' first);
    ``carbody``: the carbody's mass properties with its payload at t = 0 (None: the tare body of
    ``p``; its reference point stays the tare centre of gravity either way)."""
    return _Builder(mbs, p, static, path, options, contact).build(step_s, rail0_m, carbody)


class _Builder:
    """One car built into one system (:func:`build_model`)."""

    def __init__(self, mbs, p: VehicleParams, static: StaticReference, path: CarPath,
                 options: ModelOptions, contact: ContactGuidance | None):
        self.mbs, self.params, self.static, self.path, self.options = mbs, p, static, path, options
        self.contact = contact
        self.flexible = options.track_structure.flexible
        self.keep_alive = []  # symbolic variables and functions: must live as long as the system
        self.ground = self.carbody = None
        self.bogies, self.wheelsets = [], []

    def build(self, step_s: float, rail0_m: np.ndarray, carbody: CarbodyMass | None = None) -> CarModel:
        p, mbs, static = self.params, self.mbs, self.static
        gravity = [0.0, 0.0, -p.gravity_m_per_s2]

        def body(m, ixx, iyy, izz, pos):
            return mbs.CreateRigidBody(
                inertia=RigidBodyInertia(mass=m, inertiaTensor=np.diag([ixx, iyy, izz]),
                                         inertiaTensorAtCOM=True),
                referencePosition=[pos[0] + self.path.x0_m, pos[1], pos[2]],
                initialVelocity=[self.path.speed_m_per_s, 0.0, 0.0], gravity=gravity,
                nodeType=exu.NodeType.RotationRxyz)

        self.ground = mbs.CreateGround()
        self.carbody = body(p.carbody_mass_kg, p.carbody_inertia_xx_kg_m2,
                            p.carbody_inertia_yy_kg_m2, p.carbody_inertia_zz_kg_m2,
                            [0.0, 0.0, p.carbody_cog_height_m])
        if carbody is not None:          # loaded at t = 0: the same node, the loaded body's mass
            mbs.SetObjectParameter(self.carbody, "mass", carbody.mass_kg)
            mbs.SetObjectParameter(self.carbody, "centerOfMass", list(carbody.com_m))
            mbs.SetObjectParameter(self.carbody, "inertia", list(carbody.inertia6_kg_m2))
        self.bogies = [body(p.bogie_mass_kg, p.bogie_inertia_xx_kg_m2, p.bogie_inertia_yy_kg_m2,
                            p.bogie_inertia_zz_kg_m2, [x, 0.0, p.bogie_cog_height_m])
                       for x in static.bogie_x_m]
        self.wheelsets = [body(p.wheelset_mass_kg, p.wheelset_inertia_xx_kg_m2,
                               p.wheelset_inertia_yy_kg_m2, p.wheelset_inertia_zz_kg_m2,
                               [x, 0.0, static.wheelset_z_m])
                          for x in static.wheelset_x_m]
        guidance_vars = []
        for iw in range(4):
            guidance_vars.append(self.wheelset_guidance(iw))
            self.primary(iw)
        driven_at_centre = self.contact is not None and self.path.guided and self.options.drive is None
        drive, drive_vars = self.drive() if driven_at_centre else (None, None)
        for name in self.options.held:
            self.hold(name)
        mounts = Mounts(mbs, p, self.carbody, self.bogies, static.bogie_x_m, self.keep_alive)
        airsprings = add_airsprings(mounts, static)
        bumpstops = add_lateral_bumpstops(mounts)
        wheel_contacts, rail_vars, track_bodies = [], [], None
        spin_nodes, wheelset_nodes, track_nodes, contact_object = [], [], [], None
        wheel_torques = None
        if self.contact is not None:
            spin_nodes, wheelset_nodes, track_nodes, contact_object = self.wheel_rail_contact()
            if self.options.drive is not None:
                wheel_torques = WheelTorques.build(
                    mbs, self.options.drive, spin_nodes, self.bogies, self.contact.track_contact.r0,
                    p.wheelset_inertia_yy_kg_m2, p.carbody_mass_kg + 2.0 * p.bogie_mass_kg + 4.0 * p.wheelset_mass_kg)
        else:
            wheel_contacts, rail_vars, track_bodies = self.hertz_contacts(rail0_m)
        # optional components (nothing is built when they are off: the same model, bit for bit)
        optional = add_optional_components(mounts, step_s)
        load_force = load_torque = None
        if self.options.carbody_load:
            load_force = mbs.CreateForce(itemNumber=self.carbody, show=False)
            load_torque = mbs.CreateTorque(itemNumber=self.carbody, show=False)
        if self.options.wheelset_lateral_offset_m is not None:
            self.offset_wheelsets(self.options.wheelset_lateral_offset_m)
        mbs.Assemble()
        contact_index = None
        if self.contact is not None:
            contact_index = self.contact_coordinates(wheelset_nodes, spin_nodes, track_nodes)
        return CarModel(self.ground, self.carbody, self.bogies, self.wheelsets, guidance_vars, drive,
                        drive_vars, airsprings, bumpstops, wheel_contacts, rail_vars, track_bodies,
                        spin_nodes, wheelset_nodes, track_nodes, contact_object, contact_index,
                        optional, load_force, load_torque, wheel_torques, self.keep_alive)

    def wheelset_guidance(self, iw: int) -> tuple:
        """Track guidance of wheelset ``iw`` (see :mod:`vehicle.car`); returns its variables.

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
        forces (the car is driven at its centre, :meth:`drive`)."""
        mbs = self.mbs
        xi = esym.Real(f"xi{iw}", 0.0)  # [m]
        eta = esym.Real(f"eta{iw}", 0.0)  # [m]
        rx = esym.Real(f"rx{iw}", 0.0)  # Tait-Bryan angles of Rz(psi) Rx(-cant) [rad]
        ry = esym.Real(f"ry{iw}", 0.0)
        rz = esym.Real(f"rz{iw}", 0.0)
        zero = esym.Real(0.0)

        def offset(mbs, t, itemNumber, offsetUserFunctionParameters):
            return [xi, eta, zero, rx, ry, rz]

        pos = [float(self.static.wheelset_x_m[iw]) + self.path.x0_m, 0.0, 0.0]
        # contact guidance: only the pitch stays prescribed (the body does not spin)
        axes = [0, 0, 0, 0, 1, 0] if self.contact is not None else [1, 1, 0, 0, 1, 1]
        joint = mbs.CreateGenericJoint(itemNumbers=[self.ground, self.wheelsets[iw]],
                                       position=pos, constrainedAxes=axes, show=False)
        if self.path.guided:
            self._set_offset_function(joint, offset, zero)
        return xi, eta, rx, ry, rz

    def _set_offset_function(self, joint, offset, *keep) -> None:
        """``offset`` as the symbolic offsetUserFunction of ``joint``."""
        fn = CreateSymbolicUserFunction(self.mbs, offset, "offsetUserFunction", joint)
        self.mbs.SetObjectParameter(joint, "offsetUserFunction", fn)
        self.keep_alive.extend([fn, *keep])

    def drive(self) -> tuple:
        """Contact guidance: the car is driven at its centre; returns the joint and its variables.
        A ``GenericJoint`` between ground and the carbody's centre of gravity locks only its
        position along the track tangent at the car centre's arc length s_c(t) = start_s + v t,
        t . (p - p0) = xi_c(t) (the joint frame turns with the heading there, through a symbolic
        offset user function like the wheelsets' guidance): the carbody is free laterally,
        vertically and in every rotation, and the wheelsets, each held only in pitch, roll along
        behind it on their creep forces, where the bogie frames and the primary suspension put
        them. Its reaction is the force along the track that keeps the speed (the curving
        resistance of the creep forces), along the tangent at the car centre: no force across
        the track.

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

        joint = mbs.CreateGenericJoint(itemNumbers=[self.ground, self.carbody],
                                       position=[self.path.x0_m, 0.0, p.carbody_cog_height_m],
                                       constrainedAxes=[1, 0, 0, 0, 0, 0], show=False)
        self._set_offset_function(joint, offset, zero)
        return joint, (xi, rz)

    def hold(self, name: str) -> None:
        """Hold what :data:`.options.HOLDS` ``name`` says: per body a ``GenericJoint`` to the ground
        at the body's centre of gravity that locks the axes given (global x, y, z, roll, pitch,
        yaw; lateral and rotations only, so the body still runs along x at the car's speed).
        Straight track only: the joint frame is the ground's."""
        if self.path.track is not None:
            raise ValueError("held bodies need straight track (track=None): the holding joints do not "
                             "follow a track's heading")
        bodies = {"carbody": self.carbody, **{f"bogie {i + 1}": b for i, b in enumerate(self.bogies)},
                  **{f"wheelset {i + 1}": w for i, w in enumerate(self.wheelsets)}}
        for body, axes in HOLDS[name]:
            node = self.mbs.GetNode(self.mbs.GetObject(bodies[body])["nodeNumber"])
            position = [float(c) for c in node["referenceCoordinates"][:3]]
            self.mbs.CreateGenericJoint(itemNumbers=[self.ground, bodies[body]], position=position,
                                        constrainedAxes=list(axes), show=False)

    def primary(self, iw: int) -> None:
        """Left and right axlebox springs between bogie frame and wheelset ``iw``.

        Displacement u = 0 at the static position; the z offset carries the static axlebox load
        P (force on the wheelset -K (u - offset) = -P e_z). Intrinsic formulation (axes of the
        mid-frame between bogie and wheelset, force applied at the midpoint of the two markers
        on both bodies): no spurious couple P x (relative displacement), see :mod:`vehicle.car`."""
        p, static = self.params, self.static
        ib = iw // 2
        K = np.diag([p.primary_stiffness_x_N_per_m, p.primary_stiffness_y_N_per_m,
                     p.primary_stiffness_z_N_per_m, 0.0, 0.0, 0.0])
        D = np.diag([p.primary_damping_x_N_s_per_m, p.primary_damping_y_N_s_per_m,
                     p.primary_damping_z_N_s_per_m, 0.0, 0.0, 0.0])
        off_z = -static.axlebox_load_N / p.primary_stiffness_z_N_per_m
        for y in (p.primary_lateral_spacing_m / 2.0, -p.primary_lateral_spacing_m / 2.0):
            self.mbs.CreateRigidBodySpringDamper(
                itemNumbers=[self.bogies[ib], self.wheelsets[iw]],
                localPosition0=[static.wheelset_x_m[iw] - static.bogie_x_m[ib], y,
                                static.wheelset_z_m - p.bogie_cog_height_m],
                localPosition1=[0.0, y, 0.0],
                stiffness=K, damping=D, offset=[0.0, 0.0, off_z, 0.0, 0.0, 0.0],
                useIntrinsicFormulation=True, show=False)

    def hertz_contacts(self, rail0_m: np.ndarray) -> tuple[list, list, list | None]:
        """Kinematic guidance: the vertical Hertz contact of every wheel (:meth:`wheel_contact`),
        on the track bodies of a flexible track (:meth:`track_body`); returns the connectors,
        their variables and the track bodies (None: rigid track)."""
        track_bodies = [self.track_body(iw) for iw in range(4)] if self.flexible else None
        contacts = [self.wheel_contact(j, rail0_m[j], track_bodies) for j in range(8)]
        return [co for co, _ in contacts], [variables for _, variables in contacts], track_bodies

    def wheel_contact(self, j: int, rail0_m: float, track_bodies: list | None) -> tuple:
        """Wheel ``WHEELS[j]``: unilateral Hertz contact against its prescribed rail height;
        returns the connector and its variables (rail height, rail rate).

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
        rail = ([track_bodies[iw], [0.0, y, 0.0]] if self.flexible else
                [self.ground, [float(self.static.wheelset_x_m[iw]) + self.path.x0_m, y, 0.0]])
        co = self.mbs.CreateCartesianSpringDamper(
            itemNumbers=[rail[0], self.wheelsets[iw]], localPosition0=rail[1],
            localPosition1=[0.0, y, -p.wheel_radius_m], show=False)
        fn = CreateSymbolicUserFunction(self.mbs, contact_force, "springForceUserFunction", co)
        self.mbs.SetObjectParameter(co, "springForceUserFunction", fn)
        self.keep_alive.extend([fn, zero])
        return co, (rz, rv)

    def wheel_rail_contact(self) -> tuple:
        """Contact guidance (``guidance="contact"``): a spin node per wheelset and one
        ``ObjectGenericODE2`` on all four wheelset bodies and spin nodes (28 coordinates, per
        wheelset the body's 6 and its spin) whose force user function is the contact law of
        the 8 wheels (:class:`~vehicle.wheelrail.track_contact.WheelsetTrackContact`: one call
        per residual evaluation for the whole car) and whose Jacobian user function
        differentiates the same law (forward differences); both run compiled kernels. Returns
        (spin nodes, wheelset body nodes, track nodes, the contact object).

        Spin nodes: one coordinate each, the rotation about the axle relative to the
        non-rotating wheelset body, with the wheelsets' spin inertia (``wheelset_inertia_yy``;
        the body keeps its own, which only meets the held pitch); they start rolling freely at
        v / r0."""
        mbs, p = self.mbs, self.params
        wr = self.contact.track_contact
        Is = p.wheelset_inertia_yy_kg_m2
        spin0 = self.path.speed_m_per_s / wr.r0
        spin_nodes = [mbs.AddNode(exu.itemInterface.NodeGenericODE2(
            referenceCoordinates=[0.0], initialCoordinates=[0.0], initialCoordinates_t=[spin0],
            numberOfODE2Coordinates=1)) for _ in range(4)]
        mbs.AddObject(exu.itemInterface.ObjectGenericODE2(nodeNumbers=spin_nodes,
                                                          massMatrix=np.diag([Is] * 4)))
        ws_nodes = [mbs.GetObject(b)["nodeNumber"] for b in self.wheelsets]
        nodes = [n for pair in zip(ws_nodes, spin_nodes) for n in pair]
        track_nodes = []
        if self.flexible:
            track_nodes = self.track_nodes()
            nodes = [n for trio in zip(ws_nodes, spin_nodes, track_nodes) for n in trio]

        def forces(mbs, t, itemNumber, q, q_t):
            return wr.forces(q, q_t)

        def jacobian(mbs, t, itemNumber, q, q_t, fODE2, fODE2_t):
            return wr.jacobian(q, q_t, fODE2, fODE2_t)

        contact_object = mbs.AddObject(exu.itemInterface.ObjectGenericODE2(
            nodeNumbers=nodes, forceUserFunction=forces, jacobianUserFunction=jacobian))
        return spin_nodes, ws_nodes, track_nodes, contact_object

    def track_nodes(self) -> list:
        """Flexible track, contact guidance: per wheelset a node of three coordinates, the
        track's lateral displacement (along the track plane), vertical displacement and roll
        about the tangent through the track centre at rail level, under that wheelset, with the
        track's mass, stiffness and damping to the ground on them (one ``ObjectGenericODE2``;
        the contact's reaction is in the contact law, :mod:`vehicle.wheelrail.track_contact`).
        The track mass moves with the wheelset along the track but carries no inertia of that
        travel: it stands for the rails and sleepers under the wheel at each instant."""
        mbs, ts = self.mbs, self.options.track_structure
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

    def track_body(self, iw: int) -> int:
        """Flexible track, kinematic guidance: the track under wheelset ``iw`` as a body free to
        move vertically and to roll about its centre at rail level (a ``GenericJoint`` locks the
        rest), on a vertical spring-damper and a roll spring-damper to the ground; both wheels'
        vertical contacts act on it (:meth:`wheel_contact`), so it carries the wheelset's load
        and the load difference between its wheels. It stays where the wheelset started: with
        vertical contact forces only, where it stands does not matter, and it carries no inertia
        of the wheelset's travel (see :meth:`track_nodes`). The vertical spring's offset
        carries the static load of the wheelset on its rails: the track starts at rest at 0."""
        mbs, ts = self.mbs, self.options.track_structure
        pos = [float(self.static.wheelset_x_m[iw]) + self.path.x0_m, 0.0, 0.0]
        inertia = ts.roll_inertia_kg_m2
        body = mbs.CreateRigidBody(
            inertia=RigidBodyInertia(mass=ts.mass_kg, inertiaTensor=np.diag([inertia] * 3),
                                     inertiaTensorAtCOM=True),
            referencePosition=pos, nodeType=exu.NodeType.RotationRxyz)
        mbs.CreateGenericJoint(itemNumbers=[self.ground, body], position=pos,
                               constrainedAxes=[1, 1, 0, 0, 1, 1], show=False)
        K, D = np.zeros((6, 6)), np.zeros((6, 6))
        K[2, 2], K[3, 3] = ts.vertical_stiffness_N_per_m, ts.roll_stiffness_N_m_per_rad
        D[2, 2], D[3, 3] = ts.vertical_damping_N_s_per_m, ts.roll_damping_N_m_s_per_rad
        preload_m = 2.0 * self.static.wheel_load_N / ts.vertical_stiffness_N_per_m
        mbs.CreateRigidBodySpringDamper(itemNumbers=[self.ground, body], localPosition0=pos,
                                        localPosition1=[0.0, 0.0, 0.0], stiffness=K, damping=D,
                                        offset=[0.0, 0.0, preload_m, 0.0, 0.0, 0.0], show=False)
        return body

    def offset_wheelsets(self, offsets) -> None:
        """Initial lateral displacements of the wheelsets (see ``wheelset_lateral_offset_m``)."""
        if self.contact is None:
            raise ValueError("wheelset_lateral_offset_m needs guidance='contact'")
        table = self.contact.track_contact.table
        y0 = np.asarray(offsets, dtype=float).reshape(4)
        lo, hi = table.y_range_m
        if not np.all((y0 > lo) & (y0 < hi)):
            raise ValueError(f"wheelset_lateral_offset_m must lie inside the contact table "
                             f"({lo} .. {hi} m), got {y0}")
        geo = table.geometry(y0)
        for body, y, dz, roll in zip(self.wheelsets, y0, geo["dz0"], geo["roll0"]):
            node = self.mbs.GetObject(body)["nodeNumber"]
            self.mbs.SetNodeParameter(node, "initialCoordinates",
                                      [0.0, float(y), float(dz), float(roll), 0.0, 0.0])

    def contact_coordinates(self, wheelset_nodes: list, spin_nodes: list, track_nodes: list) -> np.ndarray:
        """After Assemble: the contact object's coordinate indices in the system vectors."""
        idx = []
        for i, (nb, ns) in enumerate(zip(wheelset_nodes, spin_nodes)):
            i0 = int(self.mbs.GetNodeODE2Index(nb))
            idx += list(range(i0, i0 + 6)) + [int(self.mbs.GetNodeODE2Index(ns))]
            if self.flexible:
                it = int(self.mbs.GetNodeODE2Index(track_nodes[i]))
                idx += [it, it + 1, it + 2]
        return np.array(idx)
