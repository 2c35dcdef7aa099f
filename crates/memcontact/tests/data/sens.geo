// The sensitivity tests' site: the rectangle (0, 2) x (0, 1) in three physical surfaces,
// "soft" (x < 1, around the plinth), "plinth" (the square (0.35, 0.55) x (0.4, 0.6)) and
// "stiff" (x > 1); physical curves "bottom", "left", "right" (fixed) and "top" (left free
// by the tests' cases). Unstructured, size 0.09 (about 300 vertices). Regenerate with
// (pip install gmsh):
//   python scripts/make_mesh.py --geo sens.geo --format 4.1 --ascii -o sens.msh
h = 0.09;
Point(1) = {0, 0, 0, h};
Point(2) = {1, 0, 0, h};
Point(3) = {2, 0, 0, h};
Point(4) = {2, 1, 0, h};
Point(5) = {1, 1, 0, h};
Point(6) = {0, 1, 0, h};
Point(7) = {0.35, 0.4, 0, h};
Point(8) = {0.55, 0.4, 0, h};
Point(9) = {0.55, 0.6, 0, h};
Point(10) = {0.35, 0.6, 0, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 5};
Line(5) = {5, 6};
Line(6) = {6, 1};
Line(7) = {2, 5};
Line(8) = {7, 8};
Line(9) = {8, 9};
Line(10) = {9, 10};
Line(11) = {10, 7};
Curve Loop(1) = {1, 7, 5, 6};
Curve Loop(2) = {8, 9, 10, 11};
Curve Loop(3) = {2, 3, 4, -7};
Plane Surface(1) = {1, 2};
Plane Surface(2) = {2};
Plane Surface(3) = {3};
Physical Surface("soft", 1) = {1};
Physical Surface("plinth", 2) = {2};
Physical Surface("stiff", 3) = {3};
Physical Curve("bottom", 11) = {1, 2};
Physical Curve("right", 12) = {3};
Physical Curve("top", 13) = {4, 5};
Physical Curve("left", 14) = {6};
