"""Linear stability of a wheelset pressed against the flange: the continuous contact model's
eigenvalues, without an integrator (why the law smooths its table and damps its
normal force, :class:`~vehicle.wheelrail.contact_law.ContactLawTable`).

The wheelset of :mod:`~vehicle.wheelrail.contact_law` (coordinates y, z, roll, yaw in the
track frame and the spin rate) rolls at speed V on a curve of curvature kappa, tied to a fixed
bogie by linear springs (the car's primary suspension: :class:`Restraint`), loaded by its axle
load and a constant lateral force F towards the right rail. For each F the steady state (all
rates zero, spin from the moment balance) is solved and the law is linearised about it by
central differences; the eigenvalues of the first-order system

    d/dt (q, q', w) = (q', M^-1 f(q, q', w), m_spin(q, q', w) / I_spin)

say whether small motions about that state grow (real part > 0). Sweeping F from 0 walks the
right wheel from the tread over the flange root onto the flank. Creep forces are included:
they are what drives the flange-contact flutter of a lightly damped normal contact.

Pure numpy/scipy (no exudyn): ``python -m vehicle.wheelrail.stability`` prints the sweep for
the shipped table of the car's 0.42 m wheels; ``--weak-mode`` what the weak ~40 Hz mode on the
flank depends on (:func:`weak_mode_study`).
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import NamedTuple, Sequence

import numpy as np
from scipy.optimize import fsolve

from .contact_law import GEOMETRY_COLUMNS, SCALAR, ContactLawTable, WheelsetParams, WheelsetState, generalized_forces

__all__ = ["Restraint", "SteadyFlanging", "flange_sweep", "weakest_mode", "weak_mode_study"]


@dataclass(frozen=True)
class Restraint:
    """Springs from the wheelset to a fixed bogie: the metro car's primary suspension of one
    wheelset (two axleboxes 2 m apart: 2 x 2.17 MN/m lateral, 2 x 0.68 MN/m vertical, roll
    2 x 0.68 MN/m x 1 m^2, yaw 2 x 17.5 MN/m x 1 m^2, vehicle.params.VehicleParams) and the
    yaw angle the bogie holds the wheelset at (the angle of attack of a leading wheelset in a
    100 m curve, -15 mrad)."""

    lateral_N_per_m: float = 4.34e6
    vertical_N_per_m: float = 1.36e6
    roll_N_m_per_rad: float = 1.36e6
    yaw_N_m_per_rad: float = 35.0e6
    yaw_rad: float = -0.015


class SteadyFlanging(NamedTuple):
    """One load of :func:`flange_sweep`."""

    lateral_load_N: float
    y_m: float  # wheelset lateral displacement (right: < 0)
    gamma_right_rad: float  # contact angle of the right (flanging) wheel
    residual: float  # largest scaled residual of the steady state (converged: ~1e-12)
    eigenvalues: np.ndarray  # of the linearised motion about it [1/s]
    system_matrix: np.ndarray  # that linearisation, d/dt x = A x, x = (q, q', spin rate)

    def growth_per_s(self, above_hz: float = 0.0) -> float:
        """Largest real part of the eigenvalues oscillating above ``above_hz`` [1/s]."""
        ev = self.eigenvalues[np.abs(self.eigenvalues.imag) >= 2.0 * math.pi * above_hz]
        return float(ev.real.max()) if ev.size else -math.inf


def flange_sweep(law: ContactLawTable, params: WheelsetParams,
                 lateral_loads_N: Sequence[float], speed_m_per_s: float = 10.0,
                 curvature_1_per_m: float = 0.01,
                 restraint: Restraint = Restraint()) -> list[SteadyFlanging]:
    """Steady states and eigenvalues for the lateral loads (N, towards the right rail: < 0),
    solved in the given order, each starting from the previous (a continuation: give them in
    increasing magnitude)."""
    p, rs, V, kappa = params, restraint, float(speed_m_per_s), float(curvature_1_per_m)
    mass = np.array([p.mass_kg, p.mass_kg, p.roll_inertia_kg_m2, p.yaw_inertia_kg_m2])
    vertical_load = p.axle_load_N + p.mass_kg * p.gravity_m_per_s2

    def forces(q, qt, spin, F):
        y, z, roll, yaw = q
        st = WheelsetState(y, z, roll, yaw, qt[0], qt[1], qt[2], qt[3], spin)
        Q = generalized_forces(SCALAR, st, law.geometry(y), V, kappa, p, law.reference_load_N)
        f = np.array([Q[1] + F - rs.lateral_N_per_m * y,
                      Q[2] - vertical_load - rs.vertical_N_per_m * z,
                      Q[3] - rs.roll_N_m_per_rad * roll,
                      Q[5] - rs.yaw_N_m_per_rad * (yaw - rs.yaw_rad)])
        return f, Q[6]

    def rhs(x, F):
        f, m_spin = forces(x[:4], x[4:8], x[8], F)
        return np.concatenate([x[4:8], f / mass, [m_spin / p.spin_inertia_kg_m2]])

    r0 = float(law.geometry(0.0)["r_L"])
    sink = (0.5 * vertical_load / p.hertz_constant_N_per_m1_5) ** (2.0 / 3.0)  # Hertz approach
    u = np.array([0.0, -sink, 0.0, rs.yaw_rad, V / r0])  # y, z, roll, yaw, spin rate
    out = []
    F_prev = 0.0
    for F in lateral_loads_N:
        def steady(v, F=F):
            try:
                f, m_spin = forces(v[:4], np.zeros(4), v[4], F)
            except ValueError:  # a trial state far off the table (a contact angle past 90 deg)
                return np.full(5, 1e6)
            return np.concatenate([f / 1e4, [m_spin / 1e3]])  # kN-scale residuals

        # continuation in 8 sub-steps from the previous load (the steady state moves fast
        # where the contact angle turns)
        with warnings.catch_warnings():  # fsolve warns when it cannot improve a converged
            warnings.simplefilter("ignore", RuntimeWarning)  # state: the residual tells
            for Fk in np.linspace(F_prev, F, 9)[1:]:
                u = fsolve(lambda v, Fk=Fk: steady(v, Fk), u, xtol=1e-13)
        F_prev = F
        x0 = np.concatenate([u[:4], np.zeros(4), u[4:]])
        # central differences: 1 nm / 1 nrad in position (the contact overlap is ~50 um),
        # 0.1 um/s in rate
        steps = np.array([1e-9] * 4 + [1e-7] * 5)
        A = np.empty((9, 9))
        for j, h in enumerate(steps):
            dx = np.zeros(9)
            dx[j] = h
            A[:, j] = (rhs(x0 + dx, F) - rhs(x0 - dx, F)) / (2.0 * h)
        out.append(SteadyFlanging(float(F), float(u[0]),
                                  float(law.geometry(u[0])["gamma_R"]),
                                  float(np.abs(steady(u)).max()), np.linalg.eigvals(A), A))
    return out


def weakest_mode(state: SteadyFlanging, params: WheelsetParams, above_hz: float = 10.0):
    """The least damped mode oscillating above ``above_hz``: (growth [1/s], frequency [Hz], the
    share of each velocity (y', z', roll', yaw', spin) in its kinetic energy)."""
    w, vectors = np.linalg.eig(state.system_matrix)
    k = int(np.argmax(np.where(np.abs(w.imag) >= 2.0 * math.pi * above_hz, w.real, -np.inf)))
    p = params
    inertia = np.array([p.mass_kg, p.mass_kg, p.roll_inertia_kg_m2, p.yaw_inertia_kg_m2,
                        p.spin_inertia_kg_m2])
    energy = inertia * np.abs(vectors[4:, k]) ** 2
    return float(w[k].real), float(abs(w[k].imag) / (2.0 * math.pi)), energy / energy.sum()


def _without(law: ContactLawTable, prefixes: tuple[str, ...]) -> ContactLawTable:
    """A copy of ``law`` whose Kalker coefficients with these prefixes are 0 (those creep terms
    switched off)."""
    import copy
    out = copy.copy(law)
    out.values = law.values.copy()
    for j, name in enumerate(GEOMETRY_COLUMNS):
        if name.startswith(prefixes):
            out.values[j] = 0.0
    out.slopes = np.diff(out.values, axis=1) / np.diff(out.y)
    return out


def weak_mode_study(load_N: float = -40e3) -> None:
    """What the weak ~40 Hz flanging mode depends on: the least damped mode above 10 Hz at
    ``load_N`` with terms of the model switched off or scaled one at a time."""
    from dataclasses import replace

    from .geometry import ContactTable, table_path

    table = ContactTable.from_csv(table_path(0.42))
    loads = np.linspace(0.0, load_N, 11)
    base = WheelsetParams()
    law = ContactLawTable(table, base)
    variants = [("shipped law", law, base)]
    for f in (0.25, 10.0, 100.0):
        p = replace(base, spin_inertia_kg_m2=base.spin_inertia_kg_m2 * f)
        variants.append((f"spin inertia x{f:g}", ContactLawTable(table, p), p))
    variants += [("longitudinal creep off (k11 = 0)", _without(law, ("k11",)), base),
                 ("spin creep off (k23 = k33 = 0)", _without(law, ("k23", "k33")), base)]
    p = replace(base, contact_damping_N_s_per_m=2.0 * base.contact_damping_N_s_per_m)
    variants.append(("normal damping x2", ContactLawTable(table, p), p))
    print(f"least damped mode above 10 Hz at F = {load_N / 1e3:g} kN (kinetic energy shares of "
          f"y', z', roll', yaw', spin)")
    for label, variant, p in variants:
        state = flange_sweep(variant, p, loads)[-1]
        growth, hz, share = weakest_mode(state, p)
        print(f"  {label:34s} {growth:+7.2f} /s {hz:6.1f} Hz  "
              + " ".join(f"{x:.2f}" for x in share))


def main() -> None:
    import sys

    if "--weak-mode" in sys.argv[1:]:
        weak_mode_study()
        return
    from .geometry import ContactTable, table_path

    table = ContactTable.from_csv(table_path(0.42))
    loads = -np.arange(0.0, 60.1e3, 4e3)
    for label, law, c in (
            ("shipped law: table smoothed 0.1 mm, normal damping 2e5 N s/m",
             ContactLawTable(table), 2e5),
            ("rigid table as it is, normal damping 5e4 N s/m (the first version)",
             ContactLawTable(table, smoothing_mm=0), 5e4)):
        params = WheelsetParams(contact_damping_N_s_per_m=c)
        law = ContactLawTable(table, params, smoothing_mm=law.smoothing_mm)
        print(label)
        print("  F [kN]   y [mm]  gamma_R [rad]  growth [1/s]: all modes / above 100 Hz")
        for s in flange_sweep(law, params, loads):
            print(f"  {s.lateral_load_N / 1e3:6.1f} {1e3 * s.y_m:8.3f} {s.gamma_right_rad:10.3f}"
                  f" {s.growth_per_s():14.2f} {s.growth_per_s(100.0):10.2f}")


if __name__ == "__main__":
    main()
