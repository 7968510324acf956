"""Derive the shipped contact tables (``python -m vehicle.wheelrail.derive_table``).

S1002 wheel (Manchester-benchmark v3 profile) on UIC60 rail (benchmark v3 profile, drawn with
its 1:40 inclination), gauge 1435 mm measured 14 mm below the running surface, wheel
back-to-back 1360 mm, tape circle 70 mm from the flange back at the nominal radius (0.46 m for
the default table, the Manchester wheel; ``--nominal-radius-m 0.42`` for the metro car's 840 mm
wheels, ``vehicle.params.VehicleParams.wheel_radius_m``); wheelset lateral displacement
-12 .. +12 mm every 0.1 mm, every 0.01 mm across the contact jumps. Prints the summary numbers quoted in docs/wheel_rail.md.
``--check`` compares with the stored file instead of writing it. The stored files are
:func:`table_path` of their radius (``data/S1002_UIC60_1in40_1435_r460.csv``, ``..._r420.csv``).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from .geometry import COLUMNS, DEFAULT_RAIL, DEFAULT_WHEEL, ContactTable, table_path


def derive_default(nominal_radius_m: float = 0.46, wheel_file=DEFAULT_WHEEL) -> ContactTable:
    """The S1002 / UIC60 1:40 / 1435 mm table for wheels of ``nominal_radius_m`` (tape circle); with
    ``wheel_file`` another wheel profile (a worn one) on the same rail and setup."""
    return ContactTable.from_profiles(wheel_file, DEFAULT_RAIL, gauge_m=1.435,
                                      inclination=1.0 / 40.0, rail_profile_inclined=True,
                                      flange_back_distance_m=1.360, flange_back_pos_mm=-70.0,
                                      nominal_radius_m=nominal_radius_m, tape_circle_y_mm=0.0,
                                      gauge_height_mm=14.0, y_max_mm=12.0, dy_mm=0.1)


def summary(table: ContactTable) -> str:
    lines = []
    y0, y1 = table.y_range_m
    n = table.columns["y_ws_mm"].size
    lines.append(f"table: y = {1e3 * y0:g} .. {1e3 * y1:g} mm, {n} rows "
                 f"({table.meta.get('grid', 'grid of the file')})")
    lines.append(f"centred: r0 = {table.r0:.6f} m, contact half spacing b = "
                 f"{table.contact_half_spacing:.6f} m")
    for j in table.contact_jumps():
        if j["side"] == "L" and j["y_from_mm"] >= 0:
            lines.append("left-wheel contact jump between y = {y_from_mm:.2f} and {y_to_mm:.2f} mm:"
                         " yw {yw_from_mm:.2f} -> {yw_to_mm:.2f} mm, gamma {gamma_from_rad:.4f} ->"
                         " {gamma_to_rad:.4f} rad".format(**j))
    lines.append(f"flange contact (gamma_L > 0.7 rad) from y = "
                 f"{1e3 * table.flange_contact_y():.1f} mm")
    for A in (0.001, 0.002, 0.003, 0.004):
        h = table.equivalent_conicity(A, "harmonic")
        k = table.equivalent_conicity(A, "klingel")
        lines.append(f"equivalent conicity at {1e3 * A:g} mm: harmonic {h:.4f}, "
                     f"Klingel/EN 15302 integration {k:.4f}")
    lam = table.equivalent_conicity(0.003, "harmonic")
    lines.append(f"Klingel wavelength for lambda_e(3 mm) = {lam:.4f}: "
                 f"{table.klingel_wavelength(lam):.2f} m")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="compare with the stored table")
    ap.add_argument("--nominal-radius-m", type=float, default=0.46,
                    help="wheel radius at the tape circle [m] (default 0.46; the metro car: 0.42)")
    ap.add_argument("--out", default=None, help="output CSV path (default: the stored table "
                    "of that radius, data/S1002_UIC60_1in40_1435_r<mm>.csv)")
    args = ap.parse_args(argv)
    stored_path = table_path(args.nominal_radius_m)
    table = derive_default(args.nominal_radius_m)
    if args.check:
        stored = ContactTable.from_csv(stored_path)
        worst = max(float(np.nanmax(np.abs(stored.columns[c] - table.columns[c]))) for c in COLUMNS)
        print(f"max abs difference to the stored table: {worst:.3g}")
        print(summary(table))
        return 0 if worst < 1e-8 else 1
    out = args.out or str(stored_path)
    table.to_csv(out)
    print(f"wrote {out}")
    print(summary(table))
    return 0


if __name__ == "__main__":
    sys.exit(main())
