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

import hashlib
import threading
import warnings
from pathlib import Path
from typing import Callable

#: the sources whose constants and helpers the compiled laws use: numba checks a cached law
#: against its own file only, so the laws' cache names carry a digest of all of them (a changed
#: constant, e.g. gas.T_REF_K, compiles afresh instead of running stale machine code)
SOURCES = ("air_supply.py", "chamber.py", "compiled.py", "compiled_step.py", "compressible_pipe.py", "fused.py", "gas.py",
           "heat_transfer.py", "integrate.py", "orifice.py", "pipe.py", "valve_signals.py", "valves.py")
_HERE = Path(__file__).resolve().parent
_HELPERS: list = []
_LOCK = threading.Lock()


def _digest() -> str:
    digest = hashlib.sha256()
    for name in SOURCES:
        digest.update((_HERE / name).read_bytes())
    return digest.hexdigest()[:16]


_DIGEST = _digest()  # the sources as imported: what numba will compile


def _compiled(fn: Callable, make: Callable) -> Callable:
    """``make(numba, cache)(fn)`` with the helpers registered: cached on disk under a name that
    carries the sources' digest; without the cache (a warning) where it cannot be written, or
    when a source changed since it was imported."""
    with _LOCK:
        import numba
        from numba.extending import register_jitable
        while _HELPERS:
            register_jitable(_HELPERS.pop())
        if _digest() != _DIGEST:
            return make(numba, False)(fn)
        fn.__qualname__ = f"{fn.__name__}_{_DIGEST}"
        try:
            return make(numba, True)(fn)
        except RuntimeError as exc:  # no writable cache folder anywhere
            warnings.warn(f"the circuit's compiled laws cannot be cached ({exc}); they compile in every "
                          f"process (a second or two)", RuntimeWarning, stacklevel=4)
            return make(numba, False)(fn)


class _Lazy:
    """The law compiled on its first call (:func:`_compiled`), then called directly."""

    def __init__(self, fn: Callable, make: Callable):
        self.py_func, self._make, self._call = fn, make, None
        self.__doc__, self.__name__, self.__wrapped__ = fn.__doc__, fn.__name__, fn

    def __call__(self, *args, **kwargs):
        if self._call is None:
            compiled = _compiled(self.py_func, self._make)
            # an elementwise law: numba's DUFunc, whose signatures are fixed (vectorize with a
            # signature compiles no other); its numpy ufunc runs the same loop without the DUFunc's
            # Python-level __call__ (a few us per call, the law's own cost on a few elements)
            self._call = getattr(compiled, "ufunc", compiled)
        return self._call(*args, **kwargs)


def elementwise(n_args: int) -> Callable[[Callable], Callable]:
    """Decorator: a scalar law of ``n_args`` floats as a ufunc over arrays and scalars (float64)."""
    signature = f"float64({', '.join(['float64'] * n_args)})"
    return lambda fn: _Lazy(fn, lambda numba, cache: numba.vectorize([signature], cache=cache))


def arrays(fn: Callable) -> Callable:
    """A function of arrays, compiled (numba ``njit``, cached) on its first call."""
    return _Lazy(fn, lambda numba, cache: numba.njit(cache=cache))


def scalar(fn: Callable) -> Callable:
    """A helper the compiled laws call (compiled into them); stays the Python function."""
    _HELPERS.append(fn)
    return fn
