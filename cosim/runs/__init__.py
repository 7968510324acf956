"""The runs the kinds compose: what every co-simulated car run shares (:mod:`cosim.runs.car`:
wheel unloading, air accounts, fault columns and figures) and the run of the car along a track
(:mod:`cosim.runs.track_spec`, :mod:`cosim.runs.track_run`, :mod:`cosim.runs.along_track`)."""
