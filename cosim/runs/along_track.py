"""Figures along the track: the positions of the car and its wheelsets against arc length, with
the track's segments shaded and named (:func:`track_axis`, :func:`track_spans`,
:func:`along_track`), and the wheel-rail figures of a run (:func:`wheel_rail_figures`)."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Dict, List, Sequence, Tuple

import numpy as np
import xarray as xr

from cosim.limits import en14363
from cosim.limits.criteria import (
    SLIDING_MEAN_M,
)
from cosim.results.plots import Figure, Panel, Span
from cosim.results.series import WHEELSETS
from cosim.runs.car import of_setting, per_case
from cosim.runs.track_run import car_centre_s_m
from cosim.runs.track_spec import CurveTest
from cosim.scenario.model import Scenario
from vehicle.params import WHEELS
from vehicle.track import Arc, TrackGeometry


@dataclass(frozen=True)
class TrackAxis:
    """Where a curve run's samples lie along the track: ``centre_m`` the car centre's arc length
    at each sample [m], ``wheelset_x_m`` each wheelset's offset from it (front first), ``spans``
    the track's segments as they are drawn (:func:`track_spans`) and ``outer`` the side of the
    outer rail in the curve (``R`` or ``L``)."""

    centre_m: np.ndarray
    wheelset_x_m: Tuple[float, ...]
    spans: Tuple[Span, ...]
    outer: str

    def wheelset(self, wheelset: str, shift_m: float = 0.0) -> np.ndarray:
        """Arc length [m] of wheelset ``1`` ... ``4`` at each sample, plus ``shift_m``."""
        return self.centre_m + self.wheelset_x_m[WHEELSETS.index(wheelset)] + shift_m

    def wheel(self, wheel: str, shift_m: float = 0.0) -> np.ndarray:
        return self.wheelset(wheel[:-1], shift_m)

    def rail(self, wheel: str) -> str:
        """`` (outer rail)`` / `` (inner rail)`` of a wheel in the curve."""
        return " (outer rail)" if wheel[-1] == self.outer else " (inner rail)"

    @property
    def outer_text(self) -> str:
        side = "right" if self.outer == "R" else "left"
        return f"outer rail {side} (wheels 1{self.outer}-4{self.outer})"


def track_axis(scenario: Scenario, t_s: np.ndarray) -> TrackAxis:
    """The :class:`TrackAxis` of a curve run sampled at ``t_s``."""
    curve = scenario.experiment
    return TrackAxis(car_centre_s_m(scenario, t_s), tuple(scenario.vehicle.wheelset_x_m), track_spans(curve.track()),
                     "R" if curve.direction > 0 else "L")


def track_spans(track: TrackGeometry) -> Tuple[Span, ...]:
    """The track's segments as spans of a position axis: straights unshaded, transitions and arcs
    shaded, each named with its EN 14363 test zone (:func:`cosim.limits.en14363.zone_table`)."""
    starts, zones, _ = en14363.zone_table(track)
    ends = [*starts[1:], track.total_length_m]
    spans = []
    for seg, zone, a, b in zip(track.segments, zones, starts, ends):
        if isinstance(seg, Arc):
            spans.append(Span(a, b, f"arc R = {seg.radius_m:g} m (zone {zone})"))
        else:
            spans.append(Span(a, b, zone, shade=zone != "straight"))
    return tuple(spans)


def along_track(figure: Figure, positions: Sequence[np.ndarray], spans: Sequence[Sequence[Span]], where: str,
                note: str = "") -> List[Figure]:
    """``figure`` (panels against time) and its twin along the track: each panel's curves against
    the arc length of what they belong to (``positions``, one per panel: the car centre, a wheel
    at its 2 m window's centre ...), with its track's segments and zones marked (``spans``, one
    list per panel); ``where`` names the position in the axis label, ``note`` is added to the
    title (e.g. which rail is outer)."""
    panels = [dataclasses.replace(p, curves=[dataclasses.replace(c, x=s) for c in p.curves],
                                  xlabel=f"position along the track s [m] ({where})", spans=list(marks))
              for p, s, marks in zip(figure.panels, positions, spans)]
    title = f"{figure.title}, along the track" + (f"; {note}" if note else "")
    return [figure, dataclasses.replace(figure, name=figure.name.replace(".png", "_along_track.png"), panels=panels,
                                        title=title)]


def wheel_rail_figures(ds: xr.Dataset, curve: CurveTest, rows: List[Dict[str, object]],
                       axis: TrackAxis) -> List[Figure]:
    """Contact guidance, per valve setting: Y/Q (2 m sliding mean) per wheel across k with Nadal's
    limit, ΔQ/Q0 per wheel across k, ΣY (2 m sliding mean) per wheelset with Prud'homme's limit;
    each against time and along the track (a 2 m mean at its window's centre: 1 m behind the
    wheel), every wheel's panel naming its rail in the curve."""
    yq_lim, sum_y_lim = rows[0]["yq_lim"], rows[0]["sum_y_lim_N"]
    nadal = [(yq_lim, f"Nadal limit {yq_lim:.2f} ({curve.nadal_flange_angle_deg:g}°, μ = {curve.nadal_friction:g})")]
    prud = [(sign * sum_y_lim * 1e-3, f"{'+' if sign > 0 else '-'}Prud'homme limit {sum_y_lim * 1e-3:.1f} kN")
            for sign in (1.0, -1.0)]
    centre = -0.5 * SLIDING_MEAN_M                        # a trailing 2 m mean belongs to its window's centre
    out = []
    for valves in curve.valve_settings:
        sub = of_setting(ds, valves)
        tag = "on" if valves else "off"
        yq = [Panel(per_case(sub["y_over_q_2m"].sel(wheel=w)), "time t [s]", f"(Y/Q)_2m, wheel {w}",
                    f"wheel {w}{axis.rail(w)}", hlines=nadal) for w in WHEELS]
        out += along_track(Figure(f"wheel_yq_valves={tag}.png", yq,
                                  f"Y/Q per wheel, {SLIDING_MEAN_M:g} m sliding mean (EN 14363), valves {tag}", 2),
                           [axis.wheel(w, centre) for w in WHEELS], [axis.spans] * len(WHEELS),
                           "the wheel's 2 m window centre", axis.outer_text)
        dqq = [Panel(per_case(sub["dqq"].sel(wheel=w)), "time t [s]", f"ΔQ/Q0, wheel {w}", f"wheel {w}{axis.rail(w)}")
               for w in WHEELS]
        out += along_track(Figure(f"wheel_dqq_valves={tag}.png", dqq, f"Wheel unloading ΔQ/Q0 per wheel, valves {tag}",
                                  2), [axis.wheel(w) for w in WHEELS], [axis.spans] * len(WHEELS), "the wheel",
                           axis.outer_text)
        sum_y = [Panel(per_case(sub["sum_y_2m_N"].sel(wheelset=ws), 1e-3), "time t [s]", "(ΣY)_2m [kN]",
                       f"wheelset {ws}", hlines=prud) for ws in WHEELSETS]
        out += along_track(Figure(f"wheelset_sum_y_valves={tag}.png", sum_y,
                                  f"ΣY per wheelset (+ left), {SLIDING_MEAN_M:g} m sliding mean, valves {tag}", 2),
                           [axis.wheelset(ws, centre) for ws in WHEELSETS], [axis.spans] * len(WHEELSETS),
                           "the wheelset's 2 m window centre", axis.outer_text)
    return out
