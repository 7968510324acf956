"""FMI: a car scenario's air circuit as an FMI 2.0 co-simulation FMU (:mod:`cosim.fmi.export`;
the slave it packs, :mod:`cosim.fmi.slave`). Needs the ``fmi`` extra (pythonfmu)."""
