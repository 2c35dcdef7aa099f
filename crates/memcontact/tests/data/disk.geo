// Unit disc with two physical surfaces: the inner disc "foam" (r < 0.5) and the annulus
// "soil" (0.5 < r < 1), plus a physical curve "rim" on the outer circle (a boundary
// region). Regenerate the four fixtures with:
//   gmsh disk.geo -2 -format msh22 -o disk_v22_ascii.msh
//   gmsh disk.geo -2 -format msh22 -bin -o disk_v22_binary.msh
//   gmsh disk.geo -2 -format msh41 -o disk_v41_ascii.msh
//   gmsh disk.geo -2 -format msh41 -bin -o disk_v41_binary.msh
lc = 0.15;
Point(1) = {0, 0, 0, lc};
Point(2) = {0.5, 0, 0, lc};
Point(3) = {0, 0.5, 0, lc};
Point(4) = {-0.5, 0, 0, lc};
Point(5) = {0, -0.5, 0, lc};
Point(6) = {1, 0, 0, lc};
Point(7) = {0, 1, 0, lc};
Point(8) = {-1, 0, 0, lc};
Point(9) = {0, -1, 0, lc};
Circle(1) = {2, 1, 3};
Circle(2) = {3, 1, 4};
Circle(3) = {4, 1, 5};
Circle(4) = {5, 1, 2};
Circle(5) = {6, 1, 7};
Circle(6) = {7, 1, 8};
Circle(7) = {8, 1, 9};
Circle(8) = {9, 1, 6};
Curve Loop(1) = {1, 2, 3, 4};
Curve Loop(2) = {5, 6, 7, 8};
Plane Surface(1) = {1};
Plane Surface(2) = {2, 1};
Physical Surface("foam", 1) = {1};
Physical Surface("soil", 2) = {2};
Physical Curve("rim", 3) = {5, 6, 7, 8};
Mesh.RandomSeed = 1;
