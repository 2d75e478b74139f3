// Test data (mesh/tests/diagnosis.rs): the specimen of tests/data/tiny-ribbed.yaml
// with bar.ribs.angle = 35 deg as the geometry stage wrote it before issue 15,
// in metres. gmsh 4.15 cannot mesh core surfaces 75 and 113 ("Impossible to mesh
// periodic surface"): their rib-foot curves end 2e-6 rad from the longitudinal
// ribs' foot lines in parameter space, above gmsh's chaining tolerance.
// Pull-out specimen: bar along z in a concrete cube (SPEC §2 frame), SI units (m).
// Cube x, y in [-L/2, L/2], z in [0, L]; z = 0 free face, z = L loaded (bearing) face.
SetFactory("OpenCASCADE");

// Bounding boxes from the tessellation: OCC's own boxes of curved faces are
// loose and would catch or miss faces in the selections below.
Geometry.OCCBoundsUseStl = 1;

// Mesh sizes (m). The mesh stage passes -setnumber h_interface/h_outer;
// the defaults only make the script usable on its own.
DefineConstant[
  h_interface = {0.0004, Name "Parameters/h_interface"},
  h_outer = {0.005, Name "Parameters/h_outer"}
];

// Specimen dimensions.
L = 0.024;
l_adh = 0.01;
z_lo = -0.002;
z_hi = 0.028;
R = 0.004;
r_out = 0.00452;
tol = 2.4e-8;

// Core: cylinder of radius R over the whole bar length.
core = newv; Cylinder(core) = {0, 0, z_lo, 0, 0, z_hi - z_lo, R};

// Longitudinal ribs at theta = 0 and pi: isosceles trapezoid (height a_l,
// crest width bl_top, width bl_base where the flanks meet the core circle),
// extended below the core surface so the union overlaps, extruded along z.
a_l = 0.0005200000000000001;
bl_top = 0.0008;
bl_base = 0.00184;
x_foot = 0.003892762515232595;
x_in = x_foot - 0.0002;
w_in = bl_base + (bl_base - bl_top) * (x_foot - x_in) / (R + a_l - x_foot);
lrib() = {};
For sd In {0:1}
  sg = 1 - 2 * sd;
  p1 = newp; Point(p1) = {sg * x_in, -w_in / 2, z_lo};
  p2 = newp; Point(p2) = {sg * (R + a_l), -bl_top / 2, z_lo};
  p3 = newp; Point(p3) = {sg * (R + a_l), bl_top / 2, z_lo};
  p4 = newp; Point(p4) = {sg * x_in, w_in / 2, z_lo};
  c1 = newc; Line(c1) = {p1, p2}; c2 = newc; Line(c2) = {p2, p3};
  c3 = newc; Line(c3) = {p3, p4}; c4 = newc; Line(c4) = {p4, p1};
  ll = newll; Curve Loop(ll) = {c1, c2, c3, c4};
  s = news; Plane Surface(s) = {ll};
  ex() = Extrude {0, 0, z_hi - z_lo} { Surface{s}; };
  lrib() += ex(1);
EndFor

// Transverse ribs: trapezoid sections (height a, axial widths wb at the core,
// wt at the crest) in planes through the axis at angles t in [t_s, pi - t_s],
// centred on z = zeta + sgn K cos t; a ThruSections through them gives exact
// rib volumes (a helical Pipe does not). Rib ends lie inside the longitudinal
// ribs. Side B (global angle t + pi): sgn = +1 rotated image, -1 mirrored.
// The section curves stay in the model after ThruSections: delete them.
a = 0.0005200000000000001;
c = 0.005;
K = 0.0057125920269684586;
wb = 0.0032079421039428206;
wt = 0.0013947574364968785;
t_s = 0.04413281899240429;
n_sec = 13;
r_in = R - 0.0001;
wb_in = wb + (wb - wt) * 0.0001 / a;
zeta0() = {-0.0054975, -0.0054975};
n_rib() = {9, 9};
sgn_side() = {1, 1.0};
ribs() = {};
For sd In {0:1}
  For kr In {1:n_rib(sd)}
    zeta = zeta0(sd) + (kr - 1) * c;
    loops() = {}; sec() = {};
    For j In {0:n_sec - 1}
      t = t_s + j * (Pi - 2 * t_s) / (n_sec - 1);
      zc = zeta + sgn_side(sd) * K * Cos(t);
      cx = Cos(t + sd * Pi); cy = Sin(t + sd * Pi);
      q1 = newp; Point(q1) = {r_in * cx, r_in * cy, zc - wb_in / 2};
      q2 = newp; Point(q2) = {(R + a) * cx, (R + a) * cy, zc - wt / 2};
      q3 = newp; Point(q3) = {(R + a) * cx, (R + a) * cy, zc + wt / 2};
      q4 = newp; Point(q4) = {r_in * cx, r_in * cy, zc + wb_in / 2};
      e1 = newc; Line(e1) = {q1, q2}; e2 = newc; Line(e2) = {q2, q3};
      e3 = newc; Line(e3) = {q3, q4}; e4 = newc; Line(e4) = {q4, q1};
      ll = newll; Curve Loop(ll) = {e1, e2, e3, e4};
      loops() += ll; sec() += {e1, e2, e3, e4};
    EndFor
    v = newv; ThruSections(v) = {loops()};
    Recursive Delete { Curve{sec()}; }
    ribs() += v;
  EndFor
EndFor

// One solid bar: fuse core and all ribs.
bar() = BooleanUnion{ Volume{core}; Delete; }{ Volume{lrib(), ribs()}; Delete; };

// Trim the ribs that cross the bar ends.
trim = newv; Cylinder(trim) = {0, 0, z_lo, 0, 0, z_hi - z_lo, r_out + R};
bar() = BooleanIntersection{ Volume{bar()}; Delete; }{ Volume{trim}; Delete; };

// Concrete cube; fragments with the bar and the plane z = l_adh give a conformal
// steel-concrete interface split at z = 0, l_adh, L.
cube = newv; Box(cube) = {-L / 2, -L / 2, 0, L, L, L};
cut = news; Rectangle(cut) = {-L / 2, -L / 2, l_adh, L, L};
BooleanFragments{ Volume{bar(), cube}; Delete; }{ Surface{cut}; Delete; }

// Steel: the volumes inside the bar's box; concrete: all the others.
rb = r_out + 0.05 * R;
steel() = Volume In BoundingBox{-rb, -rb, z_lo - tol, rb, rb, z_hi + tol};
concrete() = Volume{:};
concrete() -= steel();

// Interface: bar faces with z in [0, L] except the flat bar sections at
// z = 0, l_adh, L (and, in a quarter model, the bar's faces on the mirror
// planes x = 0, y = 0); split by the centre of their box at l_adh.
cand() = Surface In BoundingBox{-rb, -rb, -tol, rb, rb, L + tol};
adh() = {}; fre() = {};
For i In {0:#cand() - 1}
  bb() = BoundingBox Surface{cand(i)};
  zm = (bb(2) + bb(5)) / 2;
  flat = (bb(5) - bb(2) < tol);
  atcut = (Fabs(zm) < tol || Fabs(zm - l_adh) < tol || Fabs(zm - L) < tol);
  mirror = (bb(3) - bb(0) < tol && Fabs(bb(0)) < tol) || (bb(4) - bb(1) < tol && Fabs(bb(1)) < tol);
  If (!(flat && atcut) && !mirror)
    If (zm < l_adh)
      adh() += cand(i);
    Else
      fre() += cand(i);
    EndIf
  EndIf
EndFor

// Bar end faces.
free_end() = Surface In BoundingBox{-rb, -rb, z_lo - tol, rb, rb, z_lo + tol};
loaded_end() = Surface In BoundingBox{-rb, -rb, z_hi - tol, rb, rb, z_hi + tol};

// Concrete faces at z = L (bearing plate) and z = 0, without the bar's section.
big = L / 2 + tol;
bearing() = Surface In BoundingBox{-big, -big, L - tol, big, big, L + tol};
inner() = Surface In BoundingBox{-rb, -rb, L - tol, rb, rb, L + tol};
bearing() -= inner();
cfree() = Surface In BoundingBox{-big, -big, -tol, big, big, tol};
inner() = Surface In BoundingBox{-rb, -rb, -tol, rb, rb, tol};
cfree() -= inner();

// Physical groups read by the mesh stage.
Physical Volume("steel") = {steel()};
Physical Volume("concrete") = {concrete()};
Physical Surface("interface_adhesive") = {adh()};
Physical Surface("interface_free") = {fre()};
Physical Surface("bar_loaded_end") = {loaded_end()};
Physical Surface("bar_free_end") = {free_end()};
Physical Surface("concrete_bearing_face") = {bearing()};
Physical Surface("concrete_free_face") = {cfree()};

// Size field (SPEC §9): h(r) = min(h_outer, h_interface + k max(0, r - r_out)),
// r the distance to the bar axis: the whole bar and the interface at
// h_interface, growing linearly to h_outer at the cube's side faces.
k_grow = (h_outer - h_interface) / (L / 2 - r_out);
Field[1] = MathEval;
Field[1].F = Sprintf("Min(%.12g, %.12g + %.12g * Max(0, Sqrt(x * x + y * y) - %.12g))", h_outer, h_interface, k_grow, r_out);
Background Field = 1;
// Only the field sets sizes.
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;
