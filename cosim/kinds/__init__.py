"""The scenario kinds: each a :class:`~cosim.kinds.base.Kind` subclass (its experiment, how it
is checked and run, what it draws, its metrics and what ``compare`` overlays), an instance of which
:data:`KINDS` holds.

* :mod:`cosim.kinds.rig`: the bellow-tank test rig (paper §3): ``rig_ramp``, ``rig_sine``,
  ``rig_stiffness``, ``rig_table2``;
* :mod:`cosim.kinds.twist`: the EN 14363 twist test (paper §4.1): ``twist``;
* :mod:`cosim.kinds.curve_entry`: a run into a curve (paper §4.2): ``curve_entry``;
* :mod:`cosim.kinds.ride`: ride comfort on irregular track at a list of speeds: ``ride``;
* :mod:`cosim.kinds.stability`: linear running stability (eigenvalues, critical speed): ``stability``;
* :mod:`cosim.kinds.station_stop`: passengers boarding at a platform, the floor re-levelled: ``station_stop``;
* :mod:`cosim.kinds.service`: a line in service, stations, passengers and curves: ``service``;

The kinds compose the runs of :mod:`cosim.runs` (what every car run shares: wheel unloading, air
accounts, faults; the run of the car along a track: its spec, simulation, summary row and figures
along the track) on the engine (:mod:`cosim.engine.cases`); the EN 14363 assessment of a run on
track and the comfort columns of a car run are criteria, in :mod:`cosim.limits.en14363` and
:mod:`cosim.limits.ride_comfort`.

A new kind is a subclass of :class:`~cosim.kinds.base.CarKind` (or ``RigKind``) that implements
``run`` (and what its section needs: ``parse``, ``duration_s``, ``make_car``), and its instance in
:data:`KINDS` below.
"""
from __future__ import annotations

from typing import Callable, Dict

from cosim.kinds import curve_entry, ride, rig, service, stability, station_stop, twist
from cosim.kinds.base import Kind

#: kind name (``kind:`` in a scenario) -> its declaration
KINDS: Dict[str, Kind] = {k.name: k for k in (*rig.KINDS, twist.KIND, curve_entry.KIND, ride.KIND, stability.KIND,
                                              station_stop.KIND, service.KIND)}


def overlays() -> Dict[str, Callable]:
    """kind name -> its ``compare`` (the kinds that have one): what ``pneumorail compare`` draws."""
    return {name: kind.compare for name, kind in KINDS.items() if kind.compares}


__all__ = ["KINDS", "Kind", "overlays"]
