"""The circuit's elementwise laws compiled by numba.

The circuit evaluates its laws on small arrays (components x cases) four times per macro-step,
where numpy's cost is the call of each operation, not the arithmetic (an orifice's eqs 6-7 took
13 us as a dozen numpy operations on a few numbers, 2 us compiled). :func:`elementwise` compiles
a law written for one set of floats into a numpy ufunc (numba's ``vectorize``): it broadcasts
like the numpy expression it replaces and gives the same numbers, operation for operation (IEEE
arithmetic and square roots are correctly rounded in both; NaN propagates through
``np.minimum`` / ``np.maximum`` as there). :func:`arrays` compiles a function of whole arrays
(``numba.njit``), e.g. a table lookup with ``np.interp``, which numba implements as numpy does.
:func:`scalar` compiles a helper the compiled laws call. ``tests/pneumatics/test_compiled.py``
checks them against the numpy expressions, bit for bit.

Each is compiled on its first call, not at import (numba alone takes ~0.4 s to import: a scenario
check should not pay it), and cached on disk (``cache=True``: a later process loads the machine
code in milliseconds). With ``NUMBA_DISABLE_JIT=1`` ``arrays`` and ``scalar`` run as Python;
``vectorize`` builds its ufunc all the same.
"""
from __future__ import annotations

from typing import Callable

_HELPERS: list = []


def _numba():
    """numba, with the :func:`scalar` helpers registered (once per process)."""
    import numba
    from numba.extending import register_jitable
    while _HELPERS:
        register_jitable(_HELPERS.pop())
    return numba


class _Lazy:
    """``compiler(fn)`` on the first call, then the compiled function (see the module doc)."""

    def __init__(self, fn: Callable, compiler: Callable[[Callable], Callable]):
        self.py_func, self._compile, self._call = fn, compiler, None
        self.__doc__, self.__name__, self.__wrapped__ = fn.__doc__, fn.__name__, fn

    def __call__(self, *args):
        if self._call is None:
            self._call = self._compile(self.py_func)
        return self._call(*args)


def elementwise(n_args: int) -> Callable[[Callable], Callable]:
    """Decorator: a scalar law of ``n_args`` floats as a ufunc over arrays and scalars (float64)."""
    signature = f"float64({', '.join(['float64'] * n_args)})"
    return lambda fn: _Lazy(fn, lambda f: _numba().vectorize([signature], cache=True)(f))


def arrays(fn: Callable) -> Callable:
    """A function of arrays, compiled (numba ``njit``, cached) on its first call."""
    return _Lazy(fn, lambda f: _numba().njit(cache=True)(f))


def scalar(fn: Callable) -> Callable:
    """A helper the compiled laws call (compiled into them); stays the Python function."""
    _HELPERS.append(fn)
    return fn
