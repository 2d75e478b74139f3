//! The mesh stage: gmsh on the geometry stage's `.geo`, then the model.

use super::ctx::Ctx;
use super::kinds::Stage;
use anyhow::Result;
use std::path::Path;

pub fn run(ctx: &Ctx, out: &Path) -> Result<()> {
    let geo = ctx.done_dir(Stage::Geometry).join("specimen.geo");
    let report = mesh::mesh_built_specimen(
        ctx.gmsh,
        &geo,
        &ctx.scene.mesh,
        &ctx.scene.bar,
        &ctx.scene.specimen.geometry,
        out,
    )?;
    ctx.printer.detail(&format!(
        "mesh: {} nodes, {} steel + {} concrete tets, {} interface elements, min quality {:.3}",
        report.nodes,
        report.tets_steel,
        report.tets_concrete,
        report.interface_elements_adhesive + report.interface_elements_free,
        report.min_quality
    ));
    Ok(())
}
