"""The engine room: the co-simulation master (:mod:`cosim.engine.master`: the macro-step exchange
of bellow crushing and forces between the cars and their circuit, and every output a car run
samples) and the running of a car scenario's cases on a pool of processes
(:mod:`cosim.engine.cases`). The kinds ask it for their cases; nothing here knows a kind."""
