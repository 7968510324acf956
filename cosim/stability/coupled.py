"""The car and its air circuit as one linear system (:func:`couple`), and its modes (:func:`modes`).

The car (:class:`~vehicle.car.linear.CarLinearisation`, independent coordinates eta, Maxwell
dampers' internal elongations w) and the circuit (:class:`~pneumatics.linear.CircuitLinearisation`,
air states x) exchange what the co-simulation exchanges, without its macro-step: the bellows'
crushing z_b and rate, and the air's force on the bellows. With u = G_x x the air's force at frozen
crushing (the frozen-air stiffness G_z is in the car's K)::

    M eta'' = -K eta - D eta' + W w + B u
    w'      = r (W_d eta - w)
    z_b     = Z eta + Z_u u,   z_b' = Z eta' + Z_u G_x x'
    x'      = A x + B_z z_b + B_zd z_b'
    =>  (I - B_zd Z_u G_x) x' = (A + B_z Z_u G_x) x + B_z Z eta + B_zd Z eta'

State (eta without the spin angles, which nothing depends on; eta'; w; x): d/dt X = A_c X.

Modes (:class:`Mode`): each eigenvalue's frequency and damping ratio, and what moves: each body's
kinetic energy by axis (1/2 M_jj |eta_j'|^2) and the air columns' in the pipes
(:attr:`~pneumatics.linear.CircuitLinearisation.kinetic_energy`), as shares of their sum. The
label (:func:`label`) is read from those shares.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List, Tuple

import numpy as np
from scipy.linalg import eig

from pneumatics.linear import CircuitLinearisation
from vehicle.car.linear import CarLinearisation

__all__ = ["CoupledModel", "Mode", "couple", "modes", "label", "family", "level_response", "NEUTRAL_RATE_PER_S"]

#: eigenvalues smaller than this [1/s] are neutral (the air mass a closed circuit conserves, time
#: constants beyond a day): no frequency, no damping, not a mode of running stability
NEUTRAL_RATE_PER_S = 1e-5
#: an eigenvalue whose imaginary part is below this fraction of its modulus is real (damping
#: ratio above 0.9999995): a double real eigenvalue splits into such a pair under round-off
REAL_BELOW = 1e-3
#: a body's axes grouped as the mode labels read them
_LATERAL, _VERTICAL, _LONGITUDINAL = ("y", "yaw"), ("z", "roll", "pitch"), ("x", "spin")


@dataclass(frozen=True)
class CoupledModel:
    """d/dt X = A X with X = (eta positions without spin angles, eta', w, x).

    Attributes
    ----------
    A : (n, n) array [1/s]
    car, air : the two linearisations it couples (``air`` None: frozen air, the car alone with
        the bellows' frozen-air stiffness)
    positions, rates, maxwell, pneumatic : slices of X
    position_coordinates : (n_pos,) int array
        The car coordinates (indices of eta) the position states are.
    """

    A: np.ndarray
    car: CarLinearisation
    air: CircuitLinearisation | None
    positions: slice
    rates: slice
    maxwell: slice
    pneumatic: slice
    position_coordinates: np.ndarray


def couple(car: CarLinearisation, air: CircuitLinearisation | None,
           bellow_coupling_N_per_m: np.ndarray | None = None) -> CoupledModel:
    """The coupled first-order system (module docstring); ``air`` None freezes the air.
    ``bellow_coupling_N_per_m`` (bellows x bellows, zero diagonal; with ``air`` None): springs
    between the bellows -- bellow i's force per metre of bellow j's crushing -- for airsprings
    that share their air (two-point circuits) replaced by a static stiffness matrix."""
    lin = car.system
    n = lin.M.shape[0]
    keep = np.setdiff1d(np.arange(n), car.spin)
    S = np.eye(n)[:, keep]                                # eta = S eta_positions
    nw = car.maxwell_rate_per_s.size
    na = 0 if air is None else air.A.shape[0]
    npos = keep.size
    size = npos + n + nw + na
    P, R, Wl, X = (slice(0, npos), slice(npos, npos + n), slice(npos + n, npos + n + nw),
                   slice(npos + n + nw, size))
    A = np.zeros((size, size))
    A[P, R] = S.T
    Minv = np.linalg.inv(lin.M)
    A[R, P] = -Minv @ lin.K @ S
    A[R, R] = -Minv @ lin.D
    A[R, Wl] = Minv @ car.maxwell_input
    r = np.diag(car.maxwell_rate_per_s)
    A[Wl, P] = r @ car.maxwell_deflection @ S
    A[Wl, Wl] = -r
    if bellow_coupling_N_per_m is not None:             # u = K_c z_b, z_b = Z eta + Z_u u
        Kc = np.asarray(bellow_coupling_N_per_m, dtype=float)
        u_per_eta = np.linalg.solve(np.eye(Kc.shape[0]) - Kc @ car.crushing_per_force, Kc @ car.crushing)
        A[R, P] += Minv @ car.bellow_input @ u_per_eta @ S
    if air is not None:
        A[R, X] = Minv @ car.bellow_input @ air.G_x
        feed = car.crushing_per_force @ air.G_x           # z_b per unit air state (emergency springs)
        L = np.eye(na) - air.B_zd @ feed
        A[X, X] = np.linalg.solve(L, air.A + air.B_z @ feed)
        A[X, P] = np.linalg.solve(L, air.B_z @ car.crushing @ S)
        A[X, R] = np.linalg.solve(L, air.B_zd @ car.crushing)
    return CoupledModel(A, car, air, P, R, Wl, X, keep)


@dataclass(frozen=True)
class Mode:
    """One eigenvalue of a :class:`CoupledModel` (of a complex pair, the one with Im >= 0).

    Attributes
    ----------
    eigenvalue : complex [1/s]
    frequency_Hz : float
        Damped frequency Im / 2 pi (0 for a real eigenvalue).
    damping_ratio : float
        -Re / |eigenvalue| (1 or -1 for a real one; negative: growing).
    label : str
        What moves (:func:`label`).
    shares : dict
        Kinetic energy shares by body and axis: keys like ``carbody y``, ``bogie 1 yaw``,
        ``wheelset 3 y``, ``air``; they sum to 1.
    """

    eigenvalue: complex
    frequency_Hz: float
    damping_ratio: float
    label: str
    shares: Dict[str, float] = field(repr=False)

    @property
    def family(self) -> str:
        return family(self.label)

    @property
    def oscillatory(self) -> bool:
        return self.frequency_Hz > 0.0


def _shares(model: CoupledModel, vector: np.ndarray) -> Dict[str, float]:
    """Kinetic energy of each (body, axis) and of the air in the pipes in an eigenvector, as shares
    of their sum (none moves: all to the air, a relaxation of its pressures or temperatures)."""
    car = model.car
    rates = vector[model.rates]
    kinetic = 0.5 * np.real(np.diag(car.system.M)) * np.abs(rates) ** 2
    energy: Dict[str, float] = {}
    for (body, axis), e in zip(car.coordinates, kinetic):
        key = f"{body} {axis}"
        energy[key] = energy.get(key, 0.0) + float(e)
    if model.air is not None:
        x = vector[model.pneumatic]
        energy["air"] = float(0.5 * np.real(np.conj(x) @ model.air.kinetic_energy @ x))
    total = sum(energy.values())
    return {k: v / total for k, v in energy.items()} if total > 0 else {"air": 1.0}


def _group(shares: Dict[str, float], bodies: Tuple[str, ...], axes: Tuple[str, ...]) -> float:
    return sum(v for k, v in shares.items() if k.rsplit(" ", 1)[0] in bodies and k.rsplit(" ", 1)[1] in axes)


def label(shares: Dict[str, float], carbody_y: complex = 0.0, carbody_roll: complex = 0.0) -> str:
    """A mode's name from its energy shares (and, for a carbody sway, the phase of lateral
    displacement and roll at the centre of gravity):

    * ``air`` when the air holds most of its energy;
    * the carbody's when it holds most of the rest: ``carbody lower sway`` / ``upper sway``
      (lateral and roll; lower when the body turns about a point above its centre of gravity),
      ``bounce``, ``pitch``, ``yaw``, ``longitudinal``;
    * else the running gear's: in the lateral plane ``bogie hunting`` where the wheelsets carry
      a fifth or more of the energy (they steer it: kinematic motion), else ``bogie yaw`` or
      ``bogie lateral``; vertically ``bogie bounce`` / ``pitch`` / ``roll``, or ``wheelset
      vertical`` (on the contacts' stiffness); along the track ``longitudinal`` or ``wheelset
      spin``. The bogie named (1 front, 2 rear) holds at least two thirds of the bogies' share,
      else ``bogies``.
    """
    if shares.get("air", 0.0) > 0.5:
        return "air"
    axes_all = _LATERAL + _VERTICAL + _LONGITUDINAL
    carbody = _group(shares, ("carbody",), axes_all)
    bogies = ("bogie 1", "bogie 2")
    wheelsets = tuple(f"wheelset {i}" for i in range(1, 5))
    gear = _group(shares, bogies + wheelsets, axes_all)
    if carbody >= gear:
        by_axis = {a: shares.get(f"carbody {a}", 0.0) for a in ("x", "y", "z", "roll", "pitch", "yaw")}
        if by_axis["y"] + by_axis["roll"] >= max(by_axis["z"], by_axis["pitch"], by_axis["yaw"], by_axis["x"]):
            if carbody_roll == 0.0:
                return "carbody sway"
            height = np.real(carbody_y / carbody_roll)    # y - h roll = 0: the centre of rotation
            return "carbody lower sway" if height > 0.0 else "carbody upper sway"
        name = max(("z", "pitch", "yaw", "x"), key=lambda a: by_axis[a])
        return "carbody " + {"z": "bounce", "pitch": "pitch", "yaw": "yaw", "x": "longitudinal"}[name]
    planes = {"lateral": _LATERAL, "vertical": _VERTICAL, "longitudinal": _LONGITUDINAL}
    plane = max(planes, key=lambda p: _group(shares, bogies + wheelsets, planes[p]))
    axes = planes[plane]
    per_bogie = [_group(shares, (b,), axes) for b in bogies]
    total_bogies = sum(per_bogie)
    which = ("bogie 1" if per_bogie[0] >= 2 * per_bogie[1] else
             "bogie 2" if per_bogie[1] >= 2 * per_bogie[0] else "bogies")
    ws = _group(shares, wheelsets, axes)
    if plane == "lateral":
        if ws >= 0.2:
            return f"{which} hunting"
        return f"{which} yaw" if _group(shares, bogies, ("yaw",)) >= _group(shares, bogies, ("y",)) else f"{which} lateral"
    if plane == "vertical":
        if ws > total_bogies:
            return "wheelset vertical"
        name = max(_VERTICAL, key=lambda a: _group(shares, bogies, (a,)))
        return f"{which} " + {"z": "bounce", "roll": "roll", "pitch": "pitch"}[name]
    return "wheelset spin" if _group(shares, wheelsets, ("spin",)) > _group(shares, bogies + wheelsets, ("x",)) \
        else "longitudinal"


def family(mode_label: str) -> str:
    """A mode label without which bogie (``bogie 1 hunting`` -> ``bogie hunting``): the families
    that the plots of damping against speed draw."""
    return mode_label.replace(" 1", "").replace(" 2", "").replace("bogies", "bogie")


def modes(model: CoupledModel) -> List[Mode]:
    """Every mode of ``model`` (one per complex pair, real ones too, the neutral ones left out:
    :data:`NEUTRAL_RATE_PER_S`), least damped first."""
    values, vectors = eig(model.A)
    coords = model.car.coordinates
    iy = next((i for i, c in enumerate(coords) if c == ("carbody", "y")), None)
    iroll = next((i for i, c in enumerate(coords) if c == ("carbody", "roll")), None)
    out = []
    for lam, vec in zip(values, vectors.T):
        if abs(lam) < NEUTRAL_RATE_PER_S or lam.imag < 0.0:
            continue
        shares = _shares(model, vec)
        rates = vec[model.rates]
        y = rates[iy] if iy is not None else 0.0
        roll = rates[iroll] if iroll is not None else 0.0
        if abs(lam.imag) <= REAL_BELOW * abs(lam):
            lam = complex(lam.real, 0.0)
        zeta = float(-lam.real / abs(lam))
        out.append(Mode(complex(lam), float(lam.imag / (2.0 * np.pi)), zeta, label(shares, y, roll), shares))
    return sorted(out, key=lambda m: m.damping_ratio)


def level_response(model: CoupledModel, omega_rad_per_s, wheelset_x_m, coordinate: Tuple[str, str]) -> np.ndarray:
    """The acceleration of one car coordinate (``("carbody", "z")`` ...) per metre of the track's
    vertical level (both rails), at each circular frequency [1/s^2 per m, complex], the car
    running at its linearisation's speed V: wheelset i (at ``wheelset_x_m[i]`` ahead of the car
    centre) meets the level x_i / V before the centre does, so its input is e^(i w x_i / V) times
    the level under the centre. The car's rail inputs enter as forces (rail_input) and through
    their rate (rail_rate_input); a ride's floor acceleration and its power spectrum follow
    (|H|^2 times the level's spectrum at w = V Omega)."""
    car = model.car
    if car.rail_input is None:
        raise ValueError("level_response needs the car linearised with its rail inputs "
                         "(vehicle.car.linear.linearise_car(..., rail_inputs=True))")
    j = car.coordinates.index(tuple(coordinate))
    V = car.speed_m_per_s
    n = model.A.shape[0]
    Minv = np.linalg.inv(car.system.M)
    B, Bd = np.zeros((n, 4)), np.zeros((n, 4))
    B[model.rates], Bd[model.rates] = Minv @ car.rail_input, Minv @ car.rail_rate_input
    row = model.rates.start + j
    out = []
    for w in np.atleast_1d(np.asarray(omega_rad_per_s, dtype=float)):
        u = np.exp(1j * w * np.asarray(wheelset_x_m, dtype=float) / V)
        forcing = (B + 1j * w * Bd) @ u
        X = np.linalg.solve(1j * w * np.eye(n) - model.A, forcing)
        out.append(model.A[row] @ X + forcing[row])
    return np.array(out)
