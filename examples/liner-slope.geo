// A geomembrane liner on a slope, in plan view: 40 m along the slope's foot (x) by 20 m up
// it (y), the ground rising 1 in 3 from the toe (y = 0) to the crest (y = 20). Physical
// surfaces: the two cover soils placed on the liner, "cover_sand" on the lower half and
// "cover_gravel" on the upper half. Physical curves: the "toe", the flanks "flank_west"
// (x = 0) and "flank_east" (x = 40), and the crest in three parts: "crest_west",
// "crest_anchor" (the stretch of anchor trench already backfilled) and "crest_east".
// The case liner-slope.toml leaves crest_west and crest_east free. Make the mesh with
// (pip install gmsh; or the Gmsh application: gmsh liner-slope.geo -2 -o liner-slope.msh):
//   python scripts/make_mesh.py --geo examples/liner-slope.geo --ascii -o examples/liner-slope.msh
lc = 0.5;
Point(1) = {0, 0, 0, lc};
Point(2) = {40, 0, 0, lc};
Point(3) = {40, 10, 0, lc};
Point(4) = {40, 20, 0, lc};
Point(5) = {25, 20, 0, lc};
Point(6) = {15, 20, 0, lc};
Point(7) = {0, 20, 0, lc};
Point(8) = {0, 10, 0, lc};
Line(1) = {1, 2};   // toe
Line(2) = {2, 3};   // east flank, lower
Line(3) = {3, 4};   // east flank, upper
Line(4) = {4, 5};   // crest, east
Line(5) = {5, 6};   // crest, anchored
Line(6) = {6, 7};   // crest, west
Line(7) = {7, 8};   // west flank, upper
Line(8) = {8, 1};   // west flank, lower
Line(9) = {8, 3};   // where the two cover soils meet (inside the mesh: no physical curve)
Curve Loop(1) = {1, 2, -9, 8};
Curve Loop(2) = {9, 3, 4, 5, 6, 7};
Plane Surface(1) = {1};
Plane Surface(2) = {2};
Physical Surface("cover_sand", 1) = {1};
Physical Surface("cover_gravel", 2) = {2};
Physical Curve("toe", 11) = {1};
Physical Curve("flank_east", 12) = {2, 3};
Physical Curve("crest_east", 13) = {4};
Physical Curve("crest_anchor", 14) = {5};
Physical Curve("crest_west", 15) = {6};
Physical Curve("flank_west", 16) = {7, 8};
Mesh.Algorithm = 6;
Mesh.RandomSeed = 1;
