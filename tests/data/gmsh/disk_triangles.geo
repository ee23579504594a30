// ricochet test mesh: a steel disk (R = 50 mm) for the disk-on-a-wall case of REFERENCES.md section 5,
// meshed by Gmsh into 3-node triangles only, finer toward the contact point (R, 0).
// Mesh it with `gmsh disk_triangles.geo -2 -format msh41 -o disk_triangles.msh`.
SetFactory("Built-in");
R = 0.05;
lc = 0.0025;   // element size far from the contact point
lf = 0.0003;   // element size at the contact point
Point(1) = {0, 0, 0, lc};
Point(2) = {R, 0, 0, lf};
Point(3) = {0, R, 0, lc};
Point(4) = {-R, 0, 0, lc};
Point(5) = {0, -R, 0, lc};
Circle(1) = {2, 1, 3};
Circle(2) = {3, 1, 4};
Circle(3) = {4, 1, 5};
Circle(4) = {5, 1, 2};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Physical Surface("disk") = {1};
Physical Curve("rim") = {1, 2, 3, 4};
Physical Point("contact") = {2};
Mesh.Algorithm = 8;
Mesh.RecombineAll = 0;
Mesh.ElementOrder = 1;
Mesh.MshFileVersion = 4.1;
