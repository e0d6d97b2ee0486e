// Plate-cylinder strip (DESIGN §4, paper §2.2): 2 m x 0.2 m in the plane
// z = 0, clamped at x = 0, loaded at (2, -0.1, 0), (2, 0, 0), (2, 0.1, 0).
// Structured 4-node quadrilaterals: nx elements along x (nx a multiple of 20
// so that node rows lie at x = 1.0, 1.1, 1.2), ny (even) across the width.
// Generate:  gmsh plate-cylinder.geo -2 -setnumber nx 40 -setnumber ny 4 -o plate-cylinder.msh
DefineConstant[ nx = {40, Name "elements along x"}, ny = {4, Name "elements across (even)"} ];
Point(1) = {0, -0.1, 0};
Point(2) = {2, -0.1, 0};
Point(3) = {2, 0, 0};
Point(4) = {2, 0.1, 0};
Point(5) = {0, 0.1, 0};
Point(6) = {0, 0, 0};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 5};
Line(5) = {5, 6};
Line(6) = {6, 1};
Curve Loop(1) = {1, 2, 3, 4, 5, 6};
Plane Surface(1) = {1};
Transfinite Curve{1, 4} = nx + 1;
Transfinite Curve{2, 3, 5, 6} = ny / 2 + 1;
Transfinite Surface{1} = {1, 2, 4, 5};
Recombine Surface{1};
Physical Surface("strip") = {1};
Physical Curve("clamp") = {5, 6};
Physical Point("load_right") = {2};
Physical Point("load_A") = {3};
Physical Point("load_left") = {4};
Mesh.MshFileVersion = 4.1;
Mesh.Binary = 0;
