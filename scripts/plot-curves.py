#!/usr/bin/env python3
"""Overlay the bond stress-slip curves of several runs (curve.csv files:
columns fed and bond_stress, SI) in one PNG.

    python3 scripts/plot-curves.py OUT.png LABEL=PATH/curve.csv [LABEL=...]
        [--fed-max MM]

Needs matplotlib (`pip install matplotlib`)."""
import argparse
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read_curve(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows or "fed" not in rows[0] or "bond_stress" not in rows[0]:
        sys.exit(f"error: {path}: not a curve.csv (needs columns fed, bond_stress)")
    return (
        [float(r["fed"]) * 1e3 for r in rows],
        [float(r["bond_stress"]) / 1e6 for r in rows],
    )


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out")
    parser.add_argument("curves", nargs="+", metavar="LABEL=CSV")
    parser.add_argument("--fed-max", type=float, default=None, metavar="MM")
    args = parser.parse_args()
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for item in args.curves:
        label, sep, path = item.partition("=")
        if not sep:
            sys.exit(f"error: {item}: expected LABEL=PATH")
        fed, bond = read_curve(path)
        ax.plot(fed, bond, label=label, lw=1.4)
    ax.set_xlabel("free-end displacement (mm)")
    ax.set_ylabel("mean bond stress σ_mb (MPa)")
    if args.fed_max is not None:
        ax.set_xlim(0.0, args.fed_max)
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.out, dpi=130)


if __name__ == "__main__":
    main()
