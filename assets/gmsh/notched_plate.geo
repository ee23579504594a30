// ricochet asset: a notched steel plate struck by a steel cylinder (plane strain).
// Units: metres. Mesh it with `gmsh notched_plate.geo -2 -format msh41 -o notched_plate.msh`
// (the Mesh options below give first-order quads only, as ricochet reads them).
SetFactory("Built-in");

w = 0.060;   // plate width
t = 0.012;   // plate thickness (height)
a = 0.003;   // notch radius (a half-disk cut into the bottom edge, at the centre)
r = 0.005;   // striker radius
gap = 0.0005; // gap between striker and plate
lc = 0.0012; // element size before the quads are split in four

// Plate outline, counter-clockwise from the bottom-left corner, with the notch.
Point(1) = {0, 0, 0, lc};
Point(2) = {w/2 - a, 0, 0, lc/3};
Point(3) = {w/2, 0, 0, lc/3};          // notch centre
Point(4) = {w/2, a, 0, lc/3};          // notch root
Point(5) = {w/2 + a, 0, 0, lc/3};
Point(6) = {w, 0, 0, lc};
Point(7) = {w, t, 0, lc};
Point(8) = {w/2, t, 0, lc/2};
Point(9) = {0, t, 0, lc};
Line(1) = {1, 2};
Circle(2) = {2, 3, 4};
Circle(3) = {4, 3, 5};
Line(4) = {5, 6};
Line(5) = {6, 7};
Line(6) = {7, 8};
Line(7) = {8, 9};
Line(8) = {9, 1};
Curve Loop(1) = {1, 2, 3, 4, 5, 6, 7, 8};
Plane Surface(1) = {1};

// Striker: a disk above the plate's centre.
cy = t + gap + r;
Point(20) = {w/2, cy, 0, lc};
Point(21) = {w/2, cy - r, 0, lc/2};
Point(22) = {w/2 + r, cy, 0, lc};
Point(23) = {w/2, cy + r, 0, lc};
Point(24) = {w/2 - r, cy, 0, lc};
Circle(21) = {21, 20, 22};
Circle(22) = {22, 20, 23};
Circle(23) = {23, 20, 24};
Circle(24) = {24, 20, 21};
Curve Loop(2) = {21, 22, 23, 24};
Plane Surface(2) = {2};

Physical Surface("plate") = {1};
Physical Surface("striker") = {2};
Physical Curve("clamp") = {5, 8};            // the plate's two ends
Physical Curve("plate_top") = {6, 7};        // where the striker lands
Physical Curve("striker_face") = {24, 21};   // the striker's lower half
Physical Curve("notch") = {2, 3};

Mesh.Algorithm = 8;             // Frontal-Delaunay for quads
Mesh.RecombineAll = 1;
Mesh.RecombinationAlgorithm = 1;
Mesh.SubdivisionAlgorithm = 1;  // split into quads only
Mesh.ElementOrder = 1;
Mesh.MshFileVersion = 4.1;
