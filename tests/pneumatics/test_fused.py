"""The fused evaluation of a circuit (pneumatics.fused) against the numpy one it stands for, bit
for bit: d(state)/dt, the held rate, the evaluation and the outputs, over random states (masses,
temperatures, pipe flows, valve signals, governors, crushing and its rate, NaN included) of the
circuits it covers: the service's (levelling valves with play, delay and lag, differential valves,
a compressor and an air demand), valves without dynamics, several valve tables, fixed orifices,
faults (a stuck valve, a blocked pipe, a lost supply, a burst), isothermal cases, one case and
several. Bit for bit, not to a tolerance: it calls the same laws in the same order."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pneumatics.air_supply import AirDemand, Compressor
from pneumatics.boundary import Supply
from pneumatics.chamber import Bellow, Tank
from pneumatics.circuit import Circuit
from pneumatics.faults import Fault
from pneumatics.fused import _clip01, fused_laws
from pneumatics.layouts import car_circuit
from pneumatics.orifice import Orifice
from pneumatics.pipe import Pipe
from pneumatics.valves import DifferentialPressureValve, LevellingValve

RNG = np.random.default_rng(7)
VALVE = LevellingValve("FL", lag_s=1.0, delay_s=1.0, hysteresis_m=0.002)


def service_like(**valve):
    """The four-point car circuit with the service's valves, a finite main reservoir, a
    compressor and an air demand."""
    comps = car_circuit(Bellow(p0_Pa=4.6e5), Tank(p0_Pa=4.6e5), Pipe("a", "b"), levelling=dataclasses.replace(VALVE, **valve),
                        differential=DifferentialPressureValve("a", "b"), supply=Supply(p_Pa=9.0e5, V_m3=0.2))
    comps["compressor"] = Compressor()
    comps["air_demand"] = AirDemand(normal_flow_m3_per_s=1.667e-3)
    return comps


def other_tables():
    """Valves of two different tables (two groups each side), a fixed orifice, a fixed supply."""
    comps = car_circuit(Bellow(p0_Pa=4.6e5), Tank(p0_Pa=4.6e5), Pipe("a", "b"),
                        levelling=LevellingValve("FL", hysteresis_m=0.003))
    comps["lv_RL"] = dataclasses.replace(comps["lv_RL"], supply_lever_m=(0.0, 0.004, 0.02),
                                         supply_C_m3_per_sPa=(0.0, 0.0, 3e-8))
    comps["leak"] = Orifice("FR", "atmosphere", 1e-10)
    return comps


CIRCUITS = {
    "service": (service_like, ()),
    "no dynamics": (lambda: service_like(lag_s=0.0, delay_s=0.0, hysteresis_m=0.0), ()),
    "tables, orifice": (other_tables, ()),
    "faults": (service_like, (Fault("stuck_open", "lv_FL", side="supply"), Fault("blocked", "pipe_RR"),
                              Fault("burst", "FR", area_m2=1e-5), Fault("stuck_at", "lv_RL", lever_m=-0.01))),
    "supply lost": (service_like, (Fault("supply_lost", "supply"),)),
}


def _same(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.tobytes() == b.tobytes()


def random_state(circuit, n, nan=False):
    """A state near the circuit's initial one, scattered, with random flows and valve signals."""
    lay = circuit.layout
    x = circuit.initial_state(n_cases=n) if circuit.k_W_per_K.ndim else np.repeat(circuit.initial_state()[:, None], n, 1)
    x = x * RNG.uniform(0.7, 1.3, x.shape)
    x[lay.q] = RNG.normal(scale=0.01, size=x[lay.q].shape)
    x[lay.valve_signal] = RNG.normal(scale=0.01, size=x[lay.valve_signal].shape)
    x[lay.governor] = RNG.integers(0, 2, x[lay.governor].shape)
    z, zd = RNG.normal(scale=0.02, size=(4, n)), RNG.normal(scale=0.05, size=(4, n))
    zd[:, 0] = 0.0
    if nan:
        x[RNG.integers(lay.size), n - 1] = np.nan
    return x, z, zd


@pytest.mark.parametrize("name", sorted(CIRCUITS))
@pytest.mark.parametrize("k", [[0.0, 100.0], [10.0, np.inf], [np.inf], [0.0], [0.0, 1.0, 30.0, np.inf, 5.0]])
def test_the_fused_evaluation_is_the_numpy_one_bit_for_bit(name, k):
    make, faults = CIRCUITS[name]
    fused = Circuit(make(), k_W_per_K=np.array(k), faults=faults, active_faults=range(len(faults)))
    plain = Circuit(make(), k_W_per_K=np.array(k), faults=faults, active_faults=range(len(faults)))
    assert fused._fused is not None
    plain._fused = None                      # the numpy evaluation
    fused.compiled_step = plain.compiled_step = None   # the fused one call by call (test_compiled_step.py: the step)
    with np.errstate(all="ignore"):
        for trial in range(12):
            x, z, zd = random_state(fused, len(k), nan=trial % 4 == 3)
            assert _same(fused.derivatives(x, z, zd), plain.derivatives(x, z, zd))
            for a, b in zip(fused.derivatives_and_held(x, z, zd), plain.derivatives_and_held(x, z, zd)):
                assert _same(a, b)
            ev_f, ev_p = fused.evaluate(x, z), plain.evaluate(x, z)
            assert all(_same(a, b) for a, b in zip(ev_f[:8] + ev_f[9:], ev_p[:8] + ev_p[9:]))
            for a, b in zip(fused.derivatives_and_held(x, z, zd, ev_f), plain.derivatives_and_held(x, z, zd, ev_p)):
                assert _same(a, b)
            out_f, out_p = fused.outputs(x, z, ev_f), plain.outputs(x, z, ev_p)
            assert all(_same(getattr(out_f, f.name), getattr(out_p, f.name)) for f in dataclasses.fields(out_f))
            if len(k) == 1:                  # a 1-D state
                assert _same(fused.derivatives(x[:, 0], z[:, 0], zd[:, 0]), plain.derivatives(x[:, 0], z[:, 0], zd[:, 0]))


def test_the_fused_clip_is_numpys():
    values = np.array([-0.0, 0.0, 1.0, np.nan, np.inf, -np.inf, 0.5, -1e-300, 2.0, 1.0 + 1e-16, 5e-324])
    expected = np.clip(values, 0.0, 1.0)
    got = np.array([_clip01(v) for v in values])                    # the Python law numba compiles
    assert _same(got, expected)


def test_circuits_the_fused_evaluation_does_not_cover_keep_the_numpy_one():
    for model in ("compressible", "quasi_steady"):
        comps = {"FL": Bellow(p0_Pa=4.6e5), "tank": Tank(p0_Pa=4.6e5), "pipe": Pipe("FL", "tank", model=model)}
        assert fused_laws(Circuit(comps)) is None


@pytest.mark.parametrize("n", [1, 2, 5])
def test_the_compiled_governors_switch_as_the_numpy_ones(n):
    """update_governors (compiled: pneumatics.fused.governors) against _governors and
    np.array_equal: reservoirs around cut-in and cut-out, governors either way, NaN states."""
    circuit = Circuit(service_like(), k_W_per_K=np.zeros(n))
    lay, i = circuit.layout, circuit._air.reservoir
    cut_in, cut_out = circuit._air.p_cut_in_Pa, circuit._air.p_cut_out_Pa
    for trial in range(200):
        x, _, _ = random_state(circuit, n, nan=trial % 9 == 8)
        p = RNG.choice([cut_in[0, 0], cut_out[0, 0], 0.5 * (cut_in[0, 0] + cut_out[0, 0]), 7e5, 1.1e6], size=n)
        x[lay.m][i] = p * circuit._chambers.V0_m3[i] / (circuit.gas.R_J_per_kgK * x[lay.T][i])
        new = circuit._governors(x, x[lay.governor])
        expected = x if np.array_equal(new, x[lay.governor]) else np.concatenate([x[:lay.governor.start], new,
                                                                                 x[lay.governor.stop:]])
        got = circuit.update_governors(x)
        assert _same(got, expected) and (got is x) == (expected is x)


@pytest.mark.parametrize("k", [[0.0, 100.0], [10.0, np.inf], [np.inf], [0.0, 1.0, 30.0, np.inf, 5.0]])
@pytest.mark.parametrize("bellow", [Bellow(p0_Pa=4.6e5), Bellow(p0_Pa=4.6e5, dA_dz_m=0.05),
                                    Bellow(p0_Pa=4.6e5, area_table_z_m=(-0.05, 0.0, 0.05),
                                           area_table_m2=(0.1, 0.11, 0.115))])
def test_the_compiled_bellow_force_laws_are_the_numpy_ones(k, bellow):
    """Circuit.bellow_force_laws (pneumatics.fused.FusedBellows; the numpy calls themselves with
    area tables) against bellow_forces_N at x and at x + dt rate and bellow_stiffness_N_per_m."""
    comps = car_circuit(bellow, Tank(p0_Pa=4.6e5), Pipe("a", "b"), levelling=VALVE)
    circuit = Circuit(comps, k_W_per_K=np.array(k))
    assert (circuit._fused_bellows is None) == bool(bellow.area_table_z_m)
    with np.errstate(all="ignore"):
        for trial in range(30):
            x, z, zd = random_state(circuit, len(k), nan=trial % 7 == 6)
            rate = RNG.normal(scale=1e3, size=x.shape) * np.abs(x)
            expected = (circuit.bellow_forces_N(x, z), circuit.bellow_forces_N(x + 0.0025 * rate, z),
                        circuit.bellow_stiffness_N_per_m(x, z))
            assert all(_same(a, b) for a, b in zip(circuit.bellow_force_laws(x, z, rate, 0.0025), expected))
