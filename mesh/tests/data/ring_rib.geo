// Test specimen: bar (d = 8 mm) with two ring ribs (height 0.8 mm, width 1.2 mm)
// through a 16 mm concrete cube; one rib in the adhesive zone, one in the free zone.
// Frame: bar axis z; cube x,y in [-L/2, L/2], z in [0, L]; bar z in [-e_free, L + e_load].
SetFactory("OpenCASCADE");
DefineConstant[ h_interface = 0.0008, h_outer = 0.004 ];
d = 0.008; L = 0.016; e_free = 0.002; e_load = 0.003; l_adh = 0.008; a = 0.0008; b = 0.0012;
Geometry.OCCBoundsUseStl = 1;

cube = newv; Box(cube) = {-L/2, -L/2, 0, L, L, L};
b1 = newv; Cylinder(b1) = {0, 0, -e_free, 0, 0, e_free, d/2};
b2 = newv; Cylinder(b2) = {0, 0, 0, 0, 0, l_adh, d/2};
b3 = newv; Cylinder(b3) = {0, 0, l_adh, 0, 0, L - l_adh, d/2};
b4 = newv; Cylinder(b4) = {0, 0, L, 0, 0, e_load, d/2};
r1 = newv; Cylinder(r1) = {0, 0, 0.003, 0, 0, b, d/2 + a};
r2 = newv; Cylinder(r2) = {0, 0, 0.012, 0, 0, b, d/2 + a};
out() = BooleanFragments{ Volume{cube}; Delete; }{ Volume{b1, b2, b3, b4, r1, r2}; Delete; };

eps = 1e-6;
R = d/2 + a;
steel() = Volume In BoundingBox{-R-eps, -R-eps, -e_free-eps, R+eps, R+eps, L+e_load+eps};
all() = Volume{:};
concrete() = all();
concrete() -= steel();
Physical Volume("steel") = steel();
Physical Volume("concrete") = concrete();

// The outer boundary of the steel, split by the planes z = 0, l_adh, L.
bnd() = CombinedBoundary{ Volume{steel()}; };
adh() = Surface In BoundingBox{-R-eps, -R-eps, -eps, R+eps, R+eps, l_adh+eps};
tmp() = adh(); tmp() -= bnd(); adh() -= tmp(); // keep only outer steel faces
fre() = Surface In BoundingBox{-R-eps, -R-eps, l_adh-eps, R+eps, R+eps, L+eps};
tmp() = fre(); tmp() -= bnd(); fre() -= tmp();
Physical Surface("interface_adhesive") = adh();
Physical Surface("interface_free") = fre();
Physical Surface("bar_loaded_end") = Surface In BoundingBox{-R-eps, -R-eps, L+e_load-eps, R+eps, R+eps, L+e_load+eps};
Physical Surface("bar_free_end") = Surface In BoundingBox{-R-eps, -R-eps, -e_free-eps, R+eps, R+eps, -e_free+eps};
cb() = Surface In BoundingBox{-L/2-eps, -L/2-eps, L-eps, L/2+eps, L/2+eps, L+eps};
cb() -= Surface In BoundingBox{-R-eps, -R-eps, L-eps, R+eps, R+eps, L+eps};
Physical Surface("concrete_bearing_face") = cb();
cf() = Surface In BoundingBox{-L/2-eps, -L/2-eps, -eps, L/2+eps, L/2+eps, eps};
cf() -= Surface In BoundingBox{-R-eps, -R-eps, -eps, R+eps, R+eps, eps};
Physical Surface("concrete_free_face") = cf();

Field[1] = MathEval;
Field[1].F = Sprintf("Min(%g, %g + 0.5*Max(0, Sqrt(x*x+y*y) - %g))", h_outer, h_interface, d/2);
Background Field = 1;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;
