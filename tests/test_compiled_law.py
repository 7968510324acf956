"""The compiled contact kernels (vehicle/wheelrail/compiled.py) against the same law run by
Python.

The kernels compile the law's own functions (one source), so they must agree with the Python
evaluation to rounding. The Python side is evaluated independently of the kernels: per wheelset
with ``SCALAR`` ops (Python's math), and the Jacobian by central differences instead of the
kernel's forward differences.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys

import numpy as np
import pytest

from vehicle.wheelrail import compiled
from vehicle.wheelrail.contact_law import SCALAR, ContactLawTable, WheelsetParams
from vehicle.wheelrail.geometry import ContactTable
from vehicle.wheelrail.track_contact import WheelsetTrackContact, _wheelset

R0 = 0.46
V = 10.0


@pytest.fixture(scope="module")
def contact():
    p = WheelsetParams()
    law = ContactLawTable(ContactTable.default(), p)
    ref = np.array([[x, 0.0, R0] for x in (0.0, 1.9, 10.0, 11.9)])
    return WheelsetTrackContact(law, p, ref, R0, V)


def states(wr, rng, count):
    """``count`` random (frames, rails, q, q_t) around rolling on a curve: every wheelset at a
    lateral position across the whole table (tread, flange root, flank), in contact (pressed
    20-60 um into the rails), yawed, rolled, with rates, on a canted curve with rail offsets."""
    z0 = wr.static_rise_m(30e3)
    lo, hi = wr.table.y_range_m
    for _ in range(count):
        frames = [(x, 0.01 * rng.standard_normal(), 0.02 * rng.standard_normal(),
                   0.1 * rng.random(), 0.01 * rng.standard_normal(), 0.001 * rng.random())
                  for x in wr._ref_arr[:, 0]]
        rails = [[(1e-3 * rng.standard_normal(), 1e-2 * rng.standard_normal(),
                   1e-3 * rng.standard_normal(), 1e-2 * rng.standard_normal())
                  for _ in range(2)] for _ in range(4)]
        wr.set_track(frames, rails)
        q = np.zeros(28)
        qt = np.zeros(28)
        for i, fr in enumerate(wr._frames):
            y = rng.uniform(0.8 * lo, 0.8 * hi)
            # place the centre at lateral y, height z0 - (20..60 um) in the track frame
            target = (np.array([fr.ox, fr.oy, fr.oz]) + y * np.array(fr.l)
                      + (R0 + z0 - rng.uniform(2e-5, 6e-5)) * np.array(fr.n))
            q[7 * i:7 * i + 3] = target - wr._ref_arr[i]
            q[7 * i + 3] = -math.atan2(fr.l[2], fr.n[2]) + 1e-3 * rng.standard_normal()  # roll
            q[7 * i + 5] = math.atan2(fr.t[1], fr.t[0]) + 5e-3 * rng.standard_normal()  # yaw
            qt[7 * i:7 * i + 6] = [V * fr.t[0], V * fr.t[1], 0.0, 0.0, 0.0, 0.0]
            qt[7 * i:7 * i + 6] += np.r_[1e-2 * rng.standard_normal(3),
                                         1e-2 * rng.standard_normal(3)]
            qt[7 * i + 6] = V / R0 * (1.0 + 1e-3 * rng.standard_normal())
        yield q, qt


def python_forces(wr, q, qt):
    """The law per wheelset with Python's math (SCALAR ops), no kernel."""
    out = []
    for i, fr in enumerate(wr._frames):
        Q = _wheelset(SCALAR, wr._table, wr._setup, wr._ref[i], fr, q[7 * i:7 * i + 7].tolist(),
                      qt[7 * i:7 * i + 7].tolist())[0]
        out += [float(v) for v in Q]
    return np.array(out)


def test_kernels_compile_here():
    """The speed of contact guidance rests on the kernels compiling (numba is a dependency)."""
    assert compiled.numba_available()


def test_compiled_forces_are_the_python_law(contact):
    """Same operations in the same order: equal to rounding. Tolerance: 1e-12 of each
    wheelset's largest generalized force (the normal forces, ~30 kN); compiled and Python
    transcendental functions may differ in the last bit, which the law amplifies by no more
    than a few hundred (the Hertz power 1.5 of a 20-60 um overlap)."""
    rng = np.random.default_rng(11)
    n_flange = 0
    for q, qt in states(contact, rng, 60):
        got = contact.forces(q, qt)
        ref = python_forces(contact, q, qt)
        assert np.all(np.isfinite(got))
        scale = np.abs(ref.reshape(4, 7)).max(axis=1).repeat(7)
        np.testing.assert_array_less(np.abs(got - ref), 1e-12 * scale)
        n_flange += int(np.sum(contact.outputs(q, qt).gamma_rad > 0.7))
    assert n_flange > 20  # the states include flange contact


def test_compiled_outputs_are_the_python_law(contact):
    rng = np.random.default_rng(12)
    for q, qt in states(contact, rng, 20):
        out = contact.outputs(q, qt)
        for i, fr in enumerate(contact._frames):
            _, wheels, (ry, yaw) = _wheelset(SCALAR, contact._table, contact._setup,
                                             contact._ref[i], fr, q[7 * i:7 * i + 7].tolist(),
                                             qt[7 * i:7 * i + 7].tolist())
            assert out.lateral_m[i] == pytest.approx(ry, rel=1e-13, abs=1e-15)
            assert out.yaw_rad[i] == pytest.approx(yaw, rel=1e-12, abs=1e-15)
            for side, (wc, F) in enumerate(wheels):
                k = 2 * i + side
                assert out.normal_N[k] == pytest.approx(wc.N, rel=1e-12, abs=1e-9)
                np.testing.assert_allclose(out.force_track_N[k], F, rtol=1e-12, atol=1e-7)
                assert out.gamma_rad[k] == pytest.approx(math.atan2(wc.sin_gamma,
                                                                    wc.cos_gamma), rel=1e-14)
                assert out.saturation[k] == pytest.approx(wc.eps, rel=1e-12)
                np.testing.assert_allclose(out.creepage[k], (wc.xi_x, wc.xi_y, wc.phi),
                                           rtol=1e-11, atol=1e-14)


def test_compiled_jacobian_is_the_derivative_of_the_python_law(contact):
    """The kernel's forward differences (steps 1e-8 m, 1e-6 m/s) against central differences
    of the Python law (steps 1e-7 m, 1e-5 m/s). Tolerance 2e-3 of each row's largest entry:
    forward differences err by h/2 times the second derivative, which at the Hertz contact
    (N ~ overlap^1.5 at 20 um) is ~h / (4 * 20 um) ~ 1e-4 relative, the central ones by less;
    a wrong sign, factor or column is off by order 1."""
    rng = np.random.default_rng(13)
    fq, fqt = 0.7, 0.3
    for q, qt in states(contact, rng, 6):
        J = contact.jacobian(q, qt, fq, fqt)
        ref = np.zeros_like(J)
        for col in range(28):
            for which, h, fac in ((0, 1e-7, fq), (1, 1e-5, fqt)):
                if which == 0 and col % 7 == 6:
                    continue  # the spin angle does not enter
                dp, dm = [q.copy(), qt.copy()], [q.copy(), qt.copy()]
                dp[which][col] += h
                dm[which][col] -= h
                ref[:, col] -= fac * (python_forces(contact, *dp)
                                      - python_forces(contact, *dm)) / (2 * h)
        scale = np.abs(ref).max(axis=1, keepdims=True)
        worst = float(np.max(np.abs(J - ref) / (scale + 1e-6)))
        assert worst < 2e-3, worst


def test_kernels_give_the_same_forces_without_numba(contact):
    """NUMBA_DISABLE_JIT=1 runs the kernels as Python (the fallback where numba is missing)."""
    rng = np.random.default_rng(14)
    q, qt = next(states(contact, rng, 1))
    frames = [list(map(float, f)) for f in contact._frame_rows]
    code = (
        "import sys, json, numpy as np\n"
        "from vehicle.wheelrail import compiled\n"
        "from vehicle.wheelrail.contact_law import ContactLawTable, WheelsetParams\n"
        "from vehicle.wheelrail.geometry import ContactTable\n"
        "from vehicle.wheelrail.track_contact import WheelsetTrackContact\n"
        "assert not compiled.numba_available()\n"
        "d = json.load(sys.stdin)\n"
        "p = WheelsetParams()\n"
        f"wr = WheelsetTrackContact(ContactLawTable(ContactTable.default(), p), p, "
        f"np.array(d['ref']), {R0}, {V})\n"
        "wr._frame_rows = np.array(d['frames'])\n"
        "print(json.dumps(wr.forces(np.array(d['q']), np.array(d['qt'])).tolist()))\n")
    import json
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         input=json.dumps({"ref": contact._ref_arr.tolist(), "frames": frames,
                                           "q": q.tolist(), "qt": qt.tolist()}))
    assert res.returncode == 0, res.stderr
    got = np.array(json.loads(res.stdout))
    ref = contact.forces(q, qt)
    scale = np.abs(ref.reshape(4, 7)).max(axis=1).repeat(7)
    np.testing.assert_array_less(np.abs(got - ref), 1e-12 * scale)


def test_a_changed_dependency_names_a_new_cache_entry(tmp_path):
    """numba re-validates a cached kernel against its own file only; the kernel's name carries
    a digest of every file it depends on, so editing the law cannot leave a stale kernel."""
    dep = tmp_path / "law.py"
    dep.write_text("a = 1\n")

    def make():
        def fn(x):
            return x + 1.0
        k = compiled.kernel(str(dep))(fn)
        k(1.0)
        return fn.__qualname__

    first = make()
    assert make() == first
    dep.write_text("a = 2\n")
    assert make() != first
