// Benchmark specimen: smooth bar (d = 8 mm) through the 80 mm concrete cube (paper smooth-80).
// Frame: bar axis z; cube x,y in [-L/2, L/2], z in [0, L]; bar z in [-e_free, L + e_load];
// adhesive zone z in [0, l_adh]. Lengths in metres.
SetFactory("OpenCASCADE");
DefineConstant[ h_interface = 0.0004, h_outer = 0.005 ];
d = 0.008; L = 0.080; e_free = 0.005; e_load = 0.010; l_adh = 0.040;
Geometry.OCCBoundsUseStl = 1;

cube = newv; Box(cube) = {-L/2, -L/2, 0, L, L, L};
// The bar in three pieces so that the planes z = 0, l_adh and L are mesh boundaries.
b1 = newv; Cylinder(b1) = {0, 0, -e_free, 0, 0, e_free, d/2};
b2 = newv; Cylinder(b2) = {0, 0, 0, 0, 0, l_adh, d/2};
b3 = newv; Cylinder(b3) = {0, 0, l_adh, 0, 0, L - l_adh, d/2};
b4 = newv; Cylinder(b4) = {0, 0, L, 0, 0, e_load, d/2};
out() = BooleanFragments{ Volume{cube}; Delete; }{ Volume{b1, b2, b3, b4}; Delete; };

eps = 1e-6;
steel() = Volume In BoundingBox{-d/2-eps, -d/2-eps, -e_free-eps, d/2+eps, d/2+eps, L+e_load+eps};
all() = Volume{:};
concrete() = all();
concrete() -= steel();
Physical Volume("steel") = steel();
Physical Volume("concrete") = concrete();

// Lateral bar surfaces inside the cube.
lat() = Surface In BoundingBox{-d/2-eps, -d/2-eps, -eps, d/2+eps, d/2+eps, L+eps};
adh() = Surface In BoundingBox{-d/2-eps, -d/2-eps, -eps, d/2+eps, d/2+eps, l_adh+eps};
discs() = Surface In BoundingBox{-d/2-eps, -d/2-eps, -eps, d/2+eps, d/2+eps, eps};
discs() += Surface In BoundingBox{-d/2-eps, -d/2-eps, l_adh-eps, d/2+eps, d/2+eps, l_adh+eps};
discs() += Surface In BoundingBox{-d/2-eps, -d/2-eps, L-eps, d/2+eps, d/2+eps, L+eps};
adh() -= discs();
free() = lat();
free() -= discs();
free() -= adh();
Physical Surface("interface_adhesive") = adh();
Physical Surface("interface_free") = free();
Physical Surface("bar_loaded_end") = Surface In BoundingBox{-d/2-eps, -d/2-eps, L+e_load-eps, d/2+eps, d/2+eps, L+e_load+eps};
Physical Surface("bar_free_end") = Surface In BoundingBox{-d/2-eps, -d/2-eps, -e_free-eps, d/2+eps, d/2+eps, -e_free+eps};
cb() = Surface In BoundingBox{-L/2-eps, -L/2-eps, L-eps, L/2+eps, L/2+eps, L+eps};
cb() -= discs();
Physical Surface("concrete_bearing_face") = cb();
cf() = Surface In BoundingBox{-L/2-eps, -L/2-eps, -eps, L/2+eps, L/2+eps, eps};
cf() -= discs();
Physical Surface("concrete_free_face") = cf();

// Size: h_interface at the bar surface growing linearly to h_outer.
Field[1] = MathEval;
Field[1].F = Sprintf("Min(%g, %g + 0.25*Max(0, Sqrt(x*x+y*y) - %g))", h_outer, h_interface, d/2);
Background Field = 1;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;
