"""Write the tables of the effects beyond the paper into hsgran/data:

- ``tangential_compliance.npz`` (hsgran.contact.compliance): χ = φ/min(q, 1) of the dimensionless
  Hertz–Mindlin oblique impact, integrated by hsgran.dem.mindlin on the nodes that
  hsgran.contact.compliance defines (about 45 s on one core);
- ``derived_viscoelastic_restitution.csv`` (hsgran.contact.viscous): e_n of the dimensionless
  viscoelastic Hertz contact, integrated by hsgran.dem.viscoelastic (a few seconds).

    .venv/bin/python tools/make_tables.py [--only compliance|viscous] [--out-dir DIR]

The files are shipped; run this only when the nodes or the integrations change
(tests/contact/test_compliance.py and test_viscous.py compare the shipped tables with fresh
integrations).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from hsgran.contact import compliance, viscous
from hsgran.dem import mindlin, viscoelastic

DATA = Path(__file__).resolve().parents[1] / "hsgran" / "data"


def write_compliance(out_dir: Path) -> None:
    t = time.process_time()
    chi = mindlin.table(compliance.R_NODES, compliance.KAPPA_NODES, compliance.E_NODES)
    path = out_dir / compliance.TABLE_FILE
    np.savez_compressed(path, r=compliance.R_NODES, kappa=compliance.KAPPA_NODES,
                        e_n=compliance.E_NODES, chi=chi.astype(np.float32),
                        steps=np.float64(mindlin.TABLE_STEPS))
    print(f"wrote {path}: chi {chi.shape} in [{chi.min():.4f}, {chi.max():.4f}], "
          f"{time.process_time() - t:.1f} s CPU")


def write_viscous(out_dir: Path) -> None:
    t = time.process_time()
    u = viscous.SQRT_X_NODES
    e = viscoelastic.table(u * u)
    path = out_dir / viscous.TABLE_FILE
    with open(path, "w", encoding="utf-8") as f:
        f.write("sqrt_X,X,e_n\n")
        for uk, ek in zip(u, e, strict=True):
            f.write(f"{uk:.6f},{uk * uk:.8g},{ek:.12f}\n")
    print(f"wrote {path}: {u.size} rows, e_n from {e[0]:.6f} to {e[-1]:.3g}, "
          f"{time.process_time() - t:.1f} s CPU")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", choices=("compliance", "viscous"), help="write one table only")
    ap.add_argument("--out-dir", type=Path, default=DATA, help="default: hsgran/data")
    args = ap.parse_args(argv)
    if args.only in (None, "compliance"):
        write_compliance(args.out_dir)
    if args.only in (None, "viscous"):
        write_viscous(args.out_dir)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
