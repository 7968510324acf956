"""The linear critical speed with the contact law's Kalker coefficients scaled, not run as a test.

pneumorail has no key that scales the creep coefficients (``vehicle.params.ContactParams`` holds
friction, normal damping, table smoothing and the table file only), so this patches
:class:`vehicle.wheelrail.contact_law.ContactLawTable` in-process: every row's k11, k22, k23, k33
times ``scale``, then runs ``scenarios/stability.yaml`` at k = 0 (one process, so the patch holds).
docs/validation.md ("Creep forces against CONTACT", "Does it matter") uses it with the scale that
CONTACT's exact theory implies at small creepage (1.015, tractcurv case 1).

    python benchmarks/stability_creep_scale.py 1.015 --out /tmp/stab_1.015    # ~15 s
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from vehicle.wheelrail import contact_law as cl

ROOT = Path(__file__).resolve().parents[1]


def patch(scale: float) -> None:
    original = cl.ContactLawTable.__init__

    def init(self, *args, **kwargs):
        original(self, *args, **kwargs)
        rows = [i for i, n in enumerate(cl.GEOMETRY_COLUMNS) if n[:3] in ("k11", "k22", "k23", "k33")]
        self.values[rows] *= scale
        self.slopes = np.diff(self.values, axis=1) / np.diff(self.y)

    cl.ContactLawTable.__init__ = init


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scale", type=float)
    ap.add_argument("--out", required=True)
    ap.add_argument("--k", default="0")
    a = ap.parse_args(argv)
    patch(a.scale)
    from cosim.cli import main as cli

    return cli(["run", str(ROOT / "scenarios" / "stability.yaml"), "--k", a.k, "--jobs", "1",
                "--overwrite", "--quiet", "--out", a.out])


if __name__ == "__main__":
    sys.exit(main())
