"""Extract CONTACT's published reference results into the small CSV files that
``benchmarks/contact_vs_contact.py`` compares pneumorail's contact law with.

CONTACT (E.A.H. Vollebregt and J.J. Kalker, https://github.com/eve70a/CONTACT, Apache-2.0) ships
the output of its own examples as ``examples/*.ref_out``. Two of them are used:

* ``examples/mbench_a22_left.ref_out`` and ``examples/mbench_a22_right.ref_out``: the
  Manchester contact benchmark, case A-2.2 (S1002 wheel on UIC60 1:40 rail, profiles
  ``MBench_S1002_v3.prw`` / ``MBench_UIC60_v3.prr``, the same files pneumorail's default table is
  derived from), wheelset lateral shift 0 : 0.5 : 10 mm with yaw 0 : 1.2 : 24 mrad, vertical force
  10 kN per wheel, V = 2 m/s, mu = 0.30, G = 82 GPa, nu = 0.28 (inputs
  ``examples/mbench_a22_{left,right}.inp``; user guide section "The Manchester wheel-rail
  benchmark"). One row per case and wheel (every case there has one contact patch).
* ``examples/tractcurv.ref_out``: a creep-force curve on a Hertzian ellipse (a/b = 0.5, A =
  0.0008 /mm, FN = 106.7 kN, mu = 0.33, pure longitudinal creepage 1e-5 ... 0.25), cases 1-30:
  Kalker's exact theory with Coulomb friction; cases 61-90: the same creepages with Kalker's
  original FASTSIM (parabolic traction bound, Coulomb friction 0.33, no slope reduction)
  (``examples/tractcurv.inp``, user guide "Calculation of creep force curves").
* ``examples/fastsim.ref_out``, cases 1 and 2: lateral creepage with spin on a Hertzian ellipse
  (semi-axes 8 mm along x, 4 mm across, FN = 82 kN, mu = 0.3, CETA = -0.000625, CPHI =
  0.000625 /mm); case 1 Kalker's exact theory, case 2 FASTSIM (parabolic traction bound), the
  same inputs (``examples/fastsim.inp``).

Every number is copied as CONTACT printed it, in CONTACT's own units and sign conventions
(track frame x forward, y to the right, z down; forces **on the rail**; N, mm, rad, creepages
CKSI/CETA dimensionless, CPHI in 1/mm), with the line of the ``.ref_out`` it came from. The
conversion to pneumorail's frames is done by the comparison, not here.

    python benchmarks/contact_reference.py /path/to/CONTACT     # a checkout (or git dir) of CONTACT

writes ``vehicle/wheelrail/data/contact_mbench_a22.csv`` and
``vehicle/wheelrail/data/contact_hertz_cases.csv``. Files taken from CONTACT commit
``d431cdbd125084c79bd59df83b4ac4c63c570ac9`` (2025-07-23, "update ref_out"; the ref_out header:
"Version: open(win64), $Revision: 2707 $, $Date:: 2025-07-23$").
"""
from __future__ import annotations

import argparse
import csv
import subprocess
from pathlib import Path

DATA = Path(__file__).resolve().parents[1] / "vehicle" / "wheelrail" / "data"
MBENCH_CSV = DATA / "contact_mbench_a22.csv"
HERTZ_CSV = DATA / "contact_hertz_cases.csv"

#: columns of the benchmark file, in CONTACT's names (see the module docstring for units)
MBENCH_COLUMNS = [
    "case", "wheel", "Y_WS", "Z_WS", "ROLL_WS", "YAW_WS", "VX_WS", "VPITCH_WS",
    "FX_TR", "FY_TR", "FZ_TR", "XCP_TR", "YCP_TR", "ZCP_TR", "DELTCP_TR", "YCP_R", "ZCP_R",
    "XCP_W", "YCP_W", "ZCP_W", "VELOC", "CKSI", "CETA", "CPHI", "FN", "FX", "FS", "MN",
    "NCON", "NADH", "NSLIP", "file", "line_ws", "line_forces_tr", "line_patch_forces",
]


def _read(root: Path, rel: str) -> list[str]:
    """A file of the CONTACT checkout ``root`` (a work tree, or a git directory: read at HEAD)."""
    if (root / rel).is_file():
        return (root / rel).read_text().splitlines()
    out = subprocess.run(["git", "--git-dir", str(root), "show", f"HEAD:{rel}"],
                         capture_output=True, text=True, check=True).stdout
    return out.splitlines()


def _values_below(lines, i):
    """The numbers on the first non-empty line after line index i (and its index)."""
    j = i + 1
    while not lines[j].strip():
        j += 1
    return [float(v) for v in lines[j].split()], j


def parse_mbench(lines: list[str], rel: str) -> list[dict]:
    rows, cur = [], None
    for i, line in enumerate(lines):
        s = line.strip()
        if s.startswith("Case "):
            cur = {"case": int(s.split()[1]), "file": rel}
        elif s.startswith("WHEEL-RAIL CONTACT,"):
            cur["wheel"] = "left" if "LEFT" in s else "right"
            if "1 CONTACT PATCH" not in s:
                raise ValueError(f"{rel}:{i + 1}: more than one patch ({s}); not handled")
        elif s.startswith("S_WS") and "PITCH_WS" in s:
            v, j = _values_below(lines, i)
            cur.update(Y_WS=v[1], Z_WS=v[2], ROLL_WS=v[3], YAW_WS=v[4], line_ws=j + 1)
        elif s.startswith("VX_WS"):
            v, _ = _values_below(lines, i)
            cur.update(VX_WS=v[0], VPITCH_WS=v[5])
        elif s.startswith("FX(TR)"):
            v, j = _values_below(lines, i)
            cur.update(FX_TR=v[0], FY_TR=v[1], FZ_TR=v[2], line_forces_tr=j + 1)
        elif s.startswith("XCP(TR)"):
            v, _ = _values_below(lines, i)
            cur.update(XCP_TR=v[0], YCP_TR=v[1], ZCP_TR=v[2], DELTCP_TR=v[3], YCP_R=v[4],
                       ZCP_R=v[5])
        elif s.startswith("XCP(W)"):
            v, _ = _values_below(lines, i)
            cur.update(XCP_W=v[0], YCP_W=v[1], ZCP_W=v[2])
        elif s.startswith("CHI") and "CPHI" in s:
            v, _ = _values_below(lines, i)
            cur.update(VELOC=v[2], CKSI=v[3], CETA=v[4], CPHI=v[5])
        elif s.startswith("FN ") and "FS" in s and "MN" in s:
            v, j = _values_below(lines, i)
            cur.update(FN=v[0], FX=v[1], FS=v[2], MN=v[3], line_patch_forces=j + 1)
        elif s.startswith("NPOT"):
            v, _ = _values_below(lines, i)
            cur.update(NCON=int(v[1]), NADH=int(v[2]), NSLIP=int(v[3]))
            missing = [c for c in MBENCH_COLUMNS if c not in cur]
            if missing:
                raise ValueError(f"{rel}: case {cur['case']} lacks {missing}")
            rows.append(cur)
    return rows


def parse_module3(lines: list[str], rel: str, inp: list[str], cases) -> list[dict]:
    """Module-3 (Hertzian) cases: the creepages CKSI, CETA, CPHI of each case from its line
    ``FN, CKSI, CETA, CPHI`` in the .inp (one per case, in order), FN, FX, FY, MZ from the
    .ref_out."""
    creep = [[float(v) for v in ln.split()[:4]] for ln in inp
             if ln.strip().endswith("FN, CKSI, CETA, CPHI") and not ln.lstrip().startswith("%")]
    rows, case = [], None
    for i, line in enumerate(lines):
        s = line.strip()
        if s.startswith("Case "):
            case = int(s.split()[1])
        elif case in cases and s.startswith("FN ") and "FX" in s and "MZ" in s:
            v, j = _values_below(lines, i)
            _, cksi, ceta, cphi = creep[case - 1]
            rows.append({"example": Path(rel).stem, "case": case, "CKSI": cksi, "CETA": ceta,
                         "CPHI": cphi, "FN": v[0], "FX": v[1], "FY": v[2], "MZ": v[3],
                         "file": rel, "line": j + 1})
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("contact", type=Path, help="CONTACT checkout or git directory")
    a = ap.parse_args(argv)
    rows = []
    for side in ("left", "right"):
        rel = f"examples/mbench_a22_{side}.ref_out"
        rows += parse_mbench(_read(a.contact, rel), rel)
    rows.sort(key=lambda r: (r["case"], r["wheel"]))
    with MBENCH_CSV.open("w", newline="") as f:
        w = csv.DictWriter(f, MBENCH_COLUMNS)
        w.writeheader()
        w.writerows(rows)
    tc = []
    for name, cases in (("tractcurv", [*range(1, 31), *range(61, 91)]), ("fastsim", (1, 2))):
        rel = f"examples/{name}.ref_out"
        tc += parse_module3(_read(a.contact, rel), rel, _read(a.contact, f"examples/{name}.inp"),
                            cases)
    with HERTZ_CSV.open("w", newline="") as f:
        w = csv.DictWriter(f, ["example", "case", "CKSI", "CETA", "CPHI", "FN", "FX", "FY", "MZ",
                               "file", "line"])
        w.writeheader()
        w.writerows(tc)
    print(f"{MBENCH_CSV.name}: {len(rows)} rows; {HERTZ_CSV.name}: {len(tc)} rows")


if __name__ == "__main__":
    main()
