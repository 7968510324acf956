"""Pneumatic chambers: bellows and tanks (paper §2.1, eqs 1-4 and 8).

The functions are pure and vectorised: every argument may be a scalar or an array, with
chambers along the first axis and, optionally, independent cases along a trailing axis.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional, Tuple

import numpy as np

from pneumorail.quantities import plausible, ranged

from .compiled import elementwise
from .gas import ABSOLUTE_PRESSURE, AIR_TEMPERATURE
from .heat_transfer import ChamberHeat

#: ranges of the chambers' fields (metadata). An airspring's effective area: the paper's 0.13 m^2,
#: the largest rail airsprings ~0.5 m^2 (a value in cm^2 is ~1e4 times too large)
_AREA = plausible(0.0, 2.0, "m^2", "an airspring's effective area", low_inclusive=False)
#: an airspring's volume: 1 litre (a small cab airspring) to 1 m^3 (the paper's holds 12 litres,
#: the largest rail airsprings ~0.1 m^3; a value in litres is 1000 times too large)
_BELLOW_VOLUME = plausible(1e-3, 1.0, "m^3", "an airspring's volume")
#: a rigid vessel's volume: 1 litre to 10 m^3 (the paper's auxiliary tank holds 27 litres, a
#: train's main reservoirs 0.1-1 m^3)
VESSEL_VOLUME = plausible(1e-3, 10.0, "m^3", "an auxiliary tank or a main reservoir")


@dataclass(frozen=True)
class Bellow:
    """An airspring: a chamber whose volume and effective area depend on the crushing z.

    z is positive in compression (docs/models.md): V = V0 - (dV/dz) z, A_e = A0 + (dA/dz) z.
    Defaults are the paper's Table 1 (its "volume gradient 0.13 m^2" equals the effective area).
    ``p0_Pa`` None means the user of the circuit sets it (e.g. from the static load).

    A measured effective area replaces the linear law when given as a table of crushing
    (``area_table_z_m``, increasing) and area (``area_table_m2``): A_e(z) interpolated linearly
    between the points and held at the end values beyond them (``A0_m2``, ``dA_dz_m`` are then
    not used). Manufacturers give A_e against height; crushing is nominal height minus height.

    ``heat``: its own heat exchange (:class:`~pneumatics.heat_transfer.ChamberHeat`); None, the
    case's k (eq. 8).
    """

    V0_m3: float = field(default=0.012, metadata=_BELLOW_VOLUME)
    # the volume gradient is about the effective area (Table 1: both 0.13 m^2)
    dV_dz_m2: float = field(default=0.13, metadata=_AREA)
    A0_m2: float = field(default=0.13, metadata=_AREA)
    # +-10 m: the area changing by 0.1 m^2 (most of it) over 10 mm of crushing
    dA_dz_m: float = field(default=0.0, metadata=plausible(-10.0, 10.0, "m", "change of effective area with crushing, "
                                                                              "either sign"))
    p0_Pa: Optional[float] = field(default=None, metadata=ranged(ABSOLUTE_PRESSURE))
    T0_K: Optional[float] = field(default=None, metadata=ranged(AIR_TEMPERATURE))
    area_table_z_m: Tuple[float, ...] = field(default=(), metadata=plausible(-0.5, 0.5, "m", "crushing from the static height"))
    area_table_m2: Tuple[float, ...] = field(default=(), metadata=_AREA)
    heat: Optional[ChamberHeat] = None

    def volume_m3(self, z_m):
        return self.V0_m3 - self.dV_dz_m2 * z_m

    def area_m2(self, z_m):
        """Effective area A_e(z) [m^2]."""
        if self.area_table_z_m:
            return np.interp(z_m, self.area_table_z_m, self.area_table_m2)
        return self.A0_m2 + self.dA_dz_m * z_m

    def area_slope_m(self, z_m):
        """dA_e/dz [m]: ``dA_dz_m``, or the slope of the table's interval at z (0 beyond its ends,
        where the area is held)."""
        if not self.area_table_z_m:
            return self.dA_dz_m
        zs, As = np.asarray(self.area_table_z_m), np.asarray(self.area_table_m2)
        slopes = np.diff(As) / np.diff(zs)
        z = np.asarray(z_m, float)
        i = np.clip(np.searchsorted(zs, z, side="right") - 1, 0, len(slopes) - 1)
        return np.where((z < zs[0]) | (z > zs[-1]), 0.0, slopes[i])


@dataclass(frozen=True)
class Tank:
    """A rigid chamber (auxiliary tank, or a finite main reservoir). Table 1: 27 dm^3.

    ``heat``: its own heat exchange (:class:`~pneumatics.heat_transfer.ChamberHeat`); None, the
    case's k (eq. 8).
    """

    V_m3: float = field(default=0.027, metadata=VESSEL_VOLUME)
    p0_Pa: Optional[float] = field(default=None, metadata=ranged(ABSOLUTE_PRESSURE))
    T0_K: Optional[float] = field(default=None, metadata=ranged(AIR_TEMPERATURE))
    heat: Optional[ChamberHeat] = None


def bellow_force_N(A_e_m2, p_Pa, p_atm_Pa):
    """Vertical bellow force, eq. (4): F = A_e (p_b - p_a). Positive pushes carbody and bogie apart."""
    return A_e_m2 * (p_Pa - p_atm_Pa)


# Eq. (2) and the enthalpy its flows carry are evaluated on every chamber and link at every stage
# of the integrator: compiled (:mod:`pneumatics.compiled`: one call instead of a numpy operation
# per term, the same operations in the same order; tests/pneumatics/test_compiled.py). A compiled
# law costs ~60 ms to load in every process that calls it (numba builds its ufunc's loop anew):
# only the laws with many terms are, not eq. (8) (two) nor the isothermal heat flow.

def heat_flow_into_W(k_W_per_K, T_K, T_atm_K):
    """Heat flow INTO a chamber from the atmosphere, eq. (8) with the physical sign.

    The paper writes dQ/dt = k (T - T_atm) and adds it in eq. (2); taken literally a hot
    chamber would heat up further (docs/models.md, erratum 1). Heat flows from hot to cold:
    dQ/dt = k (T_atm - T).
    """
    return k_W_per_K * (T_atm_K - T_K)


@elementwise(8)
def temperature_rate_K_per_s(m_kg, T_K, p_Pa, mdot_in_kg_per_s, Hdot_in_W, Qdot_in_W, Vdot_m3_per_s,
                             cv_J_per_kgK):
    """First law for an open chamber, eq. (2).

    dT/dt = (gamma-1)/(R M) (sum q_i h_i - R T/(gamma-1) sum q_i + dQ/dt - p dV/dt)
          = (Hdot_in - cv T Mdot + Qdot - p Vdot) / (M cv),
    with h_i the total enthalpy c_p T_upstream carried by each entering flow q_i.
    """
    return (Hdot_in_W - cv_J_per_kgK * T_K * mdot_in_kg_per_s + Qdot_in_W - p_Pa * Vdot_m3_per_s) / (
        m_kg * cv_J_per_kgK)


def isothermal_heat_flow_W(T_K, p_Pa, mdot_in_kg_per_s, Hdot_in_W, Vdot_m3_per_s, cv_J_per_kgK):
    """Heat flow that holds T constant (the k -> infinity limit): eq. (2) solved for dQ/dt with dT/dt = 0."""
    return cv_J_per_kgK * T_K * mdot_in_kg_per_s - Hdot_in_W + p_Pa * Vdot_m3_per_s


@elementwise(4)
def upstream_enthalpy_flow_W(w_kg_per_s, T_a_K, T_b_K, cp_J_per_kgK):
    """The total enthalpy a link's flow w (a -> b) carries, eq. (2)'s q_i h_i: w c_p T of the
    node upstream (a's for w >= 0, b's otherwise, and for a NaN flow, as np.where has it)."""
    return w_kg_per_s * (cp_J_per_kgK * (T_a_K if w_kg_per_s >= 0.0 else T_b_K))


def bellow_stiffness_N_per_m(bellow: Bellow, z_m, p_Pa, p_atm_Pa, polytropic_index):
    """Instantaneous stiffness dF/dz of a closed bellow, polytropic exponent n (gamma adiabatic, 1 isothermal).

    dF/dz = dA/dz (p - p_atm) + A_e n p (dV/dz) / V; for a cylindrical bellow (dA/dz = 0)
    this is the paper's gamma A^2 p0 / V (adiabatic) or A^2 p0 / V (isothermal), §1 and Table 2.
    """
    V = bellow.volume_m3(z_m)
    return (bellow.area_slope_m(z_m) * (p_Pa - p_atm_Pa)
            + bellow.area_m2(z_m) * polytropic_index * p_Pa * bellow.dV_dz_m2 / V)


def quasi_static_stiffness_N_per_m(bellow: Bellow, p0_Pa, V_m3, polytropic_index):
    """Table 2: n A^2 p0 / V (n = gamma adiabatic, 1 isothermal) for a bellow whose air, of total
    volume V (bellow plus tank), is compressed at z = 0: n A0 (dV/dz) p0 / V, with dV/dz = A0 for
    the paper's cylindrical bellow (Table 1, docs/models.md erratum 3). (dA/dz = 0 assumed: the
    effective-area term dA/dz (p0 - p_atm) would add to it.)"""
    return polytropic_index * bellow.A0_m2 * bellow.dV_dz_m2 * p0_Pa / V_m3
