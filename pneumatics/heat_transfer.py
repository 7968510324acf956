"""A chamber's own heat exchange with the atmosphere (docs/models.md, "Heat transfer per chamber").

By default every chamber exchanges heat with its case's k (eq. 8, dQ/dt = k (T_atm - T)). A bellow
or a tank may carry its own law instead, :class:`ChamberHeat`:

* ``model: constant``: its own k [W/K], the same in every case (0 adiabatic, inf isothermal);
* ``model: correlation``: k from convection correlations at the chamber's state,
  :func:`wall_conductance_W_per_K`.

**The correlation** (every equation number is Incropera, DeWitt, Bergman & Lavine, *Fundamentals
of Heat and Mass Transfer*, 6th ed., Wiley 2007; the same in Bergman et al., 7th ed., 2011). The
heat crosses three resistances in series, over one area A (a thin wall: inside area = outside
area), steady (the wall stores no heat):

    1 / k = 1 / (h_in A) + t / (lambda A) + 1 / (h_out A)

* Inside, h_in: natural convection along the wall of the chamber's height L_n (a bellow: its air
  column V / A_e; a tank, lying: its diameter D), Churchill & Chu's vertical plate (eq. 9.26,
  "the entire range of Ra_L"; Int. J. Heat Mass Transfer 18 (1975) 1323), combined with forced
  convection from the air flowing in, a flat plate of length D (laminar eq. 7.30 for Re_L up to
  5e5, mixed laminar-turbulent eq. 7.38 above, to 1e8; Pr 0.6-60; taken as the larger of the two,
  which switches within 1.4 % of eq. 7.38 at Re_L = 5e5), by Churchill's rule h^3 = h_F^3 +
  h_N^3 (eq. 9.64 with n = 3, on the h's: the two Nu have different lengths). The forced flow's
  velocity is that of the inflow's jet once its momentum flux has spread over the chamber's
  cross-section A_x (a momentum balance, assumed: rho u_c^2 A_x = mdot_in u_jet), u_c = mdot_in /
  (rho sqrt(A_port A_x)), mdot_in the air flowing in (the chamber's outflow stirs nothing)
  through a port of bore ``port_diameter_m``.
* Wall: conduction t / lambda (a bellow: its rubber; a tank: its steel).
* Outside, h_out: natural convection, a bellow's side as a vertical plate of its height V / A_e
  (eq. 9.26; a vertical cylinder is a plate when D / L >= 35 / Gr_L^(1/4), eq. 9.33: a bellow
  is wider than tall), a tank as a horizontal cylinder of diameter D (Churchill & Chu, eq. 9.34,
  Ra_D <= 1e12; Int. J. Heat Mass Transfer 18 (1975) 1049), combined as inside with forced
  convection at a steady air speed across the chamber (``air_speed_m_per_s``, default 0: still
  air), a cylinder in cross flow (Churchill & Bernstein, eq. 7.54, Re_D Pr >= 0.2; J. Heat
  Transfer 99 (1977) 300; the tank's axis assumed across the flow); in parallel with radiation to
  surroundings at the atmosphere's temperature, h_rad = eps sigma (T_w + T_atm)(T_w^2 + T_atm^2)
  (eq. 1.9; a grey surface of emissivity eps, ``emissivity``, 0.9 assumed: in still air it is as
  large as the natural convection). Inside, dry air neither emits nor absorbs, and the walls
  see each other at one temperature: no radiation.

The air's properties are those of the film, T_f = (T + T_wall) / 2, on each side: viscosity and
conductivity by Sutherland's law (White, *Viscous Fluid Flow*, 3rd ed., McGraw-Hill 2006, eqs 1-36
and 1-44, Tables 1-2 and 1-3: mu_0 = 1.716e-5 Pa s, S = 111 K; k_0 = 0.0241 W/(m K), S = 194 K;
T_0 = 273 K; within 1.5 % of Incropera Table A.4 at 250-350 K, tested), c_p of the gas, density
of the ideal gas at the side's pressure, beta = 1 / T_f. The wall temperatures follow from the
heat flux being the same through all three resistances, solved by :data:`WALL_ITERATIONS`
substitutions from the even split (each cuts the error by ~0.3 at worst, measured).

The chamber's surfaces: a bellow is a cylinder of its effective area A_e (D = sqrt(4 A_e / pi))
and its air column's height V / A_e, A = pi D V / A_e + 2 A_e (the real bellow's rubber bulges
beyond D: its area is larger); a tank a cylinder of diameter D (given, or by default two
diameters long) and length 4 V / (pi D^2), A = pi D L + pi D^2 / 2. Both follow the crushing.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional

from pneumorail.quantities import plausible

from .compiled import elementwise, scalar

#: the laws a chamber may carry (its ``heat: {model: ...}``)
HEAT_MODELS = ("constant", "correlation")

#: assumed values (none is measured for the paper's bellow and tank; docs/models.md)
#: a rail airspring's wall: rubber on nylon cord plies, 6 mm thick (assumed)
RUBBER_THICKNESS_M = 0.006
#: reinforced elastomer: 0.2-0.3 W/(m K) (assumed mid value)
RUBBER_CONDUCTIVITY_W_PER_MK = 0.25
#: an auxiliary tank's steel shell, 3 mm (assumed)
STEEL_THICKNESS_M = 0.003
#: carbon steel, assumed; Incropera Table A.1 at 300 K: plain carbon steel 60.5, AISI 1010 63.9,
#: stainless AISI 304 14.9 W/(m K) (the wall's share of the resistance is ~1e-4 at any of them)
STEEL_CONDUCTIVITY_W_PER_MK = 50.0
#: the bore air enters a chamber through: Table 1's pipe (assumed for every chamber)
PORT_DIAMETER_M = 0.018
#: a tank's length over its diameter when its diameter is not given (assumed)
TANK_LENGTH_PER_DIAMETER = 2.0
#: the outside surface's emissivity, rubber or painted steel (assumed; non-metallic and painted
#: surfaces are 0.8-0.95, Incropera Table A.11)
EMISSIVITY = 0.9
#: Stefan-Boltzmann constant [W/(m^2 K^4)] (CODATA 2018)
STEFAN_BOLTZMANN = 5.670374419e-8

#: standard gravity [m/s^2]
GRAVITY_M_PER_S2 = 9.80665
#: substitutions of the wall temperatures (see the module docstring): each cuts the error by ~0.3
#: at worst, k is within 5e-7 of the converged value after 10 over air at 120-420 K, 0.3-20
#: kg/m^3, still to 1 kg/s of inflow, 0-50 m/s outside (tests/pneumatics/test_heat_transfer.py
#: checks 1e-6 against a root solve); the correlations themselves are good to 10-20 %
WALL_ITERATIONS = 10

# Sutherland's law for air (White, Tables 1-2 and 1-3)
MU_REF_PA_S, MU_S_K = 1.716e-5, 111.0
K_REF_W_PER_MK, K_S_K = 0.0241, 194.0
SUTHERLAND_T_REF_K = 273.0

_K_RANGE = plausible(0.0, None, "W/K", "a chamber's own heat-transfer coefficient: 0 adiabatic, .inf isothermal",
                     infinite=True)


@dataclass(frozen=True)
class ChamberHeat:
    """A chamber's own heat exchange with the atmosphere, instead of the case's k (eq. 8): ``model:
    constant`` with its ``k_W_per_K`` (0 adiabatic, .inf isothermal), the same in every case; or
    ``model: correlation``, k from convection inside and outside and conduction through the wall
    at the chamber's state (docs/models.md). The correlation's keys, null for the assumed value:
    ``wall_thickness_m`` and ``wall_conductivity_W_per_mK`` (a bellow's rubber: 6 mm, 0.25 W/(m
    K); a tank's steel: 3 mm, 50 W/(m K)), ``diameter_m`` (a tank's: null, two diameters long; a
    bellow's follows from its effective area), ``port_diameter_m`` (the bore air enters by: 18
    mm, Table 1's pipe), ``air_speed_m_per_s`` (air across the chamber outside: 0, still air),
    ``emissivity`` (of its outside: 0.9; 0 leaves radiation out).
    """

    model: str = "constant"
    k_W_per_K: Optional[float] = field(default=None, metadata=_K_RANGE)
    wall_thickness_m: Optional[float] = field(default=None, metadata=plausible(
        0.0, 0.05, "m", "a chamber's wall: rubber 3-10 mm, steel 2-6 mm", low_inclusive=False))
    wall_conductivity_W_per_mK: Optional[float] = field(default=None, metadata=plausible(
        0.05, 500.0, "W/(m K)", "rubber 0.2-0.3, steel 15-60, aluminium ~200", low_inclusive=False))
    diameter_m: Optional[float] = field(default=None, metadata=plausible(
        0.0, 3.0, "m", "a tank's diameter", low_inclusive=False))
    port_diameter_m: Optional[float] = field(default=None, metadata=plausible(
        0.0, 0.3, "m", "the bore of a chamber's port", low_inclusive=False))
    air_speed_m_per_s: Optional[float] = field(default=None, metadata=plausible(
        0.0, 100.0, "m/s", "air across the chamber outside: 0 still air, 100 m/s = 360 km/h"))
    emissivity: Optional[float] = field(default=None, metadata=plausible(
        0.0, 1.0, "", "of a grey surface: 0 none (radiation left out), 1 black"))

    #: the correlation's own keys (refused with ``model: constant``)
    CORRELATION_KEYS = ("wall_thickness_m", "wall_conductivity_W_per_mK", "diameter_m", "port_diameter_m",
                        "air_speed_m_per_s", "emissivity")


def bellow_surface(A_e_m2, V_m3):
    """(surface A [m^2], height V / A_e [m], diameter sqrt(4 A_e / pi) [m]) of a bellow seen as a
    cylinder of its effective area and its air column's height (arrays broadcast)."""
    height = V_m3 / A_e_m2
    diameter = (4.0 * A_e_m2 / math.pi) ** 0.5
    return math.pi * diameter * height + 2.0 * A_e_m2, height, diameter


def tank_surface(V_m3: float, diameter_m: Optional[float]):
    """(surface A [m^2], diameter D [m], length [m]) of a cylindrical tank of volume V: of diameter
    ``diameter_m``, or (None) :data:`TANK_LENGTH_PER_DIAMETER` diameters long."""
    D = diameter_m if diameter_m is not None else (4.0 * V_m3 / (math.pi * TANK_LENGTH_PER_DIAMETER)) ** (1.0 / 3.0)
    length = 4.0 * V_m3 / (math.pi * D * D)
    return math.pi * D * length + 0.5 * math.pi * D * D, D, length


@scalar
def sutherland(T_K, reference, S_K):
    """Sutherland's law: a property of air at T_K from its value at 273 K (White, eqs 1-36, 1-44)."""
    return reference * (T_K / SUTHERLAND_T_REF_K) ** 1.5 * (SUTHERLAND_T_REF_K + S_K) / (T_K + S_K)


@scalar
def vertical_plate_nusselt(Ra, Pr):
    """Churchill & Chu, a vertical plate, all Ra_L (Incropera eq. 9.26)."""
    return (0.825 + 0.387 * Ra ** (1.0 / 6.0) / (1.0 + (0.492 / Pr) ** (9.0 / 16.0)) ** (8.0 / 27.0)) ** 2


@scalar
def horizontal_cylinder_nusselt(Ra, Pr):
    """Churchill & Chu, a long horizontal cylinder, Ra_D <= 1e12 (Incropera eq. 9.34)."""
    return (0.60 + 0.387 * Ra ** (1.0 / 6.0) / (1.0 + (0.559 / Pr) ** (9.0 / 16.0)) ** (8.0 / 27.0)) ** 2


@scalar
def flat_plate_nusselt(Re, Pr):
    """Mean Nu of a flat plate in parallel flow: laminar (eq. 7.30) or, the larger above
    Re_L ~ 5e5, mixed laminar-turbulent with Re_x,c = 5e5 (eq. 7.38); Pr 0.6-60."""
    laminar = 0.664 * Re ** 0.5 * Pr ** (1.0 / 3.0)
    mixed = (0.037 * Re ** 0.8 - 871.0) * Pr ** (1.0 / 3.0)
    return max(laminar, mixed)


@scalar
def cross_flow_cylinder_nusselt(Re, Pr):
    """Churchill & Bernstein, a cylinder in cross flow, Re_D Pr >= 0.2 (Incropera eq. 7.54); 0
    in still air (Re = 0: no forced convection to combine)."""
    if Re <= 0.0:
        return 0.0
    return 0.3 + (0.62 * Re ** 0.5 * Pr ** (1.0 / 3.0) / (1.0 + (0.4 / Pr) ** (2.0 / 3.0)) ** 0.25
                  * (1.0 + (Re / 282000.0) ** 0.625) ** 0.8)


@scalar
def _film(T_K, T_wall_K, p_Pa, cp, R):
    """(conductivity, dynamic viscosity, density, Prandtl number, beta) of air at the film
    temperature (T + T_wall) / 2 and pressure p."""
    T_f = 0.5 * (T_K + T_wall_K)
    mu = sutherland(T_f, MU_REF_PA_S, MU_S_K)
    k = sutherland(T_f, K_REF_W_PER_MK, K_S_K)
    return k, mu, p_Pa / (R * T_f), cp * mu / k, 1.0 / T_f


@scalar
def _rayleigh(dT_K, L_m, k, mu, rho, cp, beta):
    """Ra_L = g beta |dT| L^3 / (nu alpha), nu = mu / rho, alpha = k / (rho c_p)."""
    return GRAVITY_M_PER_S2 * beta * abs(dT_K) * L_m ** 3 * rho * rho * cp / (mu * k)


@elementwise(15)
def wall_conductance_W_per_K(T_K, rho_kg_per_m3, inflow_kg_per_s, T_atm_K, p_atm_Pa, area_m2, height_m, diameter_m,
                             port_area_m2, wall_m2K_per_W, air_speed_m_per_s, emissivity, cylinder, cp, R):
    """k = 1 / (1 / (h_in A) + t / (lambda A) + 1 / (h_out A)) [W/K] of a chamber of air at T_K and
    density rho, ``inflow_kg_per_s`` flowing in through a port of area ``port_area_m2``, of
    surface ``area_m2``, height ``height_m`` (the inside natural convection's length; a bellow's
    outside too) and diameter ``diameter_m`` (its cross-section pi D^2 / 4, the inside forced
    convection's length, the outside cylinder's), wall resistance t / lambda ``wall_m2K_per_W``,
    in still air at T_atm, p_atm or in ``air_speed_m_per_s`` across it, radiating with
    ``emissivity`` to surroundings at T_atm; ``cylinder`` 1.0 (a tank):
    outside a horizontal cylinder, 0.0 (a bellow): a vertical plate. Module docstring: the
    equations. Compiled (:mod:`pneumatics.compiled`)."""
    p_in = rho_kg_per_m3 * R * T_K
    dT = T_K - T_atm_K
    jet_area = (port_area_m2 * 0.25 * math.pi * diameter_m * diameter_m) ** 0.5
    T_wall_in = T_K - 0.5 * dT
    T_wall_out = T_wall_in
    resistance = wall_m2K_per_W
    for _ in range(WALL_ITERATIONS):
        k, mu, rho, Pr, beta = _film(T_K, T_wall_in, p_in, cp, R)
        natural = vertical_plate_nusselt(_rayleigh(T_K - T_wall_in, height_m, k, mu, rho, cp, beta), Pr)
        # the jet's velocity u_c = inflow / (rho_chamber sqrt(A_port A_x)), Re = rho_f u_c D / mu_f
        forced = flat_plate_nusselt(rho * inflow_kg_per_s * diameter_m / (rho_kg_per_m3 * jet_area * mu), Pr)
        # Nu_N on the height, Nu_F on the length D: Churchill's rule on the h's (eq. 9.64, n = 3)
        h_in = ((natural * k / height_m) ** 3 + (forced * k / diameter_m) ** 3) ** (1.0 / 3.0)
        k, mu, rho, Pr, beta = _film(T_atm_K, T_wall_out, p_atm_Pa, cp, R)
        if cylinder > 0.5:
            h_natural = horizontal_cylinder_nusselt(_rayleigh(T_wall_out - T_atm_K, diameter_m, k, mu, rho, cp, beta),
                                                    Pr) * k / diameter_m
        else:
            h_natural = vertical_plate_nusselt(_rayleigh(T_wall_out - T_atm_K, height_m, k, mu, rho, cp, beta),
                                               Pr) * k / height_m
        h_forced = cross_flow_cylinder_nusselt(rho * air_speed_m_per_s * diameter_m / mu, Pr) * k / diameter_m
        h_radiation = emissivity * STEFAN_BOLTZMANN * (T_wall_out + T_atm_K) * (T_wall_out ** 2 + T_atm_K ** 2)
        h_out = (h_natural ** 3 + h_forced ** 3) ** (1.0 / 3.0) + h_radiation
        resistance = 1.0 / h_in + wall_m2K_per_W + 1.0 / h_out
        flux = dT / resistance
        T_wall_in = T_K - flux / h_in
        T_wall_out = T_atm_K + flux / h_out
    return area_m2 / resistance
