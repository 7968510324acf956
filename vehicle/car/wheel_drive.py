"""Traction and braking through the wheels (``drive=WheelDrive()``, contact guidance only).

Without it a contact car is driven at its centre: a joint holds the carbody's position along the
track at the speed profile's s(t), and the wheelsets roll behind on their creep forces. With it
there is no such joint. The car is moved by torques on the wheelsets' spin coordinates, as a
train is by its motors and brakes. Each torque reacts on the bogie frame that carries the axle's
motor or brake. The longitudinal creep forces at the rails then carry the car's inertia. The
carbody pitch, the bellows' load transfer and the wheel-load transfer (with the axle-height lever
of forces at the rails) come out of the model. So does the adhesion limit: the creep law
saturates at mu N, and a demand beyond it makes the wheels slide.

Sign convention: a torque T > 0 on a spin coordinate drives the wheel forward (rolling forward
is > 0, :mod:`vehicle.wheelrail.track_contact`). Its reaction -T acts on the bogie frame about the
frame's own y axis (the axle's, to the frame's small pitch relative to the wheelset).

**The torques** (:class:`WheelTorques`, set before every internal step and held over it). The
driver follows the speed profile by feed-forward and by feedback on where the car is against the
profile. The total force along the track is

    F = M_e a_ref - M g_t - M (omega^2 e + 2 zeta omega de/dt),    M_e = M + 4 I_s / r0^2,

where:

* a_ref is the profile's mean acceleration over the step, (v(t) - v(t0)) / (t - t0);
* on a gradient (:mod:`.gradient`) the driver also knows the line: - M g_t is added, g_t
  gravity's component along the track (< 0 uphill) on the translating mass (the spins feel
  none);
* M is the translating mass (carbody with its payload at the step's start, two bogie frames, four
  wheelsets);
* I_s is a wheelset's spin inertia and r0 the centred rolling radius;
* e is the mean of the four wheelsets' offsets along the track from where the profile puts them,
  and de/dt its rate;
* omega = 2 pi ``tracking_frequency_Hz`` and zeta = ``tracking_damping_ratio``.

The feedback stands for the driver and the brake controller. It takes up what the feed-forward
does not know: curving and rolling resistance, and the creep a torque needs. On its own the car
is a mass on a spring of M omega^2. A resistance R leaves it R / (M omega^2) behind the profile
(at 0.5 Hz and 26 t: 1 mm per 100 N).

F >= 0 (traction) is shared equally by the motored wheelsets. F < 0 (braking) is shared equally by
all four: blended braking, every axle braked. Wheelset i gets T_i = r0 F_i.

At a stand a = 0, and the feedback holds the car where the profile stopped it (the holding brake).
Below the contact's ``min_creep_speed_m_per_s`` the creep law is viscous, not divided by zero
(:mod:`vehicle.wheelrail.track_contact`).

Left out:
* the motors' and gears' rotating inertia (only the wheelsets' spin inertia is in M_e);
* wheel-slide protection: a demand beyond adhesion lets a wheelset slide; once its creepage
  passes :data:`SLIDE_CREEPAGE` the car stops (:class:`vehicle.errors.WheelSlide`) and a
  co-simulation stops the case with a diagnosis;
* the brake's friction character: a torque is applied as asked for, whatever the wheel's spin.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import exudyn as exu
import numpy as np

__all__ = ["WheelDrive", "WheelTorques", "SLIDE_CREEPAGE"]

#: a wheelset slides once its longitudinal creepage (v - r0 Omega) / v passes this: ten times the
#: ~0.5 % at which Kalker's law with Shen-Hedrick-Elkins saturation reaches mu N on a 40 kN wheel
#: (3 mu N / f11, f11 ~ 9 MN): past saturation nothing holds the spin, and the creepage runs away
SLIDE_CREEPAGE = 0.05
#: ... relative to the wheelset's speed, or to this speed below it [m/s] (a car at a stand: a slip
#: of 5 cm/s)
SLIDE_SPEED_M_PER_S = 1.0


@dataclass(frozen=True)
class WheelDrive:
    """How a contact car is moved along its speed profile: by torques on its wheelsets (module doc).

    Args:
        motored_wheelsets: the wheelsets that carry traction, 1..4 from the front (braking: all).
        tracking_frequency_Hz: the driver's feedback on the car's position against the profile,
            as a natural frequency [Hz] of the car's mass on the feedback's spring.
        tracking_damping_ratio: its damping ratio.
    """

    motored_wheelsets: Sequence[int] = (1, 2, 3, 4)
    tracking_frequency_Hz: float = 0.5
    tracking_damping_ratio: float = 1.0

    def __post_init__(self):
        motored = tuple(self.motored_wheelsets)
        if not motored or any(not isinstance(i, (int, np.integer)) or isinstance(i, bool) or not 1 <= i <= 4
                              for i in motored) or len(set(motored)) != len(motored):
            raise ValueError("motored_wheelsets must be distinct wheelset numbers 1..4 (from the front), "
                             f"at least one, got {self.motored_wheelsets!r}")
        object.__setattr__(self, "motored_wheelsets", tuple(sorted(int(i) for i in motored)))
        for name in ("tracking_frequency_Hz", "tracking_damping_ratio"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{name} must be finite and > 0, got {value!r}")


class WheelTorques:
    """The torques of one car's :class:`WheelDrive`, as exudyn loads: a ``LoadCoordinate`` on each
    spin node and a body-fixed torque on each bogie frame (the reactions). Built before the
    system is assembled (:meth:`build`); set before every internal step (:meth:`pre_step`)."""

    def __init__(self, drive: WheelDrive, spin_loads: list, bogie_loads: list, r0_m: float,
                 spin_inertia_kg_m2: float, tare_mass_kg: float):
        self.drive = drive
        self._spin_loads, self._bogie_loads = spin_loads, bogie_loads
        self.r0_m = float(r0_m)
        self._spin_inertia = float(spin_inertia_kg_m2)
        self._tare_mass_kg = float(tare_mass_kg)
        self._motored = np.zeros(4)
        self._motored[[i - 1 for i in drive.motored_wheelsets]] = 1.0 / len(drive.motored_wheelsets)
        self._omega = 2.0 * math.pi * drive.tracking_frequency_Hz
        #: total force along the track asked for over the last step [N] (> 0 traction)
        self.force_N = 0.0
        #: per wheelset the torque of the last step [N m] (> 0 driving forward)
        self.torques_N_m = np.zeros(4)
        #: the car's mean offset along the track from the profile [m] and its rate [m/s]
        self.offset_m, self.offset_rate_m_per_s = 0.0, 0.0
        #: per wheelset the longitudinal creepage at the last step's start (> 0 braking)
        self.creepage = np.zeros(4)

    @classmethod
    def build(cls, mbs, drive: WheelDrive, spin_nodes: list, bogies: list, r0_m: float,
              spin_inertia_kg_m2: float, tare_mass_kg: float) -> WheelTorques:
        """Add the loads (zero) to ``mbs`` before it is assembled."""
        spin_loads = []
        for node in spin_nodes:
            marker = mbs.AddMarker(exu.itemInterface.MarkerNodeCoordinate(nodeNumber=node, coordinate=0))
            spin_loads.append(mbs.AddLoad(exu.itemInterface.LoadCoordinate(markerNumber=marker, load=0.0)))
        bogie_loads = [mbs.CreateTorque(itemNumber=b, loadVector=[0.0, 0.0, 0.0], bodyFixed=True, show=False)
                       for b in bogies]
        return cls(drive, spin_loads, bogie_loads, r0_m, spin_inertia_kg_m2, tare_mass_kg)

    def force(self, a_ref: float, offset_m: float, rate_m_per_s: float, payload_kg: float,
              gravity_along_m_per_s2: float = 0.0) -> float:
        """The total force along the track [N] for the profile's acceleration ``a_ref`` [m/s^2],
        the car's mean offset from the profile and its rate, and gravity's component along the
        track (module doc)."""
        mass = self._tare_mass_kg + payload_kg
        effective = mass + 4.0 * self._spin_inertia / (self.r0_m * self.r0_m)
        zeta, omega = self.drive.tracking_damping_ratio, self._omega
        return (effective * a_ref - mass * gravity_along_m_per_s2
                - mass * (omega * omega * offset_m + 2.0 * zeta * omega * rate_m_per_s))

    def shares(self, force_N: float) -> np.ndarray:
        """Each wheelset's share of ``force_N`` [N]: traction on the motored ones, braking on all."""
        return force_N * (self._motored if force_N >= 0.0 else np.full(4, 0.25))

    def set(self, mbs, a_ref: float, offset_m: float, rate_m_per_s: float, payload_kg: float,
            gravity_along_m_per_s2: float = 0.0) -> None:
        """Set the torques for the coming step."""
        self.offset_m, self.offset_rate_m_per_s = offset_m, rate_m_per_s
        self.force_N = self.force(a_ref, offset_m, rate_m_per_s, payload_kg, gravity_along_m_per_s2)
        torques = self.r0_m * self.shares(self.force_N)
        self.torques_N_m = torques
        for load, torque in zip(self._spin_loads, torques.tolist()):
            mbs.SetLoadParameter(load, "load", torque)
        for load, pair in zip(self._bogie_loads, (torques[:2].sum(), torques[2:].sum())):
            mbs.SetLoadParameter(load, "loadVector", [0.0, -float(pair), 0.0])
