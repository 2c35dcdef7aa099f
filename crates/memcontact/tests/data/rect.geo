// The rectangle (0, 2) x (0, 1) as a structured 16 x 8 mesh cut along the diagonals from
// (x_i, y_j) to (x_i+1, y_j+1): the triangles of memcontact's rectangle generator
// (nx = 16, ny = 8, x1 = 2). Physical surfaces "lower" (y < 0.5) and "upper"; physical
// curves named like the generator's sides ("bottom", "right", "top", "left") and a seam
// "seam" inside the mesh along y = 0.5 (which the reader reports and ignores: a boundary
// region holds boundary edges only). Regenerate the four fixtures with (pip install gmsh):
//   python scripts/make_mesh.py --geo rect.geo --format 2.2 --ascii -o rect_v22_ascii.msh
//   python scripts/make_mesh.py --geo rect.geo --format 2.2 -o rect_v22_binary.msh
//   python scripts/make_mesh.py --geo rect.geo --format 4.1 --ascii -o rect_v41_ascii.msh
//   python scripts/make_mesh.py --geo rect.geo --format 4.1 -o rect_v41_binary.msh
Point(1) = {0, 0, 0};
Point(2) = {2, 0, 0};
Point(3) = {2, 0.5, 0};
Point(4) = {0, 0.5, 0};
Point(5) = {2, 1, 0};
Point(6) = {0, 1, 0};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Line(5) = {3, 5};
Line(6) = {5, 6};
Line(7) = {6, 4};
Curve Loop(1) = {1, 2, 3, 4};
Curve Loop(2) = {-3, 5, 6, 7};
Plane Surface(1) = {1};
Plane Surface(2) = {2};
Transfinite Curve {1, 3, 6} = 17;
Transfinite Curve {2, 4, 5, 7} = 5;
Transfinite Surface {1} = {1, 2, 3, 4} Right;
Transfinite Surface {2} = {4, 3, 5, 6} Right;
Physical Surface("lower", 1) = {1};
Physical Surface("upper", 2) = {2};
Physical Curve("bottom", 11) = {1};
Physical Curve("right", 12) = {2, 5};
Physical Curve("top", 13) = {6};
Physical Curve("left", 14) = {4, 7};
Physical Curve("seam", 15) = {3};
