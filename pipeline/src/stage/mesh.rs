//! The mesh stage: gmsh on the geometry stage's `.geo`, then the model.

use super::ctx::Ctx;
use super::kinds::Stage;
use anyhow::Result;
use std::path::Path;

pub fn run(ctx: &Ctx, out: &Path) -> Result<()> {
    let geo = ctx.done_dir(Stage::Geometry).join("specimen.geo");
    let limit = ctx.scene.mesh.timeout;
    let report = ctx.printer.while_running(
        |t| {
            format!(
                "mesh: gmsh has run {:.0} s (it is stopped at mesh.timeout = {limit:.0} s)",
                t.as_secs_f64()
            )
        },
        || {
            mesh::mesh_built_specimen(
                ctx.gmsh,
                &geo,
                &ctx.scene.mesh,
                &ctx.scene.bar,
                &ctx.scene.specimen.geometry,
                out,
            )
        },
    )?;
    let estimate = mesh::estimate::estimated_tets(
        &ctx.scene.bar,
        &ctx.scene.specimen.geometry,
        &ctx.scene.mesh,
    );
    ctx.printer.detail(&format!(
        "mesh: {} nodes, {} steel + {} concrete tets ({estimate:.0} estimated from the size \
         field), {} interface elements, min quality {:.3}",
        report.nodes,
        report.tets_steel,
        report.tets_concrete,
        report.interface_elements_adhesive + report.interface_elements_free,
        report.min_quality
    ));
    if let Some(occ) = &report.occ {
        let worst = occ
            .checks
            .values()
            .map(|c| c.max_rel_diff)
            .fold(0.0, f64::max);
        ctx.printer.detail(&format!(
            "mesh: gmsh built the model in {:.1} s; its volumes and areas within {:.3} % of the geometry's",
            occ.build_seconds,
            100.0 * worst
        ));
    }
    Ok(())
}
