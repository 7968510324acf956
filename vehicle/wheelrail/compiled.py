"""The contact law compiled by numba: the operations the law is written against, and kernels.

The force law (:mod:`vehicle.wheelrail.contact_law`) and its application to the car's wheelsets
(:mod:`vehicle.wheelrail.track_contact`) are written once, against a table of math operations
``ops`` (:class:`Ops`). Python runs them with floats (:data:`PYTHON`), numpy arrays, or exudyn
symbolic expressions; a **kernel** (:func:`kernel`) runs them compiled to machine code by numba
(``nopython`` mode), passing the module :mod:`vehicle.wheelrail.kernel_ops` as ``ops`` (the same
operations as functions numba compiles). So the
compiled law is the Python law, operation for operation; ``tests/vehicle/test_compiled_law.py`` checks
that they agree to rounding.

* :func:`jitable` marks a function the kernels call. It stays the plain Python function
  (numba's ``register_jitable``, applied when the first kernel compiles).
* :func:`kernel` makes a function numba compiles on its first call, cached on disk (numba's
  ``cache=True``: later processes load it in ~0.1 s instead of compiling for seconds).

numba invalidates a cached kernel when the file that defines the kernel changes, not when a
function it calls from another file does. A kernel's name therefore carries a digest of the
source files given to :func:`kernel` (``depends``), taken when they are imported: a change to
the law compiles afresh instead of running a stale kernel (and a file changed after it was
imported compiles without the cache). Old cache files stay in ``__pycache__`` (or numba's cache
folder) until removed; each set is ~1 MB.

Without numba installed, or with ``NUMBA_DISABLE_JIT=1``, the kernels run as Python: the same
numbers, many times slower.
"""

from __future__ import annotations

import hashlib
import importlib.util
import math
import os
import warnings
from typing import Callable, NamedTuple

from . import kernel_ops

__all__ = ["Ops", "PYTHON", "jitable", "kernel", "numba_available"]


class Ops(NamedTuple):
    """The math operations the contact law uses (each takes and returns numbers, arrays or
    expressions of one kind)."""

    sqrt: Callable
    sin: Callable
    cos: Callable
    atan2: Callable
    pow: Callable
    where: Callable  # where(cond, a, b): a if cond else b; both a and b are evaluated
    max: Callable
    min: Callable
    const: Callable  # a constant of the kind (float, or exudyn's symbolic Real)


#: floats, with Python's ``math``
PYTHON = Ops(math.sqrt, math.sin, math.cos, math.atan2, math.pow, kernel_ops.where,
             kernel_ops.max, kernel_ops.min, float)

_JITABLE: list[Callable] = []
_STATE: dict = {}


def numba_available() -> bool:
    """Whether kernels compile (numba installed and ``NUMBA_DISABLE_JIT`` not set)."""
    return (importlib.util.find_spec("numba") is not None
            and os.environ.get("NUMBA_DISABLE_JIT", "0") in ("", "0"))


def jitable(fn: Callable) -> Callable:
    """Mark ``fn`` as callable from kernels; returns ``fn`` itself."""
    _JITABLE.append(fn)
    return fn


def _activate() -> None:
    """Once per process: register the jitable functions and the kernels' operations
    (:mod:`vehicle.wheelrail.kernel_ops`) with numba. If numba is installed but does not import
    (e.g. built for another numpy), the kernels run as Python, with a warning."""
    if "njit" not in _STATE:
        _STATE["njit"] = None
        if numba_available():
            try:
                import numba
                from numba.extending import register_jitable
            except ImportError as exc:
                warnings.warn(f"numba does not import ({exc}); the contact law runs as Python, "
                              f"many times slower", RuntimeWarning, stacklevel=3)
                return
            for fn in _JITABLE + list(kernel_ops.OPERATIONS):
                register_jitable(fn)
            _STATE["njit"] = numba.njit


def _digest(paths: tuple[str, ...]) -> str:
    digest = hashlib.sha256()
    for path in paths:
        with open(path, "rb") as fh:
            digest.update(fh.read())
    return digest.hexdigest()[:16]


class _Kernel:
    """A function compiled by numba on its first call (see :func:`kernel`)."""

    def __init__(self, fn: Callable, depends: tuple[str, ...]):
        self.py_func = fn
        self._depends = depends
        # the sources as imported: the code numba will compile is the code loaded now
        self._digest = _digest(depends)
        self._call = None
        self.__doc__ = fn.__doc__
        self.__name__ = fn.__name__

    def _compile(self) -> Callable:
        _activate()
        njit = _STATE["njit"]
        if njit is None:
            return self.py_func
        if _digest(self._depends) != self._digest:
            # a source changed since it was imported: the loaded code is not what the files
            # say, so compile it without reading or writing the cache
            return njit(self.py_func)
        self.py_func.__qualname__ = f"{self.py_func.__name__}_{self._digest}"
        try:
            return njit(cache=True)(self.py_func)
        except RuntimeError as exc:  # no writable cache folder anywhere
            warnings.warn(f"the contact kernels cannot be cached ({exc}); they compile in "
                          f"every process (a few seconds)", RuntimeWarning, stacklevel=3)
            return njit(self.py_func)

    def __call__(self, *args):
        call = self._call
        if call is None:
            call = self._call = self._compile()
        return call(*args)


def kernel(*depends: str) -> Callable[[Callable], _Kernel]:
    """Decorator: compile the function with numba on its first call. ``depends``: the source
    files of the jitable functions it calls (its own file included), whose digest names the
    cached machine code."""
    def wrap(fn: Callable) -> _Kernel:
        return _Kernel(fn, tuple(os.path.abspath(p) for p in depends))
    return wrap
