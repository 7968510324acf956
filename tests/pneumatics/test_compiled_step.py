"""The compiled macro-step (pneumatics.compiled_step) against the present path it stands for:
:func:`pneumatics.integrate.rk4` over :meth:`CircuitRuntime.derivatives` (the fused laws, the
matrix products by numpy), on random states of the circuits the fused laws cover: four-point
with the service's valves (play, delay, lag), differential valves, a compressor and an air demand;
valves without dynamics; two-point; several valve tables and a fixed orifice; faults; isothermal
cases; one case and several; one RK4 sub-step and several; with and without RK4's given first
stage; NaN states.

Not bit for bit: the compiled step sums each matrix product (volumes, levers, incidence) over its
terms in order, numpy's BLAS in its own order with fused multiply-adds, so a lever's mean of two
crushings and what follows from it differ in the last bits. The tolerance, 1e-12 of each state
row's scale, is four orders above what they differ by here (< 1e-15 relative after a macro-step)
and far below any error of a law (a wrong term moves a row by its own size, >= 1e-6 of it)."""
from __future__ import annotations

import numpy as np
import pytest
from test_fused import CIRCUITS, random_state

from pneumatics.chamber import Bellow, Tank
from pneumatics.circuit import Circuit
from pneumatics.compiled_step import _column_sum
from pneumatics.integrate import advance, hermite_motion
from pneumatics.layouts import car_circuit
from pneumatics.pipe import Pipe
from pneumatics.valves import LevellingValve

RNG = np.random.default_rng(11)
TOLERANCE = 1e-12


def two_point():
    """The two-point circuit: one valve per bogie on its two bellows' mean height, cross pipes."""
    return car_circuit(Bellow(p0_Pa=4.6e5), Tank(p0_Pa=4.6e5), Pipe("a", "b"), points=2, cross_pipe=Pipe("a", "b"),
                       levelling=LevellingValve("FL", lag_s=0.5, delay_s=0.2, hysteresis_m=0.002))


STEP_CIRCUITS = dict(CIRCUITS, **{"two-point": (two_point, ())})


def _close(a, b, scale) -> bool:
    """a and b equal within TOLERANCE of each row's ``scale`` (NaN where the other is NaN)."""
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape or not np.array_equal(np.isnan(a), np.isnan(b)):
        return False
    bound = TOLERANCE * np.asarray(scale).reshape(-1, *([1] * (a.ndim - 1)))
    return bool(np.all(np.where(np.isnan(a), True, np.abs(a - b) <= bound)))


def _row_scale(*states) -> np.ndarray:
    """Each state row's scale: its largest magnitude over the states and cases (a floor of 1e-300)."""
    rows = [np.abs(np.nan_to_num(s.reshape(s.shape[0], -1), nan=0.0)).max(axis=1) for s in states]
    return np.maximum(np.max(rows, axis=0), 1e-300)


def _pair(name, k):
    make, faults = STEP_CIRCUITS[name]
    compiled = Circuit(make(), k_W_per_K=np.array(k), faults=faults, active_faults=range(len(faults)))
    present = Circuit(make(), k_W_per_K=np.array(k), faults=faults, active_faults=range(len(faults)))
    assert compiled.compiled_step is not None
    present.compiled_step = None             # rk4 over the fused evaluation, call by call
    return compiled, present


@pytest.mark.parametrize("name", sorted(STEP_CIRCUITS))
@pytest.mark.parametrize("k", [[0.0, 100.0], [10.0, np.inf], [0.0], [0.0, 1.0, 30.0, np.inf, 5.0]])
def test_the_compiled_macro_step_is_rk4_over_the_present_evaluation(name, k):
    compiled, present = _pair(name, k)
    with np.errstate(all="ignore"):
        for trial in range(8):
            x, z, zd = random_state(compiled, len(k), nan=trial % 4 == 3)
            z1, zd1 = z + RNG.normal(scale=1e-3, size=z.shape), zd + RNG.normal(scale=0.05, size=zd.shape)
            t0, H = 0.25, 0.005
            motion = hermite_motion(t0, t0 + H, z, zd, z1, zd1)
            h = H if trial % 2 else 1e-3                       # one sub-step, five
            rate0 = present.derivatives(x, z, zd) if trial % 3 else None
            got = advance(compiled, x, t0, t0 + H, motion, h, rate0=rate0)
            expected = advance(present, x, t0, t0 + H, motion, h, rate0=rate0)
            assert _close(got, expected, _row_scale(x, expected))
            # a part of the macro-step (a fault's switch within it): the same motion, a sub-interval
            got = advance(compiled, x, t0 + 0.002, t0 + H, motion, 1e-3)
            expected = advance(present, x, t0 + 0.002, t0 + H, motion, 1e-3)
            assert _close(got, expected, _row_scale(x, expected))
            if len(k) == 1:                                    # a 1-D state and crushing
                m1 = hermite_motion(t0, t0 + H, z[:, 0], zd[:, 0], z1[:, 0], zd1[:, 0])
                got, expected = (advance(c, x[:, 0], t0, t0 + H, m1, 1e-3) for c in (compiled, present))
                assert got.shape == x[:, :1].shape[:1] and _close(got, expected, _row_scale(x, expected))


@pytest.mark.parametrize("name", sorted(STEP_CIRCUITS))
@pytest.mark.parametrize("k", [[0.0, 100.0], [10.0, np.inf], [0.0]])
def test_the_compiled_derivatives_and_held_are_the_present_ones(name, k):
    compiled, present = _pair(name, k)
    with np.errstate(all="ignore"):
        for trial in range(8):
            x, z, zd = random_state(compiled, len(k), nan=trial % 4 == 3)
            got, expected = compiled.derivatives_and_held(x, z, zd), present.derivatives_and_held(x, z, zd)
            for a, b in zip(got, expected):
                assert _close(a, b, _row_scale(b))
            # the held rate is the rate at zero crushing rate, as the present path has it
            assert _close(got[1], present.derivatives(x, z, np.zeros_like(zd)), _row_scale(expected[1]))


def test_the_governors_switch_within_a_compiled_macro_step():
    """A reservoir just above cut-in, its compressor stopped, drawn by the demand: the governor
    switches on within the macro-step, in both paths at the same sub-step."""
    compiled, present = _pair("service", [0.0, 100.0])
    lay, i = compiled.layout, compiled._air.reservoir
    x, z, zd = random_state(compiled, 2)
    x[lay.governor] = 0.0
    cut_in = compiled._air.p_cut_in_Pa[0, 0]
    x[lay.m][i] = (cut_in + 1.0) * compiled._chambers.V0_m3[i] / (compiled.gas.R_J_per_kgK * x[lay.T][i])
    motion = hermite_motion(0.0, 0.05, z, zd, z, zd)
    got, expected = (advance(c, x, 0.0, 0.05, motion, 1e-3) for c in (compiled, present))
    assert np.all(expected[lay.governor] == 1.0) and np.array_equal(got[lay.governor], expected[lay.governor])
    assert _close(got, expected, _row_scale(x, expected))


def test_other_motions_and_circuits_keep_the_present_path():
    """A motion that is not a Hermite one, and the circuits the fused laws do not cover, are
    advanced by rk4 over derivatives (bit for bit what they were)."""
    compiled, present = _pair("service", [0.0, 100.0])
    x, z, zd = random_state(compiled, 2)
    motion = (lambda t: (z, zd))
    assert np.array_equal(advance(compiled, x, 0.0, 0.005, motion, 1e-3), advance(present, x, 0.0, 0.005, motion, 1e-3))
    comps = {"FL": Bellow(p0_Pa=4.6e5), "tank": Tank(p0_Pa=4.6e5), "pipe": Pipe("FL", "tank", model="quasi_steady")}
    assert Circuit(comps).compiled_step is None


@pytest.mark.parametrize("n", [1, 2, 5])
def test_the_column_sums_are_numpys(n):
    """_column_sum (the heat and work rows) as np.add.reduce(a, axis=0) orders it, bit for bit:
    one column pairwise from +0, several row by row; signed zeros included."""
    for rows in list(range(1, 40)) + [64, 127, 128]:
        a = RNG.normal(size=(rows, n)) * 10.0 ** RNG.uniform(-6, 6, (rows, n))
        a[RNG.random(a.shape) < 0.2] = -0.0
        assert _column_sum(a).tobytes() == np.add.reduce(a, axis=0).tobytes()   # the Python law numba compiles
        a[:] = -0.0
        assert _column_sum(a).tobytes() == np.add.reduce(a, axis=0).tobytes()
