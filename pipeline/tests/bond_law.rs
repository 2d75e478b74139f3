//! The post stage's bond laws on a real run of a tiny ribbed scene:
//! bond_law.json, summary.json's design code, the MC2010 curves on the
//! bond–slip plot, and the design-code options that rerun post alone.

use crate::common::repo;
use std::path::Path;
use std::process::{Command, Stdio};

fn run(work: &Path, sets: &[&str]) -> String {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_ribbar"));
    cmd.args([
        "run",
        "tests/data/tiny-ribbed.yaml",
        "--work",
        work.to_str().unwrap(),
    ]);
    for s in ["loading.u_final=0.1 mm", "outputs.plots=[svg]"]
        .iter()
        .chain(sets)
    {
        cmd.args(["--set", s]);
    }
    let o = cmd
        .current_dir(repo())
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let text = crate::common::text(&o);
    assert!(o.status.success(), "{text}");
    text
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(
        &std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())),
    )
    .unwrap()
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a / b - 1.0).abs() < rel
}

/// Every run publishes bond_law.json with the fitted MC2010 law (six
/// parameters inside their bounds, its error), the piecewise law of the
/// stated points and MC2010's own law for the scene (f_cm derived from f_t
/// and said so, τ_max = 2.5 √f_cm, s3 the clear rib spacing); summary.json
/// repeats them with τ_max / (2.5 √f_cm); the bond–slip plot draws both
/// MC2010 curves. `fcm` and `bond_conditions` then rerun post alone.
#[test]
fn every_run_has_its_bond_laws_and_the_design_codes() {
    let work = std::env::temp_dir().join(format!("ribbar-bond-law-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&work);
    run(&work, &[]);
    let dir = work.join("tiny-ribbed");
    let law = json(&dir.join("bond_law.json"));
    let fit = &law["mc2010"];
    let x = law["slip_range"].as_f64().unwrap();
    let s1 = fit["s1"].as_f64().unwrap();
    assert!(s1 > 0.0 && s1 <= x * (1.0 + 1e-9), "{law}");
    assert!(
        fit["s2"].as_f64().unwrap() >= s1
            && fit["s3"].as_f64().unwrap() > fit["s2"].as_f64().unwrap()
    );
    assert!(
        (0.02..=1.0).contains(&fit["alpha"].as_f64().unwrap()),
        "{law}"
    );
    assert!(fit["tau_f"].as_f64().unwrap() <= fit["tau_max"].as_f64().unwrap());
    let error = fit["fit_error"].as_f64().unwrap();
    assert!(error > 0.0 && error < 0.1, "{law}");
    assert_eq!(
        law["piecewise_linear"]["points"].as_array().unwrap().len(),
        8
    );
    let code = &law["design_code"];
    let fcm = code["fcm"].as_f64().unwrap();
    // f_t = 3 MPa: f_ck = (3 / 0.3)^1.5 MPa, f_cm = f_ck + 8 MPa.
    assert!(close(fcm, 8e6 + 1e6 * 10f64.powf(1.5), 1e-9), "{code}");
    assert_eq!(code["fcm_source"], "derived_from_tensile_strength");
    assert!(
        code["notes"][0].as_str().unwrap().contains("derived"),
        "{code}"
    );
    assert!(close(
        code["tau_max"].as_f64().unwrap(),
        2.5e6 * (fcm / 1e6).sqrt(),
        1e-12
    ));
    let clear = 5e-3 - 1.84e-3 / 55f64.to_radians().sin();
    assert!(close(code["s3"].as_f64().unwrap(), clear, 1e-9), "{code}");
    let summary = json(&dir.join("summary.json"));
    assert_eq!(summary["bond_law"], law);
    let ratio = summary["design_code"]["tau_max_ratio"].as_f64().unwrap();
    assert!(close(
        ratio,
        fit["tau_max"].as_f64().unwrap() / (2.5e6 * (fcm / 1e6).sqrt()),
        1e-12
    ));
    assert!(
        summary["geometry"]["f_R"].as_f64().unwrap() > 0.0,
        "{summary}"
    );
    let svg = std::fs::read_to_string(dir.join("plots/bond_slip.svg")).unwrap();
    assert!(
        svg.contains("MC2010 form fitted") && svg.contains("MC2010, good bond"),
        "legend"
    );

    let out = run(
        &work,
        &[
            "materials.concrete.fcm=50 MPa",
            "outputs.bond_conditions=other",
        ],
    );
    assert!(
        out.contains("solve: up to date") && out.contains("post: done"),
        "{out}"
    );
    let code = json(&dir.join("bond_law.json"))["design_code"].clone();
    assert_eq!(code["fcm_source"], "given");
    assert!(
        close(
            code["tau_max"].as_f64().unwrap(),
            1.25e6 * 50f64.sqrt(),
            1e-12
        ),
        "{code}"
    );
    assert_eq!(code["s1"], 1.8e-3);
    std::fs::remove_dir_all(&work).ok();
}
