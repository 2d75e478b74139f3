//! Runs the topology checks of the test suite on a written model:
//! `cargo run --release -p mesh --example check_model -- WORK/scene/model.bin`

#[path = "../tests/common/mod.rs"]
mod common;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .ok_or("usage: check_model MODEL.bin")?;
    let t = std::time::Instant::now();
    let model = mesh::Model::load(std::path::Path::new(&path))?;
    println!(
        "loaded {} nodes, {} tets in {:.3} s",
        model.nodes.len(),
        model.tets.len(),
        t.elapsed().as_secs_f64()
    );
    common::check_topology(&model);
    println!(
        "topology checks passed: {} interface elements",
        model.interfaces.len()
    );
    Ok(())
}
