"""The compiled contact kernels (vehicle/wheelrail/compiled.py) against the same law run by
Python.

The kernels compile the law's own functions (one source), so they must agree with the Python
evaluation to rounding. The Python side is evaluated independently of the kernels: per wheelset
with ``SCALAR`` ops (Python's math), and the Jacobian by central differences instead of the
kernel's forward differences. Since that shares the car's assembly (``_wheelset``, its table
packing and lookup) with the kernels, the forces are also checked against the law assembled the
free wheelset's way (``contact_law.generalized_forces`` on ``ContactLawTable.geometry``), which
shares neither.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys

import numpy as np
import pytest

from vehicle.wheelrail import compiled
from vehicle.wheelrail.contact_law import SCALAR, ContactLawTable, WheelsetParams, WheelsetState, generalized_forces
from vehicle.wheelrail.geometry import ContactTable
from vehicle.wheelrail.track_contact import WheelsetTrackContact, _wheelset

R0 = 0.46
V = 10.0


REFS = np.array([[x, 0.0, R0] for x in (0.0, 1.9, 10.0, 11.9)])


@pytest.fixture(scope="module")
def law():
    return ContactLawTable(ContactTable.default(), WheelsetParams())


@pytest.fixture(scope="module")
def contact(law):
    return WheelsetTrackContact(law, WheelsetParams(), REFS, R0, V)


@pytest.fixture(scope="module")
def creeping(law):
    """Below the creep regularisation speed (0.3 < V_min = 1 m/s): viscous creep forces."""
    return WheelsetTrackContact(law, WheelsetParams(), REFS, R0, 0.3)


def states(wr, rng, count):
    """``count`` random (q, q_t) around rolling on a curve (set as the track of ``wr``): every
    wheelset at a lateral position across the whole table (tread, flange root, flank), in
    contact (pressed 20-60 um into the rails), yawed, rolled, with rates, on a canted curve with
    rail offsets. About every third state has one wheelset beyond the table (its end rows hold)
    and one lifted 1 mm off the rails (no contact)."""
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
            qt[7 * i + 6] = wr.V / R0 * (1.0 + 1e-3 * rng.standard_normal())
        if rng.random() < 1 / 3:
            i, j = rng.choice(4, size=2, replace=False)
            q[7 * i:7 * i + 3] += 1.3 * hi * np.array(wr._frames[i].l)
            q[7 * j:7 * j + 3] += 1e-3 * np.array(wr._frames[j].n)
        yield q, qt


def python_forces(wr, q, qt):
    """The law per wheelset with Python's math (SCALAR ops), no kernel."""
    out = []
    for i, fr in enumerate(wr._frames):
        Q = _wheelset(SCALAR, wr._table, wr._setup, wr._ref[i], fr, q[7 * i:7 * i + 7].tolist(),
                      qt[7 * i:7 * i + 7].tolist())[0]
        out += [float(v) for v in Q[:wr.m]]
    return np.array(out)


def test_kernels_compile_here():
    """The speed of contact guidance rests on the kernels compiling (numba is a dependency)."""
    assert compiled.numba_available()


@pytest.mark.parametrize("which", ["contact", "creeping"])
def test_compiled_forces_are_the_python_law(which, request):
    """Same operations in the same order: equal to rounding. Tolerance: 1e-12 of each
    wheelset's largest generalized force (the normal forces, ~30 kN; a lifted wheelset's are
    0, hence the floor of 1 N); compiled and Python transcendental functions may differ in the
    last bit, which the law amplifies by no more than a few hundred (the Hertz power 1.5 of a
    20-60 um overlap)."""
    wr = request.getfixturevalue(which)
    rng = np.random.default_rng(11)
    n_flange = n_lifted = 0
    for q, qt in states(wr, rng, 60):
        got = wr.forces(q, qt)
        ref = python_forces(wr, q, qt)
        assert np.all(np.isfinite(got))
        scale = np.maximum(np.abs(ref.reshape(4, 7)).max(axis=1), 1.0).repeat(7)
        np.testing.assert_array_less(np.abs(got - ref), 1e-12 * scale)
        N = wr.outputs(q, qt).normal_N
        n_flange += int(np.sum(wr.outputs(q, qt).gamma_rad > 0.7))
        n_lifted += int(np.sum((N[0::2] == 0) & (N[1::2] == 0)))
    assert n_flange > 20 and n_lifted > 5  # the states include flange contact and lifted ones


def test_compiled_forces_are_the_free_wheelset_law(contact, law):
    """On straight, level track the car's wheelset coordinates are the free wheelset's: roll
    and yaw are the Rxyz angles a and c (pitch b = 0), the roll rate a', the yaw rate
    cos(a) c'. So the kernel's generalized forces must equal ``generalized_forces`` of the law
    (the coefficient form, with the table read by ``ContactLawTable.geometry``: neither the
    kernels' assembly nor their table packing) with its gyroscopic terms taken out (the two
    models write those differently; the kernel's spin inertia is set to 0 here). Tolerance
    1e-9 of the wheelset's largest force: two assemblies of the same sums (rounding)."""
    P = WheelsetParams()
    wr = WheelsetTrackContact(law, P, REFS, R0, V)
    wr._setup_row[7] = 0.0  # spin inertia: no gyroscopic moments
    wr.set_track([(x, 0.0, 0.0, 0.0, 0.0, 0.0) for x in REFS[:, 0]])
    z0 = wr.static_rise_m(30e3)
    lo, hi = law.y_range_m
    rng = np.random.default_rng(21)
    for _ in range(40):
        q, qt = np.zeros(28), np.zeros(28)
        for i in range(4):
            k = 7 * i
            # positions (x, y, z, a = roll, b = pitch = 0, c = yaw) and rates (x' = V, y', z',
            # a', b' = 0, c', spin)
            q[k:k + 6] = [0.0, rng.uniform(0.8 * lo, 0.8 * hi), z0 - rng.uniform(2e-5, 6e-5),
                          1e-3 * rng.standard_normal(), 0.0, 5e-3 * rng.standard_normal()]
            y_t, z_t, a_t, c_t = 1e-2 * rng.standard_normal(4)
            qt[k:k + 7] = [V, y_t, z_t, a_t, 0.0, c_t,
                           V / R0 * (1.0 + 1e-3 * rng.standard_normal())]
        got = wr.forces(q, qt).reshape(4, 7)
        for i in range(4):
            y, z, a, c = q[7 * i + 1], q[7 * i + 2], q[7 * i + 3], q[7 * i + 5]
            st = WheelsetState(y, z, a, c, qt[7 * i + 1], qt[7 * i + 2], qt[7 * i + 3],
                               math.cos(a) * qt[7 * i + 5], qt[7 * i + 6])
            ref = np.array(generalized_forces(SCALAR, st, law.geometry(y), V, 0.0, P,
                                              law.reference_load_N), dtype=float)
            Is, spin = P.spin_inertia_kg_m2, st.spin_t
            ref[3] -= Is * spin * st.yaw_t
            ref[5] += Is * spin * st.roll_t
            keep = [0, 1, 2, 3, 5, 6]  # the pitch entry: held (the free wheelset's is 0)
            scale = np.abs(ref).max()
            np.testing.assert_array_less(np.abs(got[i, keep] - ref[keep]), 1e-9 * scale)


def test_compiled_outputs_are_the_python_law(contact):
    rng = np.random.default_rng(12)
    for q, qt in states(contact, rng, 20):
        out = contact.outputs(q, qt)
        for i, fr in enumerate(contact._frames):
            e_mean = 0.5 * (fr.rails[0][0] + fr.rails[1][0])
            assert out.lateral_to_rails_m[i] == pytest.approx(out.lateral_m[i] - e_mean,
                                                              rel=1e-15, abs=1e-18)
            _, wheels, (ry, yaw, _) = _wheelset(SCALAR, contact._table, contact._setup,
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


@pytest.mark.slow
def test_an_edited_law_is_not_run_from_a_stale_cache(tmp_path):
    """numba re-validates a cached kernel against its own file only. A kernel that calls a
    jitable law from another file is compiled and cached in one process; the law is edited;
    a new process must run the edited law (without the digest in the kernel's name it loads
    the cached machine code of the old one)."""
    (tmp_path / "law_mod.py").write_text(
        "from vehicle.wheelrail.compiled import jitable\n"
        "@jitable\n"
        "def law(x):\n"
        "    return 1.0 * x\n")
    (tmp_path / "kernel_mod.py").write_text(
        "import law_mod\n"
        "from vehicle.wheelrail.compiled import kernel\n"
        "@kernel(__file__, law_mod.__file__)\n"
        "def run(x):\n"
        "    return law_mod.law(x)\n")
    code = "import kernel_mod; print(kernel_mod.run(3.0))"

    def run():
        res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             cwd=tmp_path, env=dict(os.environ, PYTHONPATH=str(tmp_path)
                                                    + os.pathsep + os.getcwd()))
        assert res.returncode == 0, res.stderr
        return float(res.stdout)

    assert run() == 3.0
    assert list((tmp_path / "__pycache__").glob("kernel_mod.run_*.nbi"))  # it was cached
    (tmp_path / "law_mod.py").write_text((tmp_path / "law_mod.py").read_text()
                                         .replace("1.0 * x", "2.0 * x"))
    assert run() == 6.0


def test_wrong_lengths_are_refused_before_the_kernels(contact):
    """The kernels do not check bounds: a wrong length must not reach them."""
    q = np.zeros(28)
    for bad in (np.zeros(21), np.zeros(35)):
        with pytest.raises(ValueError, match="28 entries"):
            contact.forces(bad, bad)
        with pytest.raises(ValueError, match="28 entries"):
            contact.jacobian(q, bad, 1.0, 1.0)
    with pytest.raises(ValueError, match="need 4 frames"):
        contact.set_track([(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)] * 3)


def _rotation(axis, angle):
    """Rotation matrix about a unit ``axis`` by ``angle`` (Rodrigues)."""
    k = np.asarray(axis, dtype=float)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * K @ K


def _tait_bryan(A):
    """(a, b, c) of A = Rx(a) Ry(b) Rz(c)."""
    return math.atan2(-A[1, 2], A[2, 2]), math.asin(A[0, 2]), math.atan2(-A[0, 1], A[0, 0])


def test_flexible_track_gets_the_opposite_of_the_contact_forces(law):
    """The track's coordinates carry the reaction of the contact: moving wheelset and track
    together rigidly (along the track plane's lateral axis, along its normal, or rolling both
    about the tangent through the track centre) changes no contact force, and the contact's
    generalized forces do no work in that motion but the support preload's (the pair is
    internal). Checked on a canted, curved frame with the track displaced and the wheelset yawed,
    each motion by 1e-7 m or rad; the work is first order in the step, so the
    residual is ~1e-7 of |F| times it (bound 1e-5)."""
    preload = 60e3
    wr = WheelsetTrackContact(law, WheelsetParams(), REFS, R0, V, track_preload_N=preload)
    wr.set_track([(r[0], 0.0, 0.1, 0.1, 1e-2, 0.0) for r in REFS])
    fr, ref = wr._frames[0], wr._ref[0]
    from vehicle.wheelrail.track_contact import _moved
    q = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2e-4, -1e-4, 3e-4])
    moved = _moved(fr, *q[7:10], 0.0, 0.0, 0.0)
    # the wheelset centred on its (displaced) rails, rolled with the track, at the height where
    # the contact carries ~30 kN a wheel
    p = (np.array([moved.ox, moved.oy, moved.oz]) + q[7] * np.array(moved.l)
         + (wr.r0 + wr.static_rise_m(30e3)) * np.array(moved.n))
    q[:3] = p - np.array(ref)
    # oriented with the displaced track, yawed 2 mrad on it
    frame = np.array([moved.t, moved.l, moved.n]).T
    q[3:6] = _tait_bryan(frame @ _rotation((0, 0, 1), 2e-3))
    qt = np.array([*(V * np.array(moved.t)), 0.0, 0.0, 0.0, V / R0, 0.0, 0.0, 0.0])

    def evaluate(qq):
        Q, wheels, _ = _wheelset(SCALAR, wr._table, wr._setup, ref, fr, qq.tolist(), qt.tolist())
        return np.array(Q), np.array([w[0].N for w in wheels])

    Q0, N0 = evaluate(q)
    assert 1e4 < N0.max() < 1e5 and Q0[7:].any()
    origin = np.array([moved.ox, moved.oy, moved.oz])
    d = 1e-7
    for axis in ("lateral", "normal", "roll"):
        qn = q.copy()
        if axis == "lateral":
            qn[7] += d
            qn[:3] += d * np.array(moved.l)
        elif axis == "normal":
            qn[8] += d
            qn[:3] += d * np.array(moved.n)
        else:
            qn[9] += d
            R = _rotation(moved.t, d)
            p = np.array(ref) + q[:3]
            qn[:3] = origin + R @ (p - origin) - np.array(ref)
            A = _rotation((1, 0, 0), q[3]) @ _rotation((0, 1, 0), q[4]) @ _rotation((0, 0, 1), q[5])
            qn[3:6] = _tait_bryan(R @ A)
            qn[6] += d * (A[:, 1] @ np.array(moved.t))   # the wheel turns about its axle by its share
        Qn, Nn = evaluate(qn)
        assert np.abs(Nn - N0).max() < 1e-6 * N0.max(), axis
        dq = qn - q
        work = Q0 @ dq - preload * moved.n[2] * dq[8]
        assert abs(work) < 1e-5 * np.abs(Q0[:3]).max() * d, (axis, work)


def test_offsets_along_and_across_the_track_are_the_projections_on_the_frames(contact):
    """The PreStep's compiled offsets (longitudinal along each frame's tangent t, lateral along
    its l, at q + h q_t) against numpy projections on the frames of ``_frames`` (a Python
    reading of the same rows), and the table check against the table's range: every wheel's
    y - e inside. Tolerance 1e-15 m: the same three products summed (rounding at most)."""
    rng = np.random.default_rng(15)
    lo, hi = contact.table.y_range_m
    seen = set()
    for q, qt in states(contact, rng, 30):
        h = 5e-3
        ahead = q + h * qt
        along = contact.longitudinal_offsets(q, qt, h)
        across, inside = contact.lateral_positions(q, qt, h)
        for i, fr in enumerate(contact._frames):
            d = REFS[i] + ahead[7 * i:7 * i + 3] - np.array([fr.ox, fr.oy, fr.oz])
            assert along[i] == pytest.approx(np.dot(fr.t, d), abs=1e-15)
            assert across[i] == pytest.approx(np.dot(fr.l, d), abs=1e-15)
        wheels = [across[i] - fr.rails[side][0] for i, fr in enumerate(contact._frames)
                  for side in range(2)]
        assert inside == all(lo <= y <= hi for y in wheels)
        seen.add(inside)
    assert seen == {True, False}  # the states include wheelsets beyond the table


@pytest.mark.parametrize("e_left_m, e_right_m, inside", [
    (3e-3, 3e-3, True),   # both rails moved 3 mm towards it: y - e = hi - 1 mm on both
    (3e-3, 0.0, False),   # the right wheel is 2 mm beyond (reading e_L for both: inside)
    (0.0, 3e-3, False),   # the left wheel is (reading e_R for both: inside)
    (0.0, 0.0, False),
])
def test_the_table_check_reads_each_wheel_against_its_own_rail(law, e_left_m, e_right_m, inside):
    """A wheelset 2 mm beyond the table's upper end is inside it only where both of its rails'
    lateral offsets take it back in: y - e <= hi for each wheel with its own rail's e. A sign
    error (y + e) or one rail's offset for both wheels gives the opposite answer in one case."""
    wr = WheelsetTrackContact(law, WheelsetParams(), REFS, R0, V)
    hi = wr.table.y_range_m[1]
    rails = [[(e_left_m, 0.0, 0.0, 0.0), (e_right_m, 0.0, 0.0, 0.0)]] + [[(0.0,) * 4] * 2] * 3
    wr.set_track([(x, 0.0, 0.0, 0.0, 0.0, 0.0) for x in REFS[:, 0]], rails)
    q = np.zeros(28)
    q[1] = hi + 2e-3  # on straight level track the frame's l is the global y
    y, got = wr.lateral_positions(q)
    assert y[0] == pytest.approx(hi + 2e-3, abs=1e-15)
    assert got is inside


def test_offsets_on_a_flexible_track_are_relative_to_the_tracks_lateral_displacement(law):
    """Flexible track (10 coordinates per wheelset, the 8th the track's lateral displacement):
    the lateral position is the projection on l minus that displacement, both at q + h q_t."""
    wr = WheelsetTrackContact(law, WheelsetParams(), REFS, R0, V, track_preload_N=30e3)
    rng = np.random.default_rng(16)
    frames = [(x, 0.01 * rng.standard_normal(), 0.02 * rng.standard_normal(), 0.05, 0.0, 0.0)
              for x in REFS[:, 0]]
    wr.set_track(frames)
    q, qt, h = 1e-3 * rng.standard_normal(40), 1e-2 * rng.standard_normal(40), 5e-3
    across, _ = wr.lateral_positions(q, qt, h)
    along = wr.longitudinal_offsets(q, qt, h)
    ahead = q + h * qt
    for i, fr in enumerate(wr._frames):
        d = REFS[i] + ahead[10 * i:10 * i + 3] - np.array([fr.ox, fr.oy, fr.oz])
        assert across[i] == pytest.approx(np.dot(fr.l, d) - ahead[10 * i + 7], abs=1e-15)
        assert along[i] == pytest.approx(np.dot(fr.t, d), abs=1e-15)
