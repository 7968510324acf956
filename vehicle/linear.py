"""Linearisation of an exudyn multibody system about its current state, without an integrator.

The system's equations of motion (exudyn's second-order form with algebraic constraints)

    M(q) q'' = f(q, q', t) - C_q(q)^T lambda,    C(q) = 0,

are linearised about a state (q0, q0') at which q'' = 0 and lambda = 0 (steady motion without
constraint reactions: the drive and the wheelsets' pitch locks of a car running on straight
track), by central differences of f (:func:`stiffness_and_damping`)::

    M dq'' + D dq' + K dq = 0,   K = -df/dq,  D = -df/dq'   (C_q dq = 0).

The constraints are eliminated by coordinate partitioning (:func:`independent_coordinates`): the
coordinates that the constraint Jacobian's pivoted QR picks become dependent, dq = N deta with
eta the independent coordinates (each a coordinate of the model, so that modes keep their
names), and the reduced matrices are N^T M N, N^T K N, N^T D N. The terms lambda^T C_qq that a
constraint reaction would add vanish with lambda = 0; :func:`reduced_residual` is the force
balance that the steady state must satisfy.

exudyn's own linearisation (``mbs.ComputeLinearizedSystem``, forward differences of its
Jacobian routines and an SVD null space) is the independent check of this one
(tests/vehicle/test_linear.py).
"""
from __future__ import annotations

from dataclasses import dataclass

import exudyn as exu
import numpy as np
from scipy.linalg import qr

__all__ = ["LinearSystem", "ode2_rhs", "mass_matrix", "constraint_jacobian", "independent_coordinates",
           "stiffness_and_damping", "linearise", "steady_state", "reduced_residual"]

#: central-difference steps: positions [m, rad] (Hertz contacts deflect ~0.1 mm: 1e-8 m keeps the
#: truncation error ~1e-8 relative and the round-off of ~3e4 N forces ~1e-3 N/m) and rates [m/s,
#: rad/s] (creepages of 1e-7 at 10 m/s, far inside Kalker's linear range)
STEP_POSITION = 1e-8
STEP_RATE = 1e-6


@dataclass(frozen=True)
class LinearSystem:
    """M eta'' + D eta' + K eta = 0 in the independent coordinates eta (q = q0 + N eta).

    Attributes
    ----------
    M, K, D : (n, n) arrays
        Reduced mass [kg, kg m^2], stiffness [N/m ...] and damping [N s/m ...] matrices.
    N : (n_q, n) array
        dq/deta (identity rows for the independent coordinates).
    independent : (n,) int array
        The system coordinates that eta are.
    """

    M: np.ndarray
    K: np.ndarray
    D: np.ndarray
    N: np.ndarray
    independent: np.ndarray


def _state(mbs):
    sd = mbs.systemData
    return sd.GetODE2Coordinates(), sd.GetODE2Coordinates_t()


def ode2_rhs(mbs, solver) -> np.ndarray:
    """f(q, q', t) at the system's current state (size n_q), the constraint reactions excluded."""
    solver.ComputeODE2RHS(mbs)
    return np.array(solver.GetSystemResidual()[:solver.GetODE2size()])


def mass_matrix(mbs, solver) -> np.ndarray:
    """M(q) at the current state (dense)."""
    n = solver.GetODE2size()
    solver.ComputeMassMatrix(mbs)
    return np.array(solver.GetSystemMassMatrix()[:n, :n])


def constraint_jacobian(mbs, solver) -> np.ndarray:
    """C_q at the current state, the rows of the constraints that act (a joint's unconstrained axes
    give zero rows in exudyn's system Jacobian; they are left out)."""
    n2, nae = solver.GetODE2size(), solver.GetAEsize()
    if nae == 0:
        return np.zeros((0, n2))
    solver.ComputeJacobianAE(mbs, scalarFactor_ODE2=1.0, scalarFactor_ODE2_t=0.0, scalarFactor_ODE1=0.0,
                             velocityLevel=False)
    C = np.array(solver.GetSystemJacobian()[n2:n2 + nae, :n2])
    return C[np.any(C != 0.0, axis=1)]


def independent_coordinates(C: np.ndarray, tol: float = 1e-10) -> tuple[np.ndarray, np.ndarray]:
    """(independent coordinate indices, N) with C N = 0: the dependent coordinates are the pivots of
    C's column-pivoted QR (one per independent constraint, the best-conditioned choice), and
    N = [I; -C_d^-1 C_i] in the original ordering."""
    n = C.shape[1]
    if C.shape[0] == 0:
        return np.arange(n), np.eye(n)
    _, R, piv = qr(C, pivoting=True, mode="economic")
    diag = np.abs(np.diag(R))
    rank = int(np.sum(diag > tol * max(diag.max(), 1.0)))
    dependent = np.sort(piv[:rank])
    independent = np.setdiff1d(np.arange(n), dependent)
    Cd, Ci = C[:, dependent], C[:, independent]
    N = np.zeros((n, independent.size))
    N[independent, np.arange(independent.size)] = 1.0
    N[dependent] = -np.linalg.lstsq(Cd, Ci, rcond=None)[0]
    return independent, N


def stiffness_and_damping(mbs, solver, step_position: float = STEP_POSITION,
                          step_rate: float = STEP_RATE) -> tuple[np.ndarray, np.ndarray]:
    """(K, D) = (-df/dq, -df/dq') at the current state by central differences of :func:`ode2_rhs`
    (2 n_q evaluations each); the state is restored."""
    cfg = exu.ConfigurationType.Current
    sd = mbs.systemData
    q0, v0 = _state(mbs)
    n = q0.size
    K, D = np.empty((n, n)), np.empty((n, n))
    try:
        for matrix, base, h, setter in ((K, q0, step_position, sd.SetODE2Coordinates),
                                        (D, v0, step_rate, sd.SetODE2Coordinates_t)):
            for j in range(n):
                x = base.copy()
                x[j] = base[j] + h
                setter(x, cfg)
                f_plus = ode2_rhs(mbs, solver)
                x[j] = base[j] - h
                setter(x, cfg)
                f_minus = ode2_rhs(mbs, solver)
                matrix[:, j] = -(f_plus - f_minus) / (2.0 * h)
            setter(base, cfg)
    finally:
        sd.SetODE2Coordinates(q0, cfg)
        sd.SetODE2Coordinates_t(v0, cfg)
    return K, D


def linearise(mbs, solver) -> LinearSystem:
    """The reduced linear system about the current state (see the module docstring)."""
    independent, N = independent_coordinates(constraint_jacobian(mbs, solver))
    M = mass_matrix(mbs, solver)
    K, D = stiffness_and_damping(mbs, solver)
    return LinearSystem(N.T @ M @ N, N.T @ K @ N, N.T @ D @ N, N, independent)


def reduced_residual(mbs, solver, N: np.ndarray) -> np.ndarray:
    """N^T f: the force balance in the independent coordinates (the constraint reactions drop out)."""
    return N.T @ ode2_rhs(mbs, solver)


def steady_state(mbs, solver, rate_coordinates=(), tol: float = 1e-6, max_iterations: int = 20) -> float:
    """Move the system's current state to steady motion, q'' = 0: Newton's method on the reduced
    force balance :func:`reduced_residual`. The unknowns are the independent positions, except for
    ``rate_coordinates`` (system coordinates whose position nothing depends on, such as a wheel's
    spin angle), whose rates are solved for instead. Returns the largest reduced force left;
    RuntimeError when it does not fall below ``tol`` [N, N m]."""
    independent, N = independent_coordinates(constraint_jacobian(mbs, solver))
    rates = np.flatnonzero(np.isin(independent, np.asarray(rate_coordinates, dtype=int)))
    sd, cfg = mbs.systemData, exu.ConfigurationType.Current
    residual = np.inf
    for _ in range(max_iterations):
        f = reduced_residual(mbs, solver, N)
        residual = float(np.max(np.abs(f)))
        if residual < tol:
            return residual
        K, D = stiffness_and_damping(mbs, solver)
        J = N.T @ K @ N
        J[:, rates] = (N.T @ D @ N)[:, rates]
        delta = np.linalg.solve(J, f)                      # f(x + delta) = f - J delta = 0
        q, v = (np.array(a) for a in _state(mbs))
        step = delta.copy()
        step[rates] = 0.0
        sd.SetODE2Coordinates(q + N @ step, cfg)
        v[independent[rates]] += delta[rates]
        sd.SetODE2Coordinates_t(v, cfg)
    raise RuntimeError(f"steady motion not found: reduced force {residual:.3g} after {max_iterations} "
                       f"Newton iterations")
