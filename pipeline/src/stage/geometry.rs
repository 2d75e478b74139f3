//! The geometry stage: the specimen's `.geo` and its measured report
//! (analytic and parry3d; gmsh's model is measured by the mesh stage).

use super::ctx::Ctx;
use anyhow::Result;
use std::path::Path;

pub fn run(ctx: &Ctx, out: &Path) -> Result<()> {
    let report = geom::build_geometry(&ctx.scene.bar, &ctx.scene.specimen.geometry, out)?;
    ctx.printer.detail(&format!(
        "geometry: f_R = {:.4}, rib volume {:.3e} m³, adhesive interface {:.4e} m²",
        report.f_r, report.rib_volume_m3, report.interface_area_adhesive_m2
    ));
    Ok(())
}
