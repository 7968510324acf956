"""The math operations of the contact law as plain functions of floats: the ``ops`` the
kernels of :mod:`vehicle.wheelrail.compiled` pass to the law (this module itself, whose
functions numba compiles; a module passed as an argument costs nothing at run time and keeps
the kernels cacheable). Same operations as :data:`vehicle.wheelrail.compiled.PYTHON`."""

import math


def sqrt(x):
    return math.sqrt(x)


def sin(x):
    return math.sin(x)


def cos(x):
    return math.cos(x)


def atan2(y, x):
    return math.atan2(y, x)


def pow(x, e):  # noqa: A001 (the law's name for it)
    return math.pow(x, e)


def where(cond, a, b):
    """a if cond else b (both evaluated)."""
    return a if cond else b


def max(a, b):  # noqa: A001
    return a if a >= b else b


def min(a, b):  # noqa: A001
    return a if a <= b else b


def const(x):
    return float(x)


OPERATIONS = (sqrt, sin, cos, atan2, pow, where, max, min, const)
