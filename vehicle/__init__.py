"""Vehicle side of pneumorail: exudyn model of the metro car and its parameters.

* :mod:`vehicle.params` -- :class:`~vehicle.params.VehicleParams` (SI, documented defaults);
* :mod:`vehicle.car` -- :class:`~vehicle.car.MetroCar`, the multibody model the co-simulation
  master drives macro-step by macro-step;
* :mod:`vehicle.suspension` -- force laws of the secondary components (anti-roll bar, Maxwell
  dampers with blow-off, emergency spring and bumpstops), pure functions on floats or exudyn
  symbolic expressions;
* :mod:`vehicle.wheelrail` -- wheel/rail profiles, contact geometry, creep forces, a free
  wheelset on track, and the contact forces of the car's wheelsets (``guidance="contact"``);
* :mod:`vehicle.track` -- track centre-line geometry (curve entry);
* :mod:`vehicle.guidance` -- :class:`~vehicle.guidance.TrackSampler`, the tabulated track the
  running car evaluates every time step.

This package must not import ``pneumatics`` or ``cosim``.
"""
