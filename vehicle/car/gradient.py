"""The track's gradient (``grade``): a car on a rising or falling line.

The track geometry stays in the horizontal plane (heading, curvature, cant). A gradient is modelled
by tilting gravity instead. Every body's weight (exudyn's ``LoadMassProportional``) gets the
component -g sin(theta) along the track's horizontal tangent t at the car centre and -g cos(theta)
downwards, with tan(theta) = grade (> 0 rising in the running direction). For a constant gradient
this is exact: it is the level track seen in the frame of the inclined one, where the car's
motion, its inertia and its suspension are the same. The car leans back on its traction rods
uphill, and the load shifts to the lower bogie by M g sin(theta) h / L, as it does when it
accelerates at g sin(theta).

Left out:

* the change of gradient over the car's length: the grade is read at the car centre for every
  body;
* the vertical curves' centripetal acceleration v^2 / R_v (0.2 m/s^2 at 70 km/h on
  R_v = 1 700 m, the same on every wheel);
* the vertical alignment as a geometric quantity: the track's heights do not rise, so a
  gradient never appears in a position (the floor heights are relative to the rails either way).

Set before every internal step, only when the grade or the heading has changed (a constant
gradient on a straight costs nothing).
"""
from __future__ import annotations

import math
from typing import Callable

__all__ = ["Gradient"]


class Gradient:
    """The tilted weight of every body of one car (module doc): ``grade(s_m) -> rise over run`` at
    the car centre's arc length."""

    def __init__(self, mbs, grade: Callable[[float], float], gravity_m_per_s2: float):
        self._grade = grade
        self._g = float(gravity_m_per_s2)
        self._loads = [i for i in range(mbs.systemData.NumberOfLoads())
                       if mbs.GetLoad(i)["loadType"] == "MassProportional"]
        self._set = None          # (grade, heading) last set
        #: the grade at the car centre, set last (rise over run)
        self.grade = 0.0

    def grade_at(self, s_centre_m: float) -> float:
        """The grade at the car centre's arc length ``s_centre_m`` (rise over run)."""
        grade = float(self._grade(s_centre_m))
        if not math.isfinite(grade):
            raise ValueError(f"grade at s = {s_centre_m:.3f} m is {grade!r}: expected a finite rise over run")
        return grade

    def along_track_m_per_s2(self, s_centre_m: float) -> float:
        """Gravity's component along the track in the running direction [m/s^2] (uphill < 0) with
        the car centre at ``s_centre_m``."""
        return -self._g * math.sin(math.atan(self.grade_at(s_centre_m)))

    def pre_step(self, mbs, s_centre_m: float, heading_rad: float) -> None:
        """Tilt every body's weight for the grade at ``s_centre_m`` and the track's heading there."""
        grade = self.grade_at(s_centre_m)
        if (grade, heading_rad) == self._set:
            return
        theta = math.atan(grade)
        along, down = -self._g * math.sin(theta), -self._g * math.cos(theta)
        vector = [along * math.cos(heading_rad), along * math.sin(heading_rad), down]
        for load in self._loads:
            mbs.SetLoadParameter(load, "loadVector", vector)
        self._set = (grade, heading_rad)
        self.grade = grade
