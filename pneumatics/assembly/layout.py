"""Where each group of states sits in the circuit's state vector (the table of
:mod:`pneumatics.circuit`'s docstring)."""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property


@dataclass(frozen=True)
class StateLayout:
    """Where each group of states sits in the state vector (order: see :mod:`pneumatics.circuit`).
    Each group is computed once, on first use (a plain attribute after that)."""

    n_chambers: int
    n_pipes: int
    n_links: int
    n_valves: int = 0
    n_valve_states: int = 0
    n_compressors: int = 0

    @cached_property
    def m(self) -> slice:
        return slice(0, self.n_chambers)

    @cached_property
    def T(self) -> slice:
        return slice(self.n_chambers, 2 * self.n_chambers)

    @cached_property
    def q(self) -> slice:
        start = 2 * self.n_chambers
        return slice(start, start + self.n_pipes)

    @cached_property
    def mass_through(self) -> slice:
        start = 2 * self.n_chambers + self.n_pipes
        return slice(start, start + self.n_links)

    @cached_property
    def heat_in(self) -> int:
        return 2 * self.n_chambers + self.n_pipes + self.n_links

    @cached_property
    def work_in(self) -> int:
        return self.heat_in + 1

    @cached_property
    def enthalpy_in(self) -> int:
        return self.heat_in + 2

    @cached_property
    def open_time(self) -> slice:
        """Open time of each valve side: supply sides of all valves, then exhaust sides."""
        start = self.heat_in + 3
        return slice(start, start + 2 * self.n_valves)

    @cached_property
    def valve_signal(self) -> slice:
        start = self.heat_in + 3 + 2 * self.n_valves
        return slice(start, start + self.n_valve_states)

    @cached_property
    def governor(self) -> slice:
        """Each compressor's governor: 1.0 running, 0.0 stopped (switched between steps)."""
        start = self.valve_signal.stop
        return slice(start, start + self.n_compressors)

    @cached_property
    def run_time(self) -> slice:
        """Each compressor's cumulative running time [s]."""
        start = self.governor.stop
        return slice(start, start + self.n_compressors)

    @cached_property
    def compression_work(self) -> slice:
        """Each compressor's cumulative energy of compression [J], its isothermal bound, then each
        one's adiabatic bound (:func:`pneumatics.air_supply.compression_work_J_per_kg`)."""
        start = self.run_time.stop
        return slice(start, start + 2 * self.n_compressors)

    @cached_property
    def size(self) -> int:
        return self.heat_in + 3 + 2 * self.n_valves + self.n_valve_states + 4 * self.n_compressors

    @cached_property
    def n_dynamic(self) -> int:
        """The prefix of states that describe the physical condition (m, T, q); the accumulators
        follow, then the valve-signal states (physical too, but outside this prefix so that the
        former layout is kept; see the module docstring)."""
        return 2 * self.n_chambers + self.n_pipes
