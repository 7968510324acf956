"""Wheel-rail contact physics, pure numpy/scipy (no exudyn, no pneumatics/cosim imports) except
the exudyn wheelset model :mod:`vehicle.wheelrail.wheelset`, which this package does not import;
numba compiles the car's contact kernels when they are first called.

* :mod:`vehicle.wheelrail.profiles` -- SIMPACK ``.prw``/``.prr`` and 2-column profile readers;
* :mod:`vehicle.wheelrail.geometry` -- rigid contact search, :class:`ContactTable`
  (``from_profiles``, ``from_csv``, ``default``, ``at(y)``), equivalent conicity;
* :mod:`vehicle.wheelrail.creep` -- Kalker linear theory (Table E.3), Hertz ellipse,
  Shen-Hedrick-Elkins saturation, wheelset creepages;
* :mod:`vehicle.wheelrail.contact_law` -- the contact force law of a wheelset on track (Hertz
  normal force, creepages, saturated creep forces, generalized forces), pure functions usable
  with floats, arrays or exudyn symbolic expressions;
* :mod:`vehicle.wheelrail.wheelset` -- a free wheelset on track in exudyn with that law (imports
  exudyn, hence not imported here);
* :mod:`vehicle.wheelrail.track_contact` -- that law on the wheelsets of a multibody vehicle in
  global coordinates, each with its own track frame and rails (the car's contact guidance;
  pure math, the exudyn wrapping is in ``vehicle/car/``), run as compiled kernels;
* :mod:`vehicle.wheelrail.compiled`, :mod:`vehicle.wheelrail.kernel_ops` -- compiling the law
  with numba (one source; cached on disk);
* ``python -m vehicle.wheelrail.derive_table [--nominal-radius-m R]`` rewrites the shipped tables.

See ``docs/wheel_rail.md``.
"""

from .contact_law import ContactLawTable, WheelsetParams, WheelsetState
from .creep import creep_forces, creepages, hertz_semi_axes, kalker_coefficients, kalker_linear, shen_hedrick_elkins
from .geometry import ContactGeometry, ContactState, ContactTable, PairSetup, default_setup
from .profiles import Profile, read_profile, read_simpack_profile, write_simpack_profile

__all__ = [
    "ContactGeometry", "ContactState", "ContactTable", "PairSetup", "default_setup",
    "ContactLawTable", "WheelsetParams", "WheelsetState",
    "Profile", "read_profile", "read_simpack_profile", "write_simpack_profile",
    "creep_forces", "creepages", "hertz_semi_axes", "kalker_coefficients", "kalker_linear",
    "shen_hedrick_elkins",
]
