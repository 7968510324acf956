"""The track under the car at a time: the centre line under each wheelset, the rail heights
(cant, ``rail_height_m``, irregularities) and the rails the contact law sees
(:class:`TrackInput`); what the car sets from them before each step: :mod:`.hooks`."""
from __future__ import annotations

import math
from typing import Callable

import numpy as np

from ..irregularities import TrackIrregularity
from ..wheelrail.compiled import kernel
from .path import CarPath

#: half-width [s] of the central difference that gives the rails' rates to the contact law
RAIL_RATE_DT_S = 1e-6


def _four_channels(values: tuple, shape: tuple) -> np.ndarray | None:
    """``values`` as one (4, *shape) array (four arrays shaped like s, or broadcasting to it), or
    None when they are not four or do not broadcast."""
    try:  # the usual case, four arrays shaped like s: one conversion
        v = np.array(values, dtype=float)
        if v.shape == (4,) + shape:
            return v
    except ValueError:  # shapes that differ (e.g. a scalar 0 for a channel)
        pass
    if len(values) != 4:
        return None
    try:
        return np.array([np.broadcast_to(np.asarray(x, dtype=float), shape) for x in values])
    except ValueError:
        return None


@kernel(__file__)
def rails_from(irregularity, z_rail, d):
    """Per wheelset and rail (left, right) the rail's (e, de/dt, zr, dzr/dt) at t, (n, 2, 4),
    from the ``irregularity`` (3, n, 4): (lateral, vertical, cross_level, gauge) under the n
    wheelsets at t - d, t, t + d, and the rail heights ``z_rail`` (3, 2n) of ``rail_height_m``
    at those times. Each rail moves by e_L,R = lateral +- gauge / 2, zr_L,R = z_rail + (vertical
    -+ cross_level / 2) (the signs of :mod:`vehicle.irregularities`); the rates are central
    differences over +-d."""
    n = irregularity.shape[1]
    e, z = np.empty((3, 2 * n)), np.empty((3, 2 * n))
    for k in range(3):
        for i in range(n):
            lateral, vertical, cross, gauge = irregularity[k, i]
            e[k, 2 * i], e[k, 2 * i + 1] = lateral + 0.5 * gauge, lateral - 0.5 * gauge
            z[k, 2 * i] = z_rail[k, 2 * i] + (vertical - 0.5 * cross)
            z[k, 2 * i + 1] = z_rail[k, 2 * i + 1] + (vertical + 0.5 * cross)
    out = np.empty((n, 2, 4))
    for j in range(2 * n):
        out[j // 2, j % 2, 0] = e[1, j]
        out[j // 2, j % 2, 1] = (e[2, j] - e[0, j]) / (2.0 * d)
        out[j // 2, j % 2, 2] = z[1, j]
        out[j // 2, j % 2, 3] = (z[2, j] - z[0, j]) / (2.0 * d)
    return out


class TrackInput:
    """The track a car on ``path`` meets: its geometry where the wheelsets are (with contact
    guidance each at its own offset along the track, :attr:`wheelset_offsets_m`), the rails'
    prescribed heights ``rail_height_m(t) -> (8,)`` and the ``irregularity(s) -> (lateral,
    vertical, cross_level, gauge)`` (each None: none), as documented at
    :class:`~vehicle.car.MetroCar`. ``contact_spacing_m``: the distance of the two contact
    points of a wheelset (the cant's rail heights); ``contact_guidance``: :meth:`rows` adds the
    row under the car centre."""

    def __init__(self, path: CarPath, rail_height_m: Callable[[float], np.ndarray] | None,
                 irregularity: Callable[[np.ndarray], tuple] | None, contact_spacing_m: float,
                 contact_guidance: bool):
        self.path = path
        self.rail_height_m = rail_height_m
        self.irregularity = irregularity
        self._contact_spacing_m = contact_spacing_m
        self._contact_guidance = contact_guidance
        #: contact guidance: each wheelset's offset along the track from s0 + s(t) [m] (the
        #: wheelsets are free longitudinally; their track frames follow them, see
        #: :meth:`.hooks.ContactStepHooks.pre_step`)
        self.wheelset_offsets_m = np.zeros(4)

    def wheelset_s_m(self, t) -> np.ndarray:
        """Arc lengths [m] of the wheelsets at time(s) t: s0 + s(t) (v t at constant speed), plus
        each wheelset's own offset along the track with contact guidance (shaped like s0 + v t)."""
        return self.path.wheelset_s0_m + self.path.distance_m(t) + self.wheelset_offsets_m

    def rows(self, t: float) -> np.ndarray:
        """Track centre line (x, y, heading, cant, curvature, d(cant)/ds) under each wheelset
        at time t: (4, 6), rows as :meth:`~vehicle.guidance.TrackSampler.rows` gives them (with
        contact guidance (5, 6): the last under the car centre, where the drive holds the
        carbody)."""
        s = self.wheelset_s_m(t)
        if self._contact_guidance:
            s = np.append(s, self.path.centre_s_m(t))
        if self.path.sampler is None:
            rows = np.zeros((s.size, 6))
            rows[:, 0] = s
            return rows
        return self.path.sampler.rows(s)

    def contact_rails(self, t: float) -> np.ndarray:
        """(4, 2, 4) per wheelset and rail (left, right) the rail's lateral offset e (+ left),
        de/dt, height offset zr (+ up, normal to the track plane) and dzr/dt at time t (contact
        guidance; the cant is in the track frame, not here): ``rail_height_m`` plus the
        irregularity (:func:`rails_from`), the rates central differences over
        +-:data:`RAIL_RATE_DT_S`."""
        d = RAIL_RATE_DT_S
        times = np.array([t - d, t, t + d])
        if self.rail_height_m is None:
            z = np.zeros((3, 8))
        else:
            z = np.array([self.rail_height_m(float(ti)) for ti in times], dtype=float)
            if z.shape != (3, 8):
                raise ValueError(f"rail_height_m(t) must return shape (8,), got {z.shape[1:]}")
        if self.irregularity is None:
            irr = np.zeros((3, 4, 4))
        else:
            irr = self.irregularity_stacked(times[:, None])
        return rails_from(irr, z, d)

    def irregularity_stacked(self, t) -> np.ndarray:
        """(lateral, vertical, cross_level, gauge) as one array shaped like s = s0 + v t with a
        last axis of 4: (4, 4) under the wheelsets at a time t, (n, 4, 4) for times of shape
        (n, 1)."""
        s = self.wheelset_s_m(t)
        if type(self.irregularity) is TrackIrregularity:  # finite by construction: no checks (a
            # subclass may redefine __call__: it takes the general path)
            return self.irregularity.stacked(s)
        v = _four_channels(tuple(self.irregularity(s)), s.shape)
        if v is None or not np.isfinite(v).all():
            raise ValueError("irregularity(s) must return 4 finite arrays (lateral_m, "
                             "vertical_m, cross_level_m, gauge_m) shaped like s")
        return np.moveaxis(v, 0, -1)

    def irregularity_at(self, t) -> tuple[np.ndarray, ...]:
        """(lateral, vertical, cross_level, gauge), each shaped like s = s0 + v t: (4,) under the
        wheelsets at a time t, (n, 4) for times of shape (n, 1)."""
        return tuple(np.moveaxis(self.irregularity_stacked(t), -1, 0))

    def rail_heights_m(self, t: float, rows=None) -> np.ndarray:
        """(8,) rail heights [m] at time t: cant of the track plus ``rail_height_m`` plus the
        irregularity (kinematic guidance); ``rows``: :meth:`rows` at t, if at hand."""
        if self.rail_height_m is None:
            h = np.zeros(8)
        else:
            h = np.array(self.rail_height_m(t), dtype=float)
            if h.shape != (8,):
                raise ValueError(f"rail_height_m(t) must return shape (8,), got {h.shape}")
        if self.irregularity is not None:
            _, ver, cross, _ = self.irregularity_at(t)
            h[0::2] += ver - 0.5 * cross
            h[1::2] += ver + 0.5 * cross
        if self.path.canted:
            b = self._contact_spacing_m / 2.0
            rows = self.rows(t) if rows is None else rows
            for iw, (_, _, _, cant, _, _) in enumerate(np.asarray(rows)[:4].tolist()):
                if cant != 0.0:
                    dz = b * math.sin(cant)  # track plane rolled by -cant: left down, right up
                    h[2 * iw] -= dz
                    h[2 * iw + 1] += dz
        return h
