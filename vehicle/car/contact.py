"""Contact guidance (``guidance="contact"``): the contact table, the contact law of the car's
wheelsets and where it holds them at rest (:class:`ContactGuidance`)."""
from __future__ import annotations

import functools
from dataclasses import dataclass

from ..params import ContactParams, VehicleParams
from ..wheelrail.contact_law import ContactLawTable, WheelsetParams
from ..wheelrail.geometry import ContactTable, table_path
from ..wheelrail.track_contact import WheelsetTrackContact
from .path import CarPath
from .statics import StaticReference


@dataclass(frozen=True)
class ContactGuidance:
    """The wheel-rail contact of the car's four wheelsets."""

    #: contact parameters
    params: ContactParams
    #: the contact table in use
    table: ContactTable
    #: the contact law of the 8 wheels, evaluated by the exudyn object of the contacts
    track_contact: WheelsetTrackContact
    #: height [m] of the wheelset centres at rest on the contacts (the reference configuration)
    wheelset_z_m: float


@functools.lru_cache(maxsize=8)
def contact_table(table_csv: str, wheel_radius_m: float) -> ContactTable:
    """The contact table of :class:`ContactParams` ``table_csv``, or for an empty one the S1002 /
    UIC60 1:40 / 1435 mm table for the wheel radius: shipped, else derived (~2 s, cached)."""
    if table_csv:
        return ContactTable.from_csv(table_csv)
    path = table_path(wheel_radius_m)
    if path.exists():
        return ContactTable.from_csv(path)
    from ..wheelrail.derive_table import derive_default
    return derive_default(wheel_radius_m)


def contact_guidance(p: VehicleParams, cp: ContactParams, static: StaticReference, path: CarPath,
                     flexible_track: bool) -> ContactGuidance:
    """The contact law for the car's wheelsets and the static wheelset height on the contacts
    (the reference configuration, see the module doc of :mod:`vehicle.car`)."""
    if path.speed_m_per_s < 0.0:
        raise ValueError("guidance='contact' needs speed_m_per_s >= 0 (the creep law's "
                         f"rolling direction), got {path.speed_m_per_s}")
    g = p.gravity_m_per_s2
    table = contact_table(cp.table_csv, float(p.wheel_radius_m))
    wp = WheelsetParams(
        mass_kg=p.wheelset_mass_kg, roll_inertia_kg_m2=p.wheelset_inertia_xx_kg_m2,
        spin_inertia_kg_m2=p.wheelset_inertia_yy_kg_m2,
        yaw_inertia_kg_m2=p.wheelset_inertia_zz_kg_m2, axle_load_N=2.0 * static.axlebox_load_N,
        gravity_m_per_s2=g, hertz_constant_N_per_m1_5=p.hertz_constant_N_per_m1_5,
        contact_damping_N_s_per_m=cp.normal_damping_N_s_per_m,
        friction_coefficient=cp.friction_coefficient)
    law = ContactLawTable(table, wp, smoothing_mm=cp.table_smoothing_mm,
                          given_creep=tuple(cp.creep_coefficients) or None)
    r0 = table.r0

    def contact_model(z_centre):
        refs = [[float(x) + path.x0_m, 0.0, z_centre] for x in static.wheelset_x_m]
        return WheelsetTrackContact(law, wp, refs, r0, path.speed_m_per_s,
                                    cp.min_creep_speed_m_per_s, cp.flange_angle_rad,
                                    2.0 * static.wheel_load_N if flexible_track else None,
                                    cp.roll_rate_creepage)

    # the wheelset centre sits r0 above the rail plane in the rigid centred contact and
    # approaches it by the Hertz deflection under the static wheel load
    z_m = r0 + contact_model(r0).static_rise_m(static.wheel_load_N)
    return ContactGuidance(cp, table, contact_model(z_m), z_m)
