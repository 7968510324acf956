"""A pipe that carries pressure waves: a lumped compressible line (``model: compressible``).

The pipe of length L, bore d and area A is cut into N cells of length dx = L / N. Each cell is a
small rigid, adiabatic chamber (:class:`PipeCell`, volume A dx, states mass and temperature, eqs
1-3 as every chamber); N + 1 inertial links (:class:`PipeSegment`, state: the mass flow q, a ->
b) join the pipe's end a, the cells in order and its end b: a staggered grid, pressures at the
cell centres, flows at the faces. The inner links are dx long; the two end links dx / 2 (an end
node sits at the pipe's end, the first cell's centre dx / 2 inside), so the links' lengths add up
to L and the cells' volumes to A L.

Momentum, on a link of length l between nodes L and R:

    (l / A) dq/dt = (p_L - p_R) + (M_L - M_R) / A - (lambda(Re) l / d + zeta_j) q |q| / (2 rho A^2),

rho the mean density of its two nodes. M is the momentum flux rho u^2 A of a cell: its mass flow
(the mean of its two links') times the velocity of its upwind link (an end cell moves with its
inner link). On an end link, M is left out (the flux is the same at the pipe's end as at its
first cell's centre); instead, air entering the pipe from a chamber at rest accelerates
isentropically to its cell's velocity u, a drop p_C (1 - (1 - u^2 / (2 c_p T_C))^(gamma /
(gamma - 1))) (rho u^2 / 2 at low speed), and air leaving it is a jet whose dynamic pressure is
not regained (its kinetic energy heats the chamber: the exit loss, 1 velocity head). zeta_j =
max(zeta - 1, 0) / 2 on each end link and 0 inside: ``zeta`` keeps eq. (5)'s meaning, the pipe's
total loss coefficient in a steady flow, exit loss included. lambda is the pipe's
``friction_factor`` when given (constant), or Churchill's (1977) smooth-pipe formula of the
Reynolds number Re = |q| d / (A mu) when it is null: 64 / Re in laminar flow (the drop then
linear in q), Blasius-like turbulent, one smooth curve through the transition
(:func:`darcy_friction_factor`).

Energy. Each cell's first law is the chambers' eq. (2), with the flows carrying the total
enthalpy c_p T + u^2 / 2 of their upstream node (a chamber's air at rest: c_p T) and each cell's
kinetic energy m u^2 / 2 taken out of its internal energy as it changes.

What it conserves. Mass exactly: every link's flow leaves one node and enters the next. Energy:
the internal energy of cells and chambers plus the cells' kinetic energy changes only by the
enthalpy from boundary nodes, the heat and the bellows' work (to the integrator's tolerance);
friction and the exit jet's dissipation stay in the air as heat. Momentum up to the friction and
the ends. For small motions it is the linear acoustic line (wave speed sqrt(gamma R T), the
pipe's modes, its compliance A L / (gamma p)); with the momentum flux and the kinetic energy it
also converges to Euler's solution of Sod's shock tube, at the order of an upwind scheme.

Choking. The links have no sonic limit of their own. A jet leaving the pipe sees no pressure
below the critical one, p0 (2 / (gamma + 1))^(gamma / (gamma - 1)), of its cell's stagnation
state (T0 = T + u^2 / (2 c_p), p0 = p (T0 / T)^(gamma / (gamma - 1))), and its flow is limited to
the isentropic choked mass flow of that state, m* = A p0 sqrt(gamma / (R T0)) (2 / (gamma +
1))^((gamma + 1) / (2 (gamma - 1))): the end link's state q passes as w = q / (1 + |q /
m*|^n)^(1/n) (n = :data:`CHOKE_SHARPNESS`; w = q within 1e-10 below |q| = m* / 3, and to first
order at rest, so the acoustics are untouched), and q relaxes towards w in the link's acoustic
time l / c (no wind-up). Mass and energy balances use w. Air entering the pipe and the inner
links are not limited: in a steady flow they carry what the exit passes.

Cells exchange no heat (``k_W_per_K`` is the bellows' and tanks'): a pipe's cycle is faster than
its wall's thermal time at the frequencies its waves matter. With k = inf the chambers are
isothermal, the cells still adiabatic.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Dict, Mapping, Tuple

from .chamber import Tank
from .compiled import elementwise, scalar
from .errors import CircuitError
from .pipe import Pipe

#: the loss coefficient of a jet leaving a pipe into a chamber (Borda-Carnot: its dynamic
#: pressure, not regained), which the compressible pipe models itself and takes out of zeta
EXIT_LOSS = 1.0
#: the model name of a compressible pipe, and of the links it is made of
COMPRESSIBLE = "compressible"
SEGMENT = "compressible_segment"
#: dynamic viscosity of air at 20 degrees Celsius [Pa s] (the Reynolds number of the wall friction)
AIR_VISCOSITY_PA_S = 1.81e-5
#: exponent n of the end links' choke w = q / (1 + |q/m*|^n)^(1/n): below |q| = m*/3, w = q within
#: 3^-20 / 20 = 1e-11; a pipe blowing into the atmosphere holds its exit at q = 1.09 m* and passes
#: 0.99 m* (at n = 10 it passed 0.97 m*)
CHOKE_SHARPNESS = 20.0


@dataclass(frozen=True)
class PipeCell(Tank):
    """A cell of a compressible pipe: a rigid chamber of the pipe's air, at ``position`` (0 at
    end ``a``, 1 at ``b``) along pipe ``pipe``. With no initial pressure of its own it starts at
    the pressure and temperature interpolated between the pipe's ends' (``ends``)."""

    pipe: str = ""
    ends: Tuple[str, str] = ("", "")
    position: float = 0.5


@dataclass(frozen=True)
class PipeSegment(Pipe):
    """A link of a compressible pipe (eq. 5 over its length; ``zeta``: its share of the fittings'
    loss). ``end``: ``a`` or ``b`` for the links at the pipe's ends (choked there), ``""`` inside;
    ``friction_factor`` None: from the Reynolds number."""

    owner: str = ""
    end: str = ""


def cell_count(pipe: Pipe) -> int:
    """N: ``cells``, or the length over ``cell_length_m`` rounded up (at least 1)."""
    if pipe.cells:
        return int(pipe.cells)
    return max(1, math.ceil(pipe.length_m / pipe.cell_length_m - 1e-9))


def _check(name: str, pipe: Pipe) -> None:
    cells = pipe.cells
    if isinstance(cells, bool) or not isinstance(cells, int) or cells < 0:
        raise CircuitError([name, "cells"], f"must be an integer >= 0 (0: from cell_length_m), got {cells!r}")
    if not (math.isfinite(pipe.cell_length_m) and pipe.cell_length_m > 0):
        raise CircuitError([name, "cell_length_m"], f"must be > 0 m, got {pipe.cell_length_m}")
    for field in ("length_m", "diameter_m"):
        if not getattr(pipe, field) > 0:
            raise CircuitError([name, field], f"must be > 0, got {getattr(pipe, field)}")


def expand_compressible_pipes(components: Mapping[str, object]) -> Dict[str, object]:
    """``components`` with each compressible pipe replaced, where it stands, by its links and
    cells: the link at end ``a`` keeps the pipe's name (a fault on the pipe, a flow looked up by
    its name, find it), the others are ``<pipe>.seg<i>`` (i = 1..N), the cells ``<pipe>.cell<i>``
    (i = 1..N, from a to b). Other components are kept, in their order. A pipe whose
    ``friction_factor`` is null must be compressible."""
    out: Dict[str, object] = {}
    for name, comp in components.items():
        if not isinstance(comp, Pipe) or isinstance(comp, PipeSegment):
            out[name] = comp
            continue
        if comp.model != COMPRESSIBLE:
            if comp.friction_factor is None:
                raise CircuitError([name, "friction_factor"], "null (from the Reynolds number) needs model: "
                                                              "compressible; give a number")
            out[name] = comp
            continue
        _check(name, comp)
        n = cell_count(comp)
        dx = comp.length_m / n
        fittings = max(comp.zeta - EXIT_LOSS, 0.0)     # the exit's velocity head is the model's own
        cells = [f"{name}.cell{i}" for i in range(1, n + 1)]
        nodes = [comp.a, *cells, comp.b]
        for i in range(n + 1):
            end = "a" if i == 0 else ("b" if i == n else "")
            out[name if i == 0 else f"{name}.seg{i}"] = PipeSegment(
                nodes[i], nodes[i + 1], length_m=dx / 2 if end else dx, diameter_m=comp.diameter_m,
                friction_factor=comp.friction_factor, zeta=fittings / 2 if end else 0.0, model=SEGMENT,
                owner=name, end=end)
        for i, cell in enumerate(cells):
            out[cell] = PipeCell(V_m3=comp.area_m2 * dx, pipe=name, ends=(comp.a, comp.b), position=(i + 0.5) / n)
    return out


@scalar
def darcy_friction_factor(reynolds):
    """Churchill's (1977) Darcy friction factor of a smooth pipe, every regime in one smooth
    curve: 64/Re laminar, within 2 % of Blasius 0.316 Re^-1/4 at Re = 1e4-1e5 (Re > 0)."""
    a = (2.457 * 0.9 * math.log(reynolds / 7.0)) ** 16
    b = (37530.0 / reynolds) ** 16
    return 8.0 * ((8.0 / reynolds) ** 12 + (a + b) ** -1.5) ** (1.0 / 12.0)


@elementwise(9)
def segment_flow_rate_kg_per_s2(q_kg_per_s, p_a_Pa, p_b_Pa, rho_kg_per_m3, length_m, area_m2, zeta, diameter_m,
                                viscosity_Pa_s):
    """dq/dt of a link of a compressible pipe whose lambda follows the Reynolds number:
    A/l ((p_a - p_b) - (lambda(Re) l / d + zeta) q |q| / (2 rho A^2)), Re = |q| d / (A mu).
    lambda |q| is evaluated as one expression, finite at q = 0 (64 A mu / d: laminar friction is
    linear in the flow)."""
    q_abs = abs(q_kg_per_s)
    laminar = 8.0 * area_m2 * viscosity_Pa_s / diameter_m          # (8 / Re) |q|
    reynolds = max(q_abs / laminar * 8.0, 1e-3)      # Re < 1e-3: all laminar term (no overflow)
    a = (2.457 * 0.9 * math.log(reynolds / 7.0)) ** 16
    b = (37530.0 / reynolds) ** 16
    lambda_q = 8.0 * (laminar ** 12 + q_abs ** 12 * (a + b) ** -1.5) ** (1.0 / 12.0)
    drop = (lambda_q * length_m / diameter_m + zeta * q_abs) * q_kg_per_s / (2.0 * rho_kg_per_m3 * (area_m2 * area_m2))
    return area_m2 / length_m * ((p_a_Pa - p_b_Pa) - drop)


@scalar
def choked_mass_flow_kg_per_s(area_m2, p0_Pa, T0_K, R_J_per_kgK, gamma):
    """The isentropic choked mass flow through area A from stagnation state (p0, T0):
    A p0 sqrt(gamma / (R T0)) (2 / (gamma + 1))^((gamma + 1) / (2 (gamma - 1)))."""
    return area_m2 * p0_Pa * math.sqrt(gamma / (R_J_per_kgK * T0_K)) * (2.0 / (gamma + 1.0)) ** (
        (gamma + 1.0) / (2.0 * (gamma - 1.0)))


@elementwise(7)
def choked_end_flow_kg_per_s(q_kg_per_s, area_m2, p_cell_Pa, T_cell_K, outflow_sign, R_J_per_kgK, gamma):
    """The flow w an end link passes for its state q. Leaving the pipe (q outflow_sign > 0;
    outflow_sign -1 at end a, +1 at end b): q / (1 + |q / m*|^n)^(1/n), m* the choked flow of the
    end cell (n = CHOKE_SHARPNESS); entering it: q."""
    if q_kg_per_s * outflow_sign <= 0.0:
        return q_kg_per_s
    limit = choked_mass_flow_kg_per_s(area_m2, p_cell_Pa, T_cell_K, R_J_per_kgK, gamma)
    return q_kg_per_s / (1.0 + abs(q_kg_per_s / limit) ** CHOKE_SHARPNESS) ** (1.0 / CHOKE_SHARPNESS)
