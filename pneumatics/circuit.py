"""Assemble components into one pneumatic circuit: a state vector and its time derivative.

A circuit is described declaratively as a mapping ``name -> component`` (the dataclasses of
:mod:`pneumatics.chamber`, :mod:`pneumatics.boundary`, :mod:`pneumatics.pipe`,
:mod:`pneumatics.orifice`, :mod:`pneumatics.valves`). Chambers (bellows, tanks, finite
reservoirs) are the nodes that hold air; the atmosphere and fixed-pressure supplies are boundary
nodes; pipes, orifices and valves are links that carry a signed mass flow between two nodes.

State vector (one column per independent case when batched; see :class:`StateLayout`):

=================  =========================================================
``m``              air mass in each chamber [kg] (eq. 1)
``T``              temperature of each chamber [K] (eq. 2)
``q``              mass flow in each dynamic pipe, a -> b [kg/s] (eq. 5)
``mass_through``   cumulative mass through each link, a -> b [kg]
``heat_in``        cumulative heat into all chambers from the atmosphere [J] (eq. 8)
``work_in``        cumulative work done on the gas by the bellows, -int p dV [J]
``enthalpy_in``    cumulative enthalpy brought in from boundary nodes [J]
``open_time``      cumulative time each levelling/safety valve side has been open
                   (conductance > 0) [s]: supply sides, then exhaust sides, in the
                   order of :attr:`Circuit.valve_names` (2 per valve; absent without valves)
``valve_signal``   states of the valves' response dynamics [m] (absent unless a valve sets
                   ``hysteresis_m``, ``delay_s`` or ``lag_s``): the play outputs u_p of
                   the valves with a play, then the delay-chain stages of the valves with a
                   delay (valve by valve, input side first), then the lagged lever u_f of
                   the valves with a lag; each group in the order of ``valve_names``
``governor``       each compressor's governor, 1.0 running, 0.0 stopped (a discrete
                   state: :meth:`Circuit.update_governors` switches it between steps;
                   absent without compressors)
``run_time``       each compressor's cumulative running time [s]
``compression_work``  each compressor's cumulative energy of compression [J]: isothermal
                   bounds, then adiabatic bounds
=================  =========================================================

The groups up to ``enthalpy_in`` sit where they always did: the valve groups are appended, so a
circuit without valves has exactly its former layout, and one with default (instantaneous)
valves only gains the open-time accumulators at the end (its other derivatives are unchanged
bit for bit). The mass through each side of a valve is ``mass_through`` of the links
``<valve>.supply`` (supply -> bellow) and ``<valve>.exhaust`` (bellow -> exhaust); see
:meth:`Circuit.valve_air_kg` and :meth:`Circuit.valve_open_time_s`. The valve-signal states are
physical states but lie outside the ``n_dynamic`` prefix (the periodic solver, run on rig
circuits without valves, resets everything after that prefix to 0: valves at rest at z = 0).

The circuit is compiled once (:mod:`pneumatics.assembly`: nodes, links from the table of link
types, faults, valve dynamics, this layout) and evaluated at a state by
:class:`pneumatics.runtime.CircuitRuntime` (derivatives, outputs, forces, checks), which
:class:`Circuit` is, built from its components.

Inputs: the crushing z [m] (positive in compression) and its rate of every bellow, in the order
of :attr:`Circuit.bellow_names`; the rate must be the derivative of z (it drives the bellow's
work p dV and the valves' play). Every array may carry a trailing "case" axis so that many
cases (e.g. several k values or frequencies) are integrated as one vectorised system.
"""
from __future__ import annotations

from typing import Mapping, Optional, Sequence

from .air_supply import AirDemand
from .assembly import assemble
from .assembly.components import ATMOSPHERE, COMPONENT_TYPES
from .assembly.layout import StateLayout
from .assembly.link_types import PIPE_MODELS
from .boundary import Atmosphere
from .errors import CircuitDiverged, CircuitError
from .faults import Fault
from .gas import AIR, Gas
from .runtime import CircuitOutputs, CircuitRuntime, Evaluation, ValveSides

__all__ = ["ATMOSPHERE", "COMPONENT_TYPES", "PIPE_MODELS", "Circuit", "CircuitDiverged", "CircuitError", "CircuitOutputs",
           "Evaluation", "StateLayout", "ValveSides"]


class Circuit(CircuitRuntime):
    """A compiled pneumatic circuit.

    ``k_W_per_K`` is the heat-transfer coefficient of every chamber (eq. 8): 0 is adiabatic,
    ``inf`` the exact isothermal limit (T held at the atmosphere's temperature, the heat flow
    being whatever that takes). An array of k values, one per case, batches cases.

    ``faults`` (:mod:`pneumatics.faults`) are compiled from the start, so that the state vector
    is the same whether they have happened or not; those in ``active_faults`` (their indices)
    have happened. :meth:`with_active_faults` gives the same circuit with other faults active.
    Each opening a fault makes to the atmosphere is a link of its own (``<component>.<kind>``,
    a ruptured pipe's ``<pipe>.ruptured@<end node>``), shut while the fault is inactive.
    """

    def __init__(self, components: Mapping[str, object], *, gas: Gas = AIR,
                 atmosphere: Atmosphere = Atmosphere(), k_W_per_K=0.0, faults: Sequence[Fault] = (),
                 active_faults: Sequence[int] = ()):
        self._given_components = dict(components)
        super().__init__(assemble(self._given_components, gas=gas, atmosphere=atmosphere, k_W_per_K=k_W_per_K,
                                  faults=faults, active_faults=active_faults))

    def with_active_faults(self, active: Sequence[int]) -> "Circuit":
        """The same circuit (same components, faults and state layout) with the faults of
        indices ``active`` having happened."""
        return self._variant(self._given_components, active)

    def _variant(self, components: Mapping, active: Sequence[int]) -> "Circuit":
        """This circuit (gas, atmosphere, k, faults) built of ``components`` with the faults of
        indices ``active`` having happened."""
        return Circuit(components, gas=self.gas, atmosphere=self.atmosphere, k_W_per_K=self.k_W_per_K,
                       faults=self.faults, active_faults=active)

    def with_demands(self, demands: Mapping[str, AirDemand], active: Optional[Sequence[int]] = None) -> "Circuit":
        """The same circuit (same components, faults, active faults and state layout) with each air
        demand named in ``demands`` drawing as the demand given there (from the same node): a
        scheduled demand's rate switched (:class:`~pneumatics.air_supply.ScheduledDemand`); with
        ``active``, the faults of those indices having happened instead of this circuit's."""
        for name, demand in demands.items():
            given = self._given_components.get(name)
            if not isinstance(given, AirDemand) or not isinstance(demand, AirDemand) or demand.node != given.node:
                raise CircuitError([name], "only an air demand of the circuit can be switched, to another rate from "
                                           "the same node")
        return self._variant({**self._given_components, **demands}, self.active_faults if active is None else active)
