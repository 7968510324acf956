"""Running stability: the car and its air circuit linearised together about steady running on
straight track, their eigenvalues and modes (:mod:`.coupled`), and the speed at which the least
damped mode loses its damping (:mod:`.critical`)."""
from cosim.stability.coupled import CoupledModel, Mode, couple, modes
from cosim.stability.critical import SpeedScan, critical_speed, scan_speeds

__all__ = ["CoupledModel", "Mode", "couple", "modes", "SpeedScan", "critical_speed", "scan_speeds"]
