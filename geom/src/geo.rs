//! The gmsh `.geo` script (OpenCASCADE factory) that builds the specimen.
//!
//! Construction (SPEC §3, §9): core cylinder; two longitudinal ribs as
//! extruded trapezoids whose base chord dips into the core; each transverse
//! rib a `ThruSections` through [`RIB_SECTIONS`] trapezoids in planes through
//! the bar axis (their base also dips into the core); one `BooleanUnion`;
//! `BooleanIntersection` with a cylinder spanning the bar's length trims the
//! ribs crossing the bar ends; `BooleanFragments` with the cube and the plane
//! z = l_adh makes the interface conformal. A quarter model (smooth bars,
//! `specimen.symmetry`) intersects the bar with the box x, y ≥ 0 before the
//! fragments, uses the quarter of the cube and of the plane, and adds the
//! groups `symmetry_x` / `symmetry_y` (all faces on x = 0 / y = 0); a half
//! model (herringbone bars) does the same with y ≥ 0 and `symmetry_y` alone.
//! A half-turn half (spiral bars) keeps y ≥ 0 too, imprints the axis on the
//! cut face so that its sides x > 0 and x < 0 are distinct faces,
//! declares each x < 0 face the half-turn image of its x > 0 twin
//! (`Periodic Surface … Rotate`: gmsh meshes them as images of each other)
//! and groups them all as `half_turn_y`.
//! Entities are found by bounding
//! box with `Geometry.OCCBoundsUseStl = 1` (tight boxes on curved faces),
//! never by literal tag. Mesh sizes come from `DefineConstant`s so that the
//! mesh stage sets them with `-setnumber`; the script never meshes.

use crate::layout::{Layout, RIB_SECTIONS};
use crate::spec::Symmetry;
use std::fmt::Write;

/// Default interface mesh size in the script, m (overridden by the mesh stage).
pub const DEFAULT_H_INTERFACE: f64 = 0.0004;
/// Default outer mesh size in the script, m (overridden by the mesh stage).
pub const DEFAULT_H_OUTER: f64 = 0.005;

/// Physical group names, as the mesh stage looks them up.
pub mod groups {
    pub const STEEL: &str = "steel";
    pub const CONCRETE: &str = "concrete";
    pub const INTERFACE_ADHESIVE: &str = "interface_adhesive";
    pub const INTERFACE_FREE: &str = "interface_free";
    pub const BAR_LOADED_END: &str = "bar_loaded_end";
    pub const BAR_FREE_END: &str = "bar_free_end";
    pub const CONCRETE_BEARING_FACE: &str = "concrete_bearing_face";
    pub const CONCRETE_FREE_FACE: &str = "concrete_free_face";
    /// Faces (steel and concrete) on the mirror plane x = 0 of a quarter model.
    pub const SYMMETRY_X: &str = "symmetry_x";
    /// Faces (steel and concrete) on the mirror plane y = 0 of a quarter or half model.
    pub const SYMMETRY_Y: &str = "symmetry_y";
    /// Faces (steel and concrete) on the cut plane y = 0 of a half-turn half
    /// model: those at x < 0 are meshed as the half-turn images of those at
    /// x > 0.
    pub const HALF_TURN_Y: &str = "half_turn_y";
}

/// Model units of a ribbed bar's script per metre: the solid is built in
/// millimetres.
///
/// OpenCASCADE's tolerances are absolute (Precision::Confusion = 1e-7 model
/// units) and gmsh chains the boundary of a periodic (cylindrical) face in
/// its parameter space (angle in rad, height in model units) with a
/// tolerance of 1e-6 of that space's diagonal. Built in metres, the rib feet
/// (intersections of the ribs' B-spline flanks with the core cylinder) ended
/// up to 2e-6 rad away from the longitudinal ribs' foot lines, above gmsh's
/// tolerance on the core faces between ribs, whose height span is only
/// ~0.01 m: gmsh could not mesh them ("Impossible to mesh periodic surface",
/// the 35° failure; docs/src/explanation/geometry.md). In millimetres the same ends agree to
/// ~2e-8 rad and the tolerance is larger. The saved mesh is scaled back to
/// metres (`Mesh.ScalingFactor`). A smooth bar has no such faces and stays
/// in metres ([`model_units_per_m`]), so its meshes are those it always had.
pub const MODEL_UNITS_PER_M: f64 = 1000.0;

/// Model units per metre of the script `write_geo` writes for `layout`.
pub fn model_units_per_m(layout: &Layout) -> f64 {
    if layout.ribs.is_some() {
        MODEL_UNITS_PER_M
    } else {
        1.0
    }
}

fn num(v: f64) -> String {
    // Shortest round-trip representation: the script reproduces the layout exactly.
    let s = format!("{v:?}");
    if s == "-0.0" {
        "0".into()
    } else {
        s
    }
}

/// A length of a ribbed bar's layout (m) in model units.
fn length(v: f64) -> String {
    num(v * MODEL_UNITS_PER_M)
}

/// How a transverse rib's section continues below the core surface, so
/// that the ribs overlap the core in the union.
#[derive(Debug, Clone, Copy, PartialEq)]
enum RibRoot {
    /// The flanks continue straight down to `depth` below the core (m).
    Straight { depth: f64 },
    /// The flanks continue down to `kink`, then the sides go radially
    /// (constant axial width) down to `depth` below the core (m).
    Kinked { kink: f64, depth: f64 },
}

impl RibRoot {
    fn of(r: f64, rl: &crate::layout::RibLayout) -> RibRoot {
        let depth = 0.5 * (0.05 * r).min(0.5 * rl.a);
        // Continued flanks widen the base below the core: the facing flanks
        // of neighbouring ribs meet `meet` below it. Half way there the
        // widened bases still keep half the axial gap c − wb between them.
        let meet = if rl.wb > rl.wt {
            rl.a * (rl.c - rl.wb) / (rl.wb - rl.wt)
        } else {
            f64::INFINITY
        };
        let kink = 0.5 * meet;
        if kink >= depth {
            RibRoot::Straight { depth }
        } else {
            // Ribs near the overlap bound (b_base close to 0.98 c sin β).
            // Straight flanks there either overlap the neighbours inside the
            // core, with their crossing edge just below the core surface, or
            // stop within a few hundredths of a mm of it, a base face nearly
            // parallel to the core: both made OpenCASCADE's boolean with the
            // core inconsistent (rib volumes off by 2–8 %, faces lost;
            // docs/src/explanation/geometry.md). The kink keeps the neighbours apart and the
            // base deep; the band below it is at least as thick as the kink
            // is deep.
            RibRoot::Kinked {
                kink,
                depth: depth.max(2.0 * kink),
            }
        }
    }

    /// `.geo` variables: r_in, wb_in (and r_k, wb_k for a kinked root).
    fn geo_variables(&self) -> String {
        match *self {
            RibRoot::Straight { depth } => format!(
                "r_in = R - {d};\nwb_in = wb + (wb - wt) * {d} / a;\n",
                d = length(depth)
            ),
            RibRoot::Kinked { kink, depth } => format!(
                "// Near the overlap bound: flanks continued to the kink, then radial sides.\n\
                 r_k = R - {k};\nwb_k = wb + (wb - wt) * {k} / a;\nr_in = R - {d};\nwb_in = wb_k;\n",
                k = length(kink),
                d = length(depth)
            ),
        }
    }

    /// The section loop at angle t (inside the `.geo`'s section loop).
    fn geo_section(&self) -> &'static str {
        match self {
            RibRoot::Straight { .. } => {
                "\x20     q1 = newp; Point(q1) = {r_in * cx, r_in * cy, zc - wb_in / 2};
      q2 = newp; Point(q2) = {(R + a) * cx, (R + a) * cy, zc - wt / 2};
      q3 = newp; Point(q3) = {(R + a) * cx, (R + a) * cy, zc + wt / 2};
      q4 = newp; Point(q4) = {r_in * cx, r_in * cy, zc + wb_in / 2};
      e1 = newc; Line(e1) = {q1, q2}; e2 = newc; Line(e2) = {q2, q3};
      e3 = newc; Line(e3) = {q3, q4}; e4 = newc; Line(e4) = {q4, q1};
      ll = newll; Curve Loop(ll) = {e1, e2, e3, e4};
      loops() += ll; sec() += {e1, e2, e3, e4};
"
            }
            RibRoot::Kinked { .. } => {
                "\x20     q1 = newp; Point(q1) = {r_in * cx, r_in * cy, zc - wb_in / 2};
      q5 = newp; Point(q5) = {r_k * cx, r_k * cy, zc - wb_k / 2};
      q2 = newp; Point(q2) = {(R + a) * cx, (R + a) * cy, zc - wt / 2};
      q3 = newp; Point(q3) = {(R + a) * cx, (R + a) * cy, zc + wt / 2};
      q6 = newp; Point(q6) = {r_k * cx, r_k * cy, zc + wb_k / 2};
      q4 = newp; Point(q4) = {r_in * cx, r_in * cy, zc + wb_in / 2};
      e1 = newc; Line(e1) = {q1, q5}; e5 = newc; Line(e5) = {q5, q2};
      e2 = newc; Line(e2) = {q2, q3};
      e3 = newc; Line(e3) = {q3, q6}; e6 = newc; Line(e6) = {q6, q4};
      e4 = newc; Line(e4) = {q4, q1};
      ll = newll; Curve Loop(ll) = {e1, e5, e2, e3, e6, e4};
      loops() += ll; sec() += {e1, e5, e2, e3, e6, e4};
"
            }
        }
    }
}

/// Writes the `.geo` text for `layout`: parameters, the bar, the cube and
/// its fragments, the physical groups, the size field.
pub fn write_geo(layout: &Layout) -> String {
    let mut g = String::new();
    geo_parameters(&mut g, layout);
    geo_bar(&mut g, layout);
    geo_cube(&mut g, layout);
    geo_groups(&mut g, layout);
    geo_size_field(&mut g);
    g
}

/// Units, mesh-size parameters and the specimen's dimensions.
fn geo_parameters(w: &mut String, layout: &Layout) {
    let upm = model_units_per_m(layout);
    let length = |v: f64| num(v * upm);
    let l = layout.l;
    let r_out = layout.outer_radius();
    let _ = writeln!(
        w,
        "// Pull-out specimen: bar along z in a concrete cube (SPEC §2 frame).\n\
         // Cube x, y in [-L/2, L/2], z in [0, L]; z = 0 free face, z = L loaded (bearing) face.\n\
         SetFactory(\"OpenCASCADE\");\n\
         \n\
         // Model units per metre: 1000 for a ribbed bar (OpenCASCADE's absolute and\n\
         // gmsh's parametric tolerances suit millimetre-sized ribs), 1 for a smooth one;\n\
         // the saved mesh is scaled to metres.\n\
         model_per_m = {upm};\n\
         Mesh.ScalingFactor = 1 / model_per_m;\n\
         \n\
         // Bounding boxes from the tessellation: OCC's own boxes of curved faces are\n\
         // loose and would catch or miss faces in the selections below.\n\
         Geometry.OCCBoundsUseStl = 1;\n\
         \n\
         // Mesh sizes (m, converted to model units in the size field). The mesh stage\n\
         // passes -setnumber h_interface/h_outer (and h_bar_core, h_unbonded when\n\
         // the spec sets them); the defaults only make the script usable on its own.\n\
         DefineConstant[\n  h_interface = {{{hi}, Name \"Parameters/h_interface\"}},\n  h_outer = {{{ho}, Name \"Parameters/h_outer\"}},\n  h_bar_core = {{0, Name \"Parameters/h_bar_core\"}},\n  h_unbonded = {{0, Name \"Parameters/h_unbonded\"}}\n];\n\
         \n\
         // Specimen dimensions (model units).\n\
         L = {L};\nl_adh = {ladh};\nz_lo = {zlo};\nz_hi = {zhi};\nR = {R};\nr_out = {rout};\n\
         tol = {tol};",
        upm = num(upm),
        hi = num(DEFAULT_H_INTERFACE),
        ho = num(DEFAULT_H_OUTER),
        L = length(l),
        ladh = length(layout.l_adh),
        zlo = length(layout.z_lo),
        zhi = length(layout.z_hi),
        R = length(layout.r),
        rout = length(r_out),
        tol = length(1e-6 * l),
    );
}

/// The bar: the core cylinder, and for a ribbed bar the longitudinal and
/// transverse ribs fused to it.
fn geo_bar(w: &mut String, layout: &Layout) {
    let upm = model_units_per_m(layout);
    let length = |v: f64| num(v * upm);
    let _ = writeln!(
        w,
        "\n// Core: cylinder of radius R over the whole bar length.\n\
         core = newv; Cylinder(core) = {{0, 0, z_lo, 0, 0, z_hi - z_lo, R}};"
    );
    match &layout.ribs {
        None => {
            let _ = writeln!(w, "bar() = {{core}};");
        }
        Some(rl) => {
            let dip = 0.05 * layout.r;
            let root = RibRoot::of(layout.r, rl);
            let _ = writeln!(
                w,
                "\n// Longitudinal ribs at theta = 0 and pi: isosceles trapezoid (height a_l,\n\
                 // crest width bl_top, width bl_base where the flanks meet the core circle),\n\
                 // extended below the core surface so the union overlaps, extruded along z.\n\
                 a_l = {al};\nbl_top = {blt};\nbl_base = {blb};\nx_foot = {xf};\nx_in = x_foot - {dip};\n\
                 w_in = bl_base + (bl_base - bl_top) * (x_foot - x_in) / (R + a_l - x_foot);\n\
                 lrib() = {{}};\n\
                 For sd In {{0:1}}\n\
                 \x20 sg = 1 - 2 * sd;\n\
                 \x20 p1 = newp; Point(p1) = {{sg * x_in, -w_in / 2, z_lo}};\n\
                 \x20 p2 = newp; Point(p2) = {{sg * (R + a_l), -bl_top / 2, z_lo}};\n\
                 \x20 p3 = newp; Point(p3) = {{sg * (R + a_l), bl_top / 2, z_lo}};\n\
                 \x20 p4 = newp; Point(p4) = {{sg * x_in, w_in / 2, z_lo}};\n\
                 \x20 c1 = newc; Line(c1) = {{p1, p2}}; c2 = newc; Line(c2) = {{p2, p3}};\n\
                 \x20 c3 = newc; Line(c3) = {{p3, p4}}; c4 = newc; Line(c4) = {{p4, p1}};\n\
                 \x20 ll = newll; Curve Loop(ll) = {{c1, c2, c3, c4}};\n\
                 \x20 s = news; Plane Surface(s) = {{ll}};\n\
                 \x20 ex() = Extrude {{0, 0, z_hi - z_lo}} {{ Surface{{s}}; }};\n\
                 \x20 lrib() += ex(1);\n\
                 EndFor",
                al = length(rl.a_l),
                blt = length(rl.bl_top),
                blb = length(rl.bl_base),
                xf = length(rl.x_foot),
                dip = length(dip),
            );
            let _ = writeln!(
                w,
                "\n// Transverse ribs: trapezoid sections (height a, axial widths wb at the core,\n\
                 // wt at the crest) in planes through the axis at angles t in [t_s, pi - t_s],\n\
                 // centred on z = zeta + sgn K cos t; a ThruSections through them gives exact\n\
                 // rib volumes (a helical Pipe does not). Rib ends lie inside the longitudinal\n\
                 // ribs. Side B (global angle t + pi): sgn = +1 rotated image, -1 mirrored.\n\
                 // The section curves stay in the model after ThruSections: delete them.\n\
                 a = {a};\nc = {c};\nK = {k};\nwb = {wb};\nwt = {wt};\nt_s = {ts};\nn_sec = {nsec};\n\
                 {root_vars}\
                 zeta0() = {{{za0}, {zb0}}};\nn_rib() = {{{na}, {nb}}};\nsgn_side() = {{1, {sgb}}};\n\
                 ribs() = {{}};\n\
                 For sd In {{0:1}}\n\
                 \x20 For kr In {{1:n_rib(sd)}}\n\
                 \x20   zeta = zeta0(sd) + (kr - 1) * c;\n\
                 \x20   loops() = {{}}; sec() = {{}};\n\
                 \x20   For j In {{0:n_sec - 1}}\n\
                 \x20     t = t_s + j * (Pi - 2 * t_s) / (n_sec - 1);\n\
                 \x20     zc = zeta + sgn_side(sd) * K * Cos(t);\n\
                 \x20     cx = Cos(t + sd * Pi); cy = Sin(t + sd * Pi);\n\
                 {section}\
                 \x20   EndFor\n\
                 \x20   v = newv; ThruSections(v) = {{loops()}};\n\
                 \x20   Recursive Delete {{ Curve{{sec()}}; }}\n\
                 \x20   ribs() += v;\n\
                 \x20 EndFor\n\
                 EndFor\n\
                 \n\
                 // One solid bar: fuse core and all ribs.\n\
                 bar() = BooleanUnion{{ Volume{{core}}; Delete; }}{{ Volume{{lrib(), ribs()}}; Delete; }};\n\
                 \n\
                 // Trim the ribs that cross the bar ends.\n\
                 trim = newv; Cylinder(trim) = {{0, 0, z_lo, 0, 0, z_hi - z_lo, r_out + R}};\n\
                 bar() = BooleanIntersection{{ Volume{{bar()}}; Delete; }}{{ Volume{{trim}}; Delete; }};",
                a = length(rl.a),
                c = length(rl.c),
                k = length(rl.k),
                wb = length(rl.wb),
                wt = length(rl.wt),
                ts = num(rl.t_s),
                nsec = RIB_SECTIONS,
                root_vars = root.geo_variables(),
                section = root.geo_section(),
                za0 = length(rl.sides[0].zeta.first().copied().unwrap_or(0.0)),
                zb0 = length(rl.sides[1].zeta.first().copied().unwrap_or(0.0)),
                na = rl.sides[0].zeta.len(),
                nb = rl.sides[1].zeta.len(),
                sgb = num(rl.sides[1].sign),
            );
        }
    }
}

/// The symmetric part's cut of the bar, the cube and the fragments that make
/// the steel–concrete interface conformal.
fn geo_cube(w: &mut String, layout: &Layout) {
    let has_cut = layout.l_adh < layout.l;
    // Lower x of the kept box (0 for the quarter), and the modelled part's
    // lower corner and sides in x and y of the cube's cross-section.
    let (cut, x0, c0, cs) = match layout.symmetry {
        Symmetry::Full => (None, "", ["-L / 2", "-L / 2"], ["L", "L"]),
        Symmetry::Half => (
            Some(
                "Half model: keep the part y >= 0 of the bar; the plane y = 0 of its\n\
                  // longitudinal ribs is a mirror plane of the herringbone specimen.",
            ),
            "-(r_out + R)",
            ["-L / 2", "0"],
            ["L", "L / 2"],
        ),
        Symmetry::HalfTurn => (
            Some(
                "Half model: keep the part y >= 0 of the bar; the half-turn about the\n\
                  // axis maps the spiral specimen onto itself and the cut face's side\n\
                  // x < 0 onto its side x > 0.",
            ),
            "-(r_out + R)",
            ["-L / 2", "0"],
            ["L", "L / 2"],
        ),
        Symmetry::Quarter => (
            Some(
                "Quarter model: keep the part x >= 0, y >= 0 of the bar; the planes x = 0\n\
                  // and y = 0 are mirror planes of the specimen.",
            ),
            "0",
            ["0", "0"],
            ["L / 2", "L / 2"],
        ),
    };
    if let Some(what) = cut {
        let xs = if x0 == "0" {
            "r_out + R"
        } else {
            "2 * (r_out + R)"
        };
        let _ = writeln!(
            w,
            "\n// {what} The box overshoots the bar\n\
             // ends so that no face of it coincides with a bar end.\n\
             qb = newv; Box(qb) = {{{x0}, 0, z_lo - R, {xs}, r_out + R, z_hi - z_lo + 2 * R}};\n\
             bar() = BooleanIntersection{{ Volume{{bar()}}; Delete; }}{{ Volume{{qb}}; Delete; }};"
        );
    }
    // The axis line imprinted on the cut face splits it at x = 0 into the two
    // faces the half-turn maps onto each other; cutting the bar there would
    // cut every rib (2.7× the boolean time on r1-coarse).
    let axis = if layout.symmetry == Symmetry::HalfTurn {
        let _ = writeln!(
            w,
            "// The bar axis, imprinted on the cut face by the fragments below.\n\
             pa = newp; Point(pa) = {{0, 0, z_lo}}; pb = newp; Point(pb) = {{0, 0, z_hi}};\n\
             axis = newc; Line(axis) = {{pa, pb}};"
        );
        " Curve{axis};"
    } else {
        ""
    };
    let [cx0, cy0] = c0;
    let [csx, csy] = cs;
    let _ = writeln!(
        w,
        "\n// Concrete cube{part}; fragments with the bar{cut_note} give a conformal\n\
         // steel-concrete interface split at z = 0{cut_z}, L.\n\
         cube = newv; Box(cube) = {{{cx0}, {cy0}, 0, {csx}, {csy}, L}};",
        part = match layout.symmetry {
            Symmetry::Full => "",
            Symmetry::Half | Symmetry::HalfTurn => " (its half y >= 0)",
            Symmetry::Quarter => " (its quarter x, y >= 0)",
        },
        cut_note = if has_cut {
            " and the plane z = l_adh"
        } else {
            ""
        },
        cut_z = if has_cut { ", l_adh" } else { "" },
    );
    if has_cut {
        let _ = writeln!(
            w,
            "cut = news; Rectangle(cut) = {{{cx0}, {cy0}, l_adh, {csx}, {csy}}};\n\
             BooleanFragments{{ Volume{{bar(), cube}}; Delete; }}{{ Surface{{cut}};{axis} Delete; }}"
        );
    } else {
        let _ = writeln!(
            w,
            "BooleanFragments{{ Volume{{bar(), cube}}; Delete; }}{{{tool} }}",
            tool = if axis.is_empty() {
                ""
            } else {
                " Curve{axis}; Delete;"
            }
        );
    }
}

/// The selections of volumes and faces, and the physical groups the mesh
/// stage reads.
fn geo_groups(w: &mut String, layout: &Layout) {
    let _ = writeln!(
        w,
        "\n// Steel: the volumes inside the bar's box; concrete: all the others.\n\
         rb = r_out + 0.05 * R;\n\
         steel() = Volume In BoundingBox{{-rb, -rb, z_lo - tol, rb, rb, z_hi + tol}};\n\
         concrete() = Volume{{:}};\n\
         concrete() -= steel();\n\
         \n\
         // Interface: bar faces with z in [0, L] except the flat bar sections at\n\
         // z = 0, l_adh, L (and, in a quarter or half model, the bar's faces on the mirror\n\
         // planes x = 0, y = 0); split by the centre of their box at l_adh.\n\
         cand() = Surface In BoundingBox{{-rb, -rb, -tol, rb, rb, L + tol}};\n\
         adh() = {{}}; fre() = {{}};\n\
         For i In {{0:#cand() - 1}}\n\
         \x20 bb() = BoundingBox Surface{{cand(i)}};\n\
         \x20 zm = (bb(2) + bb(5)) / 2;\n\
         \x20 flat = (bb(5) - bb(2) < tol);\n\
         \x20 atcut = (Fabs(zm) < tol || Fabs(zm - l_adh) < tol || Fabs(zm - L) < tol);\n\
         \x20 mirror = (bb(3) - bb(0) < tol && Fabs(bb(0)) < tol) || (bb(4) - bb(1) < tol && Fabs(bb(1)) < tol);\n\
         \x20 If (!(flat && atcut) && !mirror)\n\
         \x20   If (zm < l_adh)\n\
         \x20     adh() += cand(i);\n\
         \x20   Else\n\
         \x20     fre() += cand(i);\n\
         \x20   EndIf\n\
         \x20 EndIf\n\
         EndFor\n\
         \n\
         // Bar end faces.\n\
         free_end() = Surface In BoundingBox{{-rb, -rb, z_lo - tol, rb, rb, z_lo + tol}};\n\
         loaded_end() = Surface In BoundingBox{{-rb, -rb, z_hi - tol, rb, rb, z_hi + tol}};\n\
         \n\
         // Concrete faces at z = L (bearing plate) and z = 0, without the bar's section.\n\
         big = L / 2 + tol;\n\
         bearing() = Surface In BoundingBox{{-big, -big, L - tol, big, big, L + tol}};\n\
         inner() = Surface In BoundingBox{{-rb, -rb, L - tol, rb, rb, L + tol}};\n\
         bearing() -= inner();\n\
         cfree() = Surface In BoundingBox{{-big, -big, -tol, big, big, tol}};\n\
         inner() = Surface In BoundingBox{{-rb, -rb, -tol, rb, rb, tol}};\n\
         cfree() -= inner();\n\
         \n\
         // Physical groups read by the mesh stage.\n\
         Physical Volume(\"{steel}\") = {{steel()}};\n\
         Physical Volume(\"{concrete}\") = {{concrete()}};\n\
         Physical Surface(\"{ia}\") = {{adh()}};\n\
         Physical Surface(\"{ifr}\") = {{fre()}};\n\
         Physical Surface(\"{le}\") = {{loaded_end()}};\n\
         Physical Surface(\"{fe}\") = {{free_end()}};\n\
         Physical Surface(\"{cb}\") = {{bearing()}};\n\
         Physical Surface(\"{cf}\") = {{cfree()}};",
        steel = groups::STEEL,
        concrete = groups::CONCRETE,
        ia = groups::INTERFACE_ADHESIVE,
        ifr = groups::INTERFACE_FREE,
        le = groups::BAR_LOADED_END,
        fe = groups::BAR_FREE_END,
        cb = groups::CONCRETE_BEARING_FACE,
        cf = groups::CONCRETE_FREE_FACE,
    );
    let planes: &[(&str, &str)] = match layout.symmetry {
        Symmetry::Full => &[],
        Symmetry::Half => &[("sym_y", groups::SYMMETRY_Y)],
        Symmetry::HalfTurn => &[("sym_y", groups::HALF_TURN_Y)],
        Symmetry::Quarter => &[("sym_x", groups::SYMMETRY_X), ("sym_y", groups::SYMMETRY_Y)],
    };
    if !planes.is_empty() {
        let _ = writeln!(
            w,
            "\n// Mirror planes: every face (steel and concrete, inside and outside the\n\
             // cube) lying in x = 0, resp. y = 0.\n\
             span = L / 2 + z_hi - z_lo;"
        );
    }
    for (var, group) in planes {
        let lo_x = if layout.symmetry != Symmetry::Quarter {
            "-span"
        } else {
            "-tol"
        };
        let bbox = if *var == "sym_x" {
            "-tol, -tol, z_lo - tol, tol, span, z_hi + tol".to_string()
        } else {
            format!("{lo_x}, -tol, z_lo - tol, span, tol, z_hi + tol")
        };
        let _ = writeln!(
            w,
            "{var}() = Surface In BoundingBox{{{bbox}}};\n\
             Physical Surface(\"{group}\") = {{{var}()}};"
        );
    }
    if layout.symmetry == Symmetry::HalfTurn {
        geo_half_turn_pairs(w);
    }
}

/// Pairs each face of the cut plane at x < 0 with its half-turn image at
/// x > 0 (the x-mirror of its box, same z range) and has gmsh mesh it as
/// that image. A face without its twin stops the script: the mesh stage
/// would otherwise get a cut face whose nodes do not pair.
fn geo_half_turn_pairs(w: &mut String) {
    let _ = writeln!(
        w,
        "\n// Half-turn pairs on y = 0: each face at x < 0 is meshed as the image of\n\
         // its twin at x > 0 under the half-turn about the axis.\n\
         ptol = 1e-3 * R;\n\
         ht_master() = {{}}; ht_slave() = {{}};\n\
         For i In {{0:#sym_y() - 1}}\n\
         \x20 bm() = BoundingBox Surface{{sym_y(i)}};\n\
         \x20 If (bm(0) > -ptol)\n\
         \x20   For j In {{0:#sym_y() - 1}}\n\
         \x20     bs() = BoundingBox Surface{{sym_y(j)}};\n\
         \x20     If (bs(3) < ptol && Fabs(bs(0) + bm(3)) < ptol && Fabs(bs(3) + bm(0)) < ptol && Fabs(bs(2) - bm(2)) < ptol && Fabs(bs(5) - bm(5)) < ptol)\n\
         \x20       ht_master() += sym_y(i); ht_slave() += sym_y(j);\n\
         \x20     EndIf\n\
         \x20   EndFor\n\
         \x20 EndIf\n\
         EndFor\n\
         If (2 * #ht_master() != #sym_y())\n\
         \x20 Error(\"half-turn half: %g of the %g faces on y = 0 have a twin at x < 0\", #ht_master(), #sym_y());\n\
         \x20 Abort;\n\
         EndIf\n\
         Periodic Surface {{ht_slave()}} = {{ht_master()}} Rotate {{{{0, 0, 1}}, {{0, 0, 0}}, Pi}};"
    );
}

/// The size field (SPEC §9).
fn geo_size_field(w: &mut String) {
    let _ = writeln!(
        w,
        "\n// Size field (SPEC §9): h(r) = min(h_outer, h_interface + k max(0, r - r_out)),\n\
         // r the distance to the bar axis: the whole bar and the interface at\n\
         // h_interface, growing linearly to h_outer at the cube's side faces.\n\
         h_in = h_interface * model_per_m;\n\
         h_out = h_outer * model_per_m;\n\
         k_grow = (h_out - h_in) / (L / 2 - r_out);\n\
         // Each lean part adds an increment over h_interface that is zero where\n\
         // the part's rule does not apply; the increments combine by the larger.\n\
         size_increment = Sprintf(\"%.12g * Max(0, Sqrt(x * x + y * y) - %.12g)\", k_grow, r_out);\n\
         If (h_bar_core > h_interface)\n\
           // A lean bar core: h_interface in a band of two rib heights (at least\n\
           // two elements) under the bar's surface, then growing by half the\n\
           // depth below the band up to h_bar_core: the core stays elastic and\n\
           // its field smooth (docs/src/explanation/mesh.md, Bar core).\n\
           h_core = h_bar_core * model_per_m;\n\
           r_band = R - Max(2 * (r_out - R), 2 * h_in);\n\
           size_increment = StrCat(\"Max(\", size_increment, Sprintf(\", Min(%.12g, 0.5 * Max(0, %.12g - Sqrt(x * x + y * y))))\", h_core - h_in, r_band));\n\
         EndIf\n\
         If (h_unbonded > h_interface)\n\
           // Lean unbonded parts: between a band of one bar diameter past the\n\
           // bonded zone z in [0, l_adh] (the concrete in front of the last ribs\n\
           // damages up to a rib spacing beyond it) and the bearing face z = L, the\n\
           // size grows by half the distance to the nearer of the two up to\n\
           // h_unbonded; there the bar carries no bond and both bodies stay elastic.\n\
           // The bearing face and the loaded overhang keep their sizes: their\n\
           // reactions set the solver's force scale (docs/src/explanation/mesh.md, Unbonded\n\
           // parts).\n\
           h_unb = h_unbonded * model_per_m;\n\
           z_band = Max(2 * R, Max(2 * (r_out - R), 2 * h_in));\n\
           size_increment = StrCat(\"Max(\", size_increment, Sprintf(\", Min(%.12g, 0.5 * Max(0, Min(z - %.12g, %.12g - z))))\", h_unb - h_in, l_adh + z_band, L));\n\
         EndIf\n\
         Field[1] = MathEval;\n\
         Field[1].F = StrCat(Sprintf(\"Min(%.12g, %.12g + \", h_out, h_in), size_increment, \")\");\n\
         Background Field = 1;\n\
         // Only the field sets sizes.\n\
         Mesh.MeshSizeFromPoints = 0;\n\
         Mesh.MeshSizeFromCurvature = 0;\n\
         Mesh.MeshSizeExtendFromBoundary = 0;"
    );
}
