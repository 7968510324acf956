"""What a rig scenario predicts for measured data, for many parameter values at once.

A time history is predicted by driving the scenario's rig circuit with the measured crushing
(a quintic spline through ``z_m``: the crushing and its rate, continuous) from rest at the
scenario's ``p0_Pa``, with the package's fixed-step RK4 at most :data:`STEP_S` (the step also
resolves the thermal rate of the largest finite k: :func:`pneumatics.integrate.stable_step_s`),
sampled at the measured times. A stiffness table is predicted on the periodic steady state at
each measured frequency (:func:`pneumatics.rig.dynamic_stiffness_sweep`, the complex stiffness of
the force's first harmonic), the frequencies shared over ``jobs`` processes.

Every k value of a call is one column of one batched circuit, so a grid of k costs about what one
k costs; the other keys (``circuit.pipe.zeta`` ...) are applied through the scenario loader, a
circuit per value.
"""
from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, Sequence, Tuple

import numpy as np
from scipy.interpolate import make_interp_spline

from cosim.errors import ScenarioError
from cosim.identify.data import Measurements, table_channels
from cosim.interrupts import ignore_in_worker
from cosim.load import load_scenario
from pneumatics.circuit import Circuit
from pneumatics.integrate import advance, stable_step_s
from pneumatics.rig import dynamic_stiffness_sweep

#: the RK4 step of a time-history prediction [s]: 0.002 s agrees with LSODA at rtol 1e-8 to
#: 0.002 N on the paper's bellow-tank rig under a 20 mm, 1 Hz sine (60 s, 50 kN force: 4e-8)
STEP_S = 0.002
#: degree of the spline through the measured crushing. Its rate drives the bellow's work p dV/dt:
#: at 20 samples per period of a sine a cubic's rate is off by ~0.1 %, which biased k by 0.06 %
#: (2 standard errors at a tenth of the example's noise; halving the RK4 step changed nothing,
#: sampling at 80 Hz removed it); a quintic's error is ~20 times smaller
SPLINE_DEGREE = 5

#: (key, value) pairs of the parameters other than k
Others = Tuple[Tuple[str, float], ...]


@dataclass
class RigModel:
    """The rig of ``scenario_file`` (with ``overrides``) predicting ``data``."""

    scenario_file: Path
    overrides: Tuple[str, ...]
    data: Measurements
    #: processes a stiffness table's frequencies are shared over (a pool kept for the model's life)
    jobs: int = 1

    def __post_init__(self):
        self._pool = None
        from cosim.kinds import KINDS
        self.base = load_scenario(self.scenario_file, list(self.overrides))
        self.kind = KINDS[self.base.kind]
        wanted = self.kind.identify
        if not wanted:
            able = ", ".join(k.name for k in KINDS.values() if k.identify)
            raise ScenarioError(self.scenario_file, ["kind"], f"identify works on rig scenarios ({able}); "
                                                              f"this one is {self.base.kind}")
        if wanted != self.data.kind:
            what = {"time": "a time history (t_s, z_m, ...)", "table": "a stiffness table (frequency_Hz, ...)"}
            raise ScenarioError(self.data.file, ["header"], f"a {self.base.kind} scenario is fitted to {what[wanted]}, "
                                                            f"this file is {what[self.data.kind]}")
        self._cache: Dict[Others, object] = {}
        comps, _ = self.components(())
        for channel in self.data.channels:
            chamber = channel.split("_")[1] if channel[0] in "pT" else None
            if chamber is not None and chamber not in comps:
                raise ScenarioError(self.data.file, [channel], f"the scenario's rig has no {chamber} (its chambers: "
                                                               f"{', '.join(n for n in comps if n != 'pipe')})")
        if self.data.kind == "time":
            self._spline = make_interp_spline(self.data.x, self.data.z_m, k=SPLINE_DEGREE)

    def close(self) -> None:
        """Shut down the processes a stiffness table's predictions ran on (none for a time history)."""
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None

    def components(self, others: Others):
        """(components, initial pressures) of the rig with ``others`` applied."""
        if others not in self._cache:
            scenario = self.base if not others else load_scenario(
                self.scenario_file, [*self.overrides, *(f"{k}={v!r}" for k, v in others)])
            comps, p0 = self.kind.identify_circuit(scenario)
            self._cache[others] = (comps, p0, scenario)
        comps, p0, _ = self._cache[others]
        return comps, p0

    def predict(self, k_W_per_K: Sequence[float], others: Others = ()) -> Dict[str, np.ndarray]:
        """channel -> predictions (cases, points), one case per k (NaN where the model has none:
        a periodic state that did not stabilise)."""
        ks = np.asarray(k_W_per_K, dtype=float)
        comps, p0 = self.components(others)
        if self.data.kind == "time":
            return self._time_history(comps, p0, ks)
        return self._table(comps, p0, ks, self._cache[others][2].test.amplitude_m)

    def _time_history(self, comps, p0, ks) -> Dict[str, np.ndarray]:
        circuit = Circuit(comps, k_W_per_K=ks)
        x = circuit.initial_state(p0, n_cases=ks.size)
        h = stable_step_s(circuit, x, STEP_S)
        z_of, zd_of = self._spline, self._spline.derivative()

        def motion(t):
            return np.full((1, ks.size), float(z_of(t))), np.full((1, ks.size), float(zd_of(t)))

        t = self.data.x
        names = circuit.chamber_names
        out = {c: np.empty((ks.size, t.size)) for c in self.data.channels}

        def sample(i, x):
            z = motion(t[i])[0]
            if "F_bellow_N" in out:
                out["F_bellow_N"][:, i] = circuit.bellow_forces_N(x, z)[0]
            p, T = circuit.chamber_states(x, z)
            for c in out:
                if c[0] in "pT":
                    out[c][:, i] = (p if c[0] == "p" else T)[names.index(c.split("_")[1])]

        sample(0, x)
        with np.errstate(all="ignore"):
            for i in range(1, t.size):
                x = advance(circuit, x, t[i - 1], t[i], motion, h)
                sample(i, x)
        return out

    def _table(self, comps, p0, ks, amplitude_m) -> Dict[str, np.ndarray]:
        f = self.data.x
        shares = [f[i::self.jobs] for i in range(min(self.jobs, f.size))]   # alternate: equal costs
        if len(shares) == 1:
            points = dynamic_stiffness_sweep(comps, ks, f, amplitude_m, p0)
        else:
            if self._pool is None:
                self._pool = ProcessPoolExecutor(len(shares), initializer=ignore_in_worker)   # Ctrl-C: the parent's
            tasks = [self._pool.submit(dynamic_stiffness_sweep, comps, ks, share, amplitude_m, p0) for share in shares]
            points = [p for task in tasks for p in task.result()]
        at = {(p.k_W_per_K, p.frequency_Hz): p for p in points}
        Ks, Kl = np.full((ks.size, f.size), np.nan), np.full((ks.size, f.size), np.nan)
        for i, k in enumerate(ks):
            for j, fj in enumerate(f):
                p = at[(float(k), float(fj))]
                if p.stabilised:
                    Ks[i, j], Kl[i, j] = p.K_storage_N_per_m, p.K_loss_N_per_m
        return table_channels(Ks, Kl, tuple(self.data.channels))
