"""Wheel and rail profile files: the SIMPACK ``.prw`` / ``.prr`` format and plain 2-column tables.

Canonical form
--------------
Every reader returns a :class:`Profile` in one canonical form (the one CONTACT uses internally,
CONTACT user guide, section "Inputs regarding wheel and rail profiles"):

* lengths in **mm**;
* ``y`` lateral, **positive towards the field side** (a "right-side" profile: the flange of a
  wheel and the gauge face of a rail are at the negative-``y`` end);
* ``z`` vertical, **positive downwards** (rail material is at ``z > 0`` below its running
  surface, the wheel flange tip has the largest ``z`` of a wheel);
* rail points ordered by ascending ``y`` (track centre -> field side), wheel points by descending
  ``y`` (so that, walking along the points, the material is on the right-hand side).

The wheel-profile origin is the profile's own datum: for the Manchester-benchmark S1002 file it is
the tape circle (nominal rolling circle), 70 mm from the flange back; the rail-profile origin is
whatever the file uses (for the benchmark UIC60 file: near the crown; the profile is *already
inclined* 1:40, see ``data/README.md``).

SIMPACK ``.prw`` / ``.prr`` files
---------------------------------
Plain text. ``!`` starts a comment (a whole commented-out line is ignored, including commented
points). ``header.begin .. header.end`` holds ``type`` (0 rail, 1 wheel). ``spline.begin ..
spline.end`` holds processing options, ``key = value ! comment``, applied by SIMPACK to the raw
points in this order (numbers as in the file's comments):

1. ``point.dist.min`` (minimum point distance) -- only 0 is supported here;
2. ``shift.y`` / ``shift.z`` -- added to the raw coordinates;
3. ``rotate`` -- rotation about x; only 0 is supported here (the sign convention is not stated
   in the file, so a non-zero value is refused rather than guessed);
4. ``bound.y.min/max``, ``bound.z.min/max`` -- clipping, active only when min < max;
5. ``mirror.y`` / ``mirror.z`` -- 1 negates that coordinate;
6. ``inversion`` -- 1 reverses the point order;
7. ``units.len.f`` -- length unit factor l[user]/l[m] (1000: the points are in mm);
   ``units.ang.f`` likewise for angles.

``point.begin .. point.end`` holds the points, one per line: ``y z [weight]`` in the file's length
unit (whitespace separated; the weight column is ignored).

After the file's own options the profile is brought to the canonical form above (converted to mm,
reordered); a profile whose side faces point the wrong way for its kind is refused.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pneumorail.errors import InputError
from pneumorail.files import PROFILE_MAX_BYTES, read_text

__all__ = ["Profile", "read_profile", "read_simpack_profile", "write_simpack_profile"]


@dataclass(frozen=True)
class Profile:
    """A wheel or rail profile in canonical form (mm, y to the field side, z downwards)."""

    kind: str  # "wheel" or "rail"
    y_mm: np.ndarray
    z_mm: np.ndarray
    source: str = ""
    comment: str = ""
    # points exactly as listed in the file (file units, file order), for round-trip checks
    raw_yz: np.ndarray | None = field(default=None, repr=False)
    options: dict = field(default_factory=dict, repr=False)

    def __post_init__(self):
        if self.kind not in ("wheel", "rail"):
            raise ValueError(f"profile kind must be 'wheel' or 'rail', not {self.kind!r}")
        y = np.asarray(self.y_mm, dtype=float)
        z = np.asarray(self.z_mm, dtype=float)
        if y.shape != z.shape or y.ndim != 1 or y.size < 4:
            raise ValueError("a profile needs at least 4 (y, z) points of equal count")
        if not (np.all(np.isfinite(y)) and np.all(np.isfinite(z))):
            raise ValueError("profile coordinates must be finite")
        object.__setattr__(self, "y_mm", y)
        object.__setattr__(self, "z_mm", z)


_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eEdD][-+]?\d+)?"


def _parse_value(text: str):
    text = text.strip()
    if text.startswith("'") or text.startswith('"'):
        return text.strip("'\"")
    try:
        return float(text.replace("d", "e").replace("D", "e"))
    except ValueError:
        return text


def read_simpack_profile(path: str | Path) -> Profile:
    """Read a SIMPACK ``.prw`` (wheel) or ``.prr`` (rail) profile into canonical form."""
    path = Path(path)
    header: dict = {}
    options: dict = {}
    raw: list[tuple[float, float]] = []
    section = None
    # SIMPACK writes its files from Windows tools: Latin-1 where they are not UTF-8
    text = read_text(path, "SIMPACK profile", PROFILE_MAX_BYTES, encodings=("utf-8", "latin-1"))
    for lineno, line in text.lines():
        stripped = line.strip()
        if not stripped or stripped.startswith("!"):
            continue
        # strip trailing comments, but not inside a quoted string
        m = re.match(r"^((?:[^'!]|'[^']*')*)", stripped)
        body = m.group(1).strip() if m else stripped
        low = body.lower()
        if low in ("header.begin", "spline.begin", "point.begin"):
            section = low.split(".")[0]
            continue
        if low in ("header.end", "spline.end", "point.end"):
            section = None if low != "point.end" else "spline"
            continue
        if section == "point":
            nums = re.findall(_NUM, body)
            if len(nums) < 2:
                raise InputError(path, [f"line {lineno}"], f"expected 'y z [weight]', got {line!r}")
            raw.append((float(nums[0]), float(nums[1])))
            continue
        if "=" in body and section in ("header", "spline"):
            key, _, value = body.partition("=")
            (header if section == "header" else options)[key.strip().lower()] = _parse_value(value)
    if not raw:
        raise ValueError(f"{path}: no points between point.begin and point.end")
    ptype = int(header.get("type", -1))
    if ptype not in (0, 1):
        # fall back on the extension
        ptype = {".prr": 0, ".prw": 1}.get(path.suffix.lower(), -1)
    if ptype not in (0, 1):
        raise ValueError(f"{path}: header 'type' must be 0 (rail) or 1 (wheel)")
    kind = "wheel" if ptype == 1 else "rail"

    raw_arr = np.array(raw, dtype=float)
    y, z = raw_arr[:, 0].copy(), raw_arr[:, 1].copy()
    if float(options.get("point.dist.min", 0.0)) != 0.0:
        raise ValueError(f"{path}: point.dist.min != 0 is not supported")
    y += float(options.get("shift.y", 0.0))
    z += float(options.get("shift.z", 0.0))
    if float(options.get("rotate", 0.0)) != 0.0:
        raise ValueError(f"{path}: 'rotate' != 0 is not supported (sign convention not stated)")
    for ax, arr in (("y", y), ("z", z)):
        lo = float(options.get(f"bound.{ax}.min", 1.0))
        hi = float(options.get(f"bound.{ax}.max", 0.0))
        if lo < hi:
            keep = (arr >= lo) & (arr <= hi)
            y, z = y[keep], z[keep]
    if int(options.get("mirror.y", 0)) == 1:
        y = -y
    if int(options.get("mirror.z", 0)) == 1:
        z = -z
    if int(options.get("inversion", 0)) == 1:
        y, z = y[::-1], z[::-1]
    unit_per_m = float(options.get("units.len.f", 1000.0))
    if not unit_per_m > 0:
        raise ValueError(f"{path}: units.len.f must be positive")
    to_mm = 1000.0 / unit_per_m
    y, z = y * to_mm, z * to_mm
    y, z = _canonical_order(kind, y, z)
    _check_length(kind, y, z, str(path))
    _check_orientation(kind, y, z, str(path))
    return Profile(kind=kind, y_mm=y, z_mm=z, source=str(path),
                   comment=str(options.get("comment", "")), raw_yz=raw_arr, options=options)


def _canonical_order(kind: str, y: np.ndarray, z: np.ndarray):
    # rail: ascending y; wheel: descending y (CONTACT's canonical order)
    ascending = y[-1] > y[0]
    if (kind == "rail") != ascending:
        y, z = y[::-1], z[::-1]
    return y, z


#: A profile's length along its points [mm]: CONTACT accepts 5-500 mm; the shipped S1002 wheel is
#: 149 mm, the UIC60 rail 132 mm. A profile written in metres is 1000 times shorter (0.15 "mm").
PROFILE_LENGTH_MM = (5.0, 500.0)


def _check_length(kind: str, y: np.ndarray, z: np.ndarray, name: str):
    """Refuse a profile whose length is no wheel's or rail's (:data:`PROFILE_LENGTH_MM`), naming
    the unit it was likely written in."""
    length = float(np.sum(np.hypot(np.diff(y), np.diff(z))))
    lo, hi = PROFILE_LENGTH_MM
    if lo <= length <= hi:
        return
    likely = ("the points look like metres: multiply them by 1000 (or set units.len.f = 1 in a SIMPACK file)"
              if lo <= 1000 * length <= hi else "not a wheel or rail profile in mm")
    raise InputError(name, [], f"the {kind} profile is {length:.3g} mm long; a wheel or rail profile is "
                               f"{lo:g}-{hi:g} mm: {likely}")


def _check_orientation(kind: str, y: np.ndarray, z: np.ndarray, name: str):
    """Refuse profiles that are not in the canonical orientation (z down, flange/gauge at -y)."""
    if kind == "rail":
        # the running surface is the topmost (min z) part; the side faces run downwards (z > top)
        top = np.argmin(z)
        if not (z[0] > z[top] + 1.0 and z[-1] > z[top] + 1.0):
            raise ValueError(f"{name}: rail profile does not look like z-downwards "
                             "(both ends should lie below the running surface)")
    else:
        # the flange tip (max z) must be on the track-centre side (negative y of the datum)
        tip = np.argmax(z)
        if not y[tip] < 0.5 * (y.min() + y.max()):
            raise ValueError(f"{name}: wheel flange is not on the negative-y side; the profile "
                             "is not in canonical form (mirror y?)")


def read_profile(path: str | Path, kind: str | None = None) -> Profile:
    """Read a profile: SIMPACK ``.prw``/``.prr``, otherwise a 2-column ``y z`` table in mm that is
    already in canonical form (comma or whitespace separated, ``#`` comments); ``kind`` is then
    required unless the extension says it."""
    path = Path(path)
    if path.suffix.lower() in (".prw", ".prr"):
        prof = read_simpack_profile(path)
        if kind is not None and kind != prof.kind:
            raise ValueError(f"{path}: file says {prof.kind!r}, caller expected {kind!r}")
        return prof
    if kind is None:
        raise ValueError(f"{path}: give kind='wheel' or 'rail' for a plain table")
    text = read_text(path, f"{kind} profile (y z table in mm)", PROFILE_MAX_BYTES)
    try:
        data = np.loadtxt(text.text.splitlines(), comments="#",
                          delimiter=None if path.suffix.lower() != ".csv" else ",", ndmin=2)
    except ValueError as exc:
        raise InputError(path, [], f"not a table of 'y z' numbers in mm ({exc})") from None
    if data.shape[1] < 2 or data.shape[0] < 4 or not np.all(np.isfinite(data[:, :2])):
        raise InputError(path, [], f"expected at least 4 finite 'y z' points in mm, got {data.shape[0]} rows of "
                                   f"{data.shape[1]} column(s)")
    y, z = _canonical_order(kind, data[:, 0].astype(float), data[:, 1].astype(float))
    _check_length(kind, y, z, str(path))
    _check_orientation(kind, y, z, str(path))
    return Profile(kind=kind, y_mm=y, z_mm=z, source=str(path), raw_yz=data[:, :2].copy())


def write_simpack_profile(profile: Profile, path: str | Path, comment: str = "") -> None:
    """Write a canonical profile as a SIMPACK file (mm, no shift/mirror/inversion) that
    :func:`read_simpack_profile` reads back to the same canonical points (17 significant digits)."""
    path = Path(path)
    ptype = 1 if profile.kind == "wheel" else 0
    lines = [
        "! written by vehicle.wheelrail.profiles.write_simpack_profile",
        "  header.begin",
        "    version       =  1",
        f"    type          =  {ptype}                       ! 0=rail profile, 1=wheel profile",
        "  header.end",
        "  spline.begin",
        f"    comment        = '{comment or profile.comment}'",
        "    mirror.y       =  0",
        "    mirror.z       =  0",
        "    inversion      =  0",
        "    units.len.f    = +1.000000000000000e+03   ! points in mm",
        "    units.ang.f    = +1.000000000000000e+00",
        "    point.begin",
    ]
    lines += [f"{y:.17g}\t{z:.17g}" for y, z in zip(profile.y_mm, profile.z_mm)]
    lines += ["    point.end", "  spline.end", ""]
    path.write_text("\n".join(lines), encoding="ascii")


def profile_length_mm(profile: Profile) -> float:
    """Summed chord length of the profile (CONTACT requires 5..500 mm; a unit check, made on
    reading: :data:`PROFILE_LENGTH_MM`)."""
    return float(np.sum(np.hypot(np.diff(profile.y_mm), np.diff(profile.z_mm))))
