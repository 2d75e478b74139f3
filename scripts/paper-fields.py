#!/usr/bin/env python3
"""Field checks and section pictures of a ribbed scene (paper Figs. 18-19).

    python3 scripts/paper-fields.py WORK/SCENE [--which end|peak] [--out DIR]

Reads SCENE/fields/<which>_bulk.vtu and <which>_interface.vtu written by
`ribbar solve` (outputs.fields at_peak / at_end) and prints, as JSON:
the share of the adhesive interface area with D_int > 0.99; the fully
damaged concrete (D > 0.99) per rib pitch along the bonded length; where
the concrete in triaxial tension and in triaxial compression lies (radius
from the axis, against the bar radius and the rib height); the volume of
damaged concrete and the mean element size in it. Writes
section-<which>.png: the concrete within a thin slab about the plane y = 0
(the paper's section A-A), coloured by D, and the three flags of Fig. 18
(c)-(e). Needs numpy, meshio and matplotlib.
"""
import argparse
import json
import pathlib

import meshio
import numpy as np


def triangle_areas(points, tris):
    a, b, c = (points[tris[:, k]] for k in range(3))
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)


def tet_volumes(points, tets):
    a, b, c, d = (points[tets[:, k]] for k in range(4))
    return np.abs(np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a))) / 6.0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scene_dir", type=pathlib.Path)
    ap.add_argument("--which", default="end", choices=["end", "peak"])
    ap.add_argument("--out", type=pathlib.Path, default=None)
    ap.add_argument("--slab", type=float, default=0.6e-3, help="half-thickness of the section slab, m")
    args = ap.parse_args()
    d = args.scene_dir
    out = args.out or d / "plots"
    out.mkdir(parents=True, exist_ok=True)
    spec = json.loads((d / "geometry.json").read_text())
    bar = spec["bar"]
    radius = bar["diameter"] / 2.0
    ribs = (bar.get("ribs") or {}).get("transverse") or {}
    rib_height = ribs.get("height", 0.0)
    pitch = ribs.get("spacing")

    iface = meshio.read(d / "fields" / f"{args.which}_interface.vtu")
    tris = iface.cells_dict["triangle"]
    area = triangle_areas(iface.points, tris)
    dint = np.asarray(iface.cell_data["D_int"][0]).ravel()
    zc_if = iface.points[tris].mean(axis=1)[:, 2]
    bonded = (zc_if.min(), zc_if.max())

    bulk = meshio.read(d / "fields" / f"{args.which}_bulk.vtu")
    tets = bulk.cells_dict["tetra"]
    cd = {k: np.asarray(v[0]) for k, v in bulk.cell_data.items()}
    concrete = cd["region"].ravel() == 1
    cent = bulk.points[tets].mean(axis=1)
    r = np.hypot(cent[:, 0], cent[:, 1])
    damage = cd["D"].ravel()
    full = (cd["D_above_0.99"].ravel() > 0) & concrete
    tension = (cd["all_tensile"].ravel() > 0) & concrete
    compression = (cd["all_compressive"].ravel() > 0) & concrete

    report = {
        "which": args.which,
        "interface_area_share_D_above_0.99": float(area[dint > 0.99].sum() / area.sum()),
        "bonded_z_m": [float(bonded[0]), float(bonded[1])],
        "concrete_tets": int(concrete.sum()),
        "concrete_tets_D_above_0.99": int(full.sum()),
        "triaxial_tension_tets": int(tension.sum()),
        "triaxial_compression_tets": int(compression.sum()),
    }
    # The damaged concrete's volume, against the size l each tet's
    # regularisation takes (the edge of the regular tet of its volume): a
    # crack band one element wide shrinks with l, a diffuse zone does not.
    volume = tet_volumes(bulk.points, tets)
    for threshold in (0.5, 0.9, 0.99):
        sel = concrete & (damage > threshold)
        report[f"concrete_volume_D_above_{threshold}_m3"] = float(volume[sel].sum())
    sel = concrete & (damage > 0.5)
    report["mean_size_l_D_above_0.5_m"] = (
        float(np.mean((6.0 * np.sqrt(2.0) * volume[sel]) ** (1.0 / 3.0))) if sel.any() else None
    )

    def radial(mask):
        if not mask.any():
            return None
        q = np.percentile(r[mask], [10, 50, 90])
        return {"r_over_bar_radius_p10_p50_p90": [round(float(x / radius), 3) for x in q],
                "share_within_one_rib_height_of_the_bar":
                    float(np.mean(r[mask] <= radius + 1.5 * rib_height)) if rib_height else None}

    report["fully_damaged_radius"] = radial(full)
    report["triaxial_tension_radius"] = radial(tension)
    report["triaxial_compression_radius"] = radial(compression)
    if pitch:
        edges = np.arange(bonded[0], bonded[1] + 0.5 * pitch, pitch)
        counts, _ = np.histogram(cent[full, 2], bins=edges)
        report["fully_damaged_tets_per_rib_pitch"] = counts.tolist()
        report["rib_pitches_with_full_damage"] = f"{int((counts > 0).sum())} of {len(counts)}"
    print(json.dumps(report, indent=1))

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    near = concrete & (np.abs(cent[:, 1]) < args.slab) & (r < radius + 8e-3)
    near &= (cent[:, 2] > bonded[0] - 3e-3) & (cent[:, 2] < bonded[1] + 3e-3)
    fig, axes = plt.subplots(1, 4, figsize=(15, 6), sharey=True)
    x_mm, z_mm = cent[near, 0] * 1e3, cent[near, 2] * 1e3
    sc = axes[0].scatter(x_mm, z_mm, c=damage[near], s=2, cmap="viridis", vmin=0, vmax=1)
    fig.colorbar(sc, ax=axes[0], label="D")
    axes[0].set_title("damage D")
    for ax, mask, colour, title in [
        (axes[1], full, "red", "D > 0.99"),
        (axes[2], tension, "blue", "triaxial tension"),
        (axes[3], compression, "green", "triaxial compression"),
    ]:
        ax.scatter(x_mm, z_mm, c="lightgrey", s=1)
        sel = near & mask
        ax.scatter(cent[sel, 0] * 1e3, cent[sel, 2] * 1e3, c=colour, s=3)
        ax.set_title(title)
    for ax in axes:
        ax.axvline(-radius * 1e3, color="k", lw=0.5)
        ax.axvline(radius * 1e3, color="k", lw=0.5)
        ax.set_xlabel("x (mm), section y = 0")
    axes[0].set_ylabel("z (mm)")
    fig.suptitle(f"{d.name}: concrete near the bar at the {args.which} (tet centroids within "
                 f"{args.slab * 1e3:.1f} mm of y = 0)")
    fig.tight_layout()
    path = out / f"section-{args.which}.png"
    fig.savefig(path, dpi=110)
    print(f"picture: {path}")


if __name__ == "__main__":
    main()
