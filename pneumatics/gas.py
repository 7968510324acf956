"""Ideal-gas air.

All quantities are SI: Pa (absolute), K, kg, m^3.
"""
from __future__ import annotations

from dataclasses import dataclass

from pneumorail.quantities import Range

#: ISO 6358 reference conditions (paper §2.3): T_ref = 293.15 K, p_ref = 1 bar.
T_REF_K = 293.15
P_REF_PA = 1.0e5

#: the range of a given absolute pressure of air (field metadata of a supply's and a chamber's): a
#: fifth of an atmosphere to 20 bar. Railway air systems run at 10 bar or less (main reservoirs ~9
#: bar absolute, loaded airsprings 4-8), so 8 typed for 8 bar, or a gauge value in kPa, falls out
ABSOLUTE_PRESSURE = Range(2e4, 2e6, unit="Pa absolute", why="air in a railway's pneumatic system, 0.2-20 bar")
#: the range of a given air temperature (field metadata): -73 to +127 degrees Celsius covers every
#: climate a railway runs in and the heating of a fast compression; 20 typed for 20 degrees
#: Celsius falls out
AIR_TEMPERATURE = Range(200.0, 400.0, unit="K", why="air on a railway vehicle, -73 to +127 degrees Celsius")


@dataclass(frozen=True)
class Gas:
    """Ideal gas with constant specific heats (paper: R = 287 J/(kg K), gamma = 1.4 for air)."""

    R_J_per_kgK: float = 287.0
    gamma: float = 1.4

    @property
    def cv_J_per_kgK(self) -> float:
        return self.R_J_per_kgK / (self.gamma - 1.0)

    @property
    def cp_J_per_kgK(self) -> float:
        return self.gamma * self.R_J_per_kgK / (self.gamma - 1.0)

    @property
    def rho_ref_kg_per_m3(self) -> float:
        """Density at the ISO 6358 reference conditions (1.1886 kg/m^3 for air)."""
        return P_REF_PA / (self.R_J_per_kgK * T_REF_K)

    def pressure_Pa(self, m_kg, T_K, V_m3):
        """Perfect-gas law, eq. (3): p V = M R T."""
        return m_kg * self.R_J_per_kgK * T_K / V_m3

    def mass_kg(self, p_Pa, T_K, V_m3):
        return p_Pa * V_m3 / (self.R_J_per_kgK * T_K)


AIR = Gas()
