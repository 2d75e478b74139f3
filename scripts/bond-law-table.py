#!/usr/bin/env python3
"""The fitted bond laws of finished runs as one Markdown table.

    python3 scripts/bond-law-table.py RESULTS...

Each RESULTS is a scene's results folder (WORK/SCENE, as `ribbar run SCENE
--work WORK` leaves it); its bond_law.json gives a row: the MC2010 form's
six parameters and fit error, the piecewise-linear law's fit error, and
the fitted τ_max against MC2010's own for the scene's concrete and ribs.
"""

import json
import sys
from pathlib import Path


def row(results: Path) -> str:
    law = json.loads((results / "bond_law.json").read_text())
    fit, piecewise, code = law["mc2010"], law["piecewise_linear"], law["design_code"]
    cells = [
        f"`{results.name}`",
        f"{fit['tau_max'] / 1e6:.2f} MPa",
        f"{fit['s1'] * 1e3:.3f} mm",
        f"{fit['s2'] * 1e3:.3f} mm",
        f"{fit['s3'] * 1e3:.3f} mm",
        f"{fit['alpha']:.2f}",
        f"{fit['tau_f'] / 1e6:.2f} MPa",
        f"{100 * fit['fit_error']:.1f} %",
        f"{100 * piecewise['fit_error']:.1f} % ({piecewise['count']} points)",
        f"{fit['tau_max'] / code['tau_max']:.2f}",
        f"{code['tau_max'] / 1e6:.2f} MPa, s3 = {code['s3'] * 1e3:.2f} mm",
    ]
    return "| " + " | ".join(cells) + " |"


def main(folders: list[str]) -> int:
    if not folders:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    print(
        "| scene | τ_max | s1 | s2 | s3 | α | τ_f | MC2010 fit error "
        "| piecewise fit error | τ_max / (2.5 √f_cm) | MC2010's own law |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for folder in folders:
        path = Path(folder)
        try:
            print(row(path))
        except (OSError, KeyError, ValueError) as e:
            print(f"bond-law-table: {path / 'bond_law.json'}: {e}", file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
