// Analytic primitives tessellated into triangle meshes (normals by seed 001, see mesh.h), and
// height fields. All are centred on the origin; place them with TransformMesh.
#pragma once

#include <functional>

#include "geometry/mesh.h"

namespace iphong::geometry {

// Icosphere: the icosahedron subdivided `subdivisions` times (20·4^s triangles), on the sphere.
TriangleMesh MakeSphere(double radius, int subdivisions);

// Cylinder along the y axis (the image's vertical), `segments` around; caps optional.
TriangleMesh MakeCylinder(double radius, double height, int segments, bool capped);

// Torus around the z axis (its hole faces the camera): ring radius R, tube radius r.
TriangleMesh MakeTorus(double ring_radius, double tube_radius, int ring_segments,
                       int tube_segments);

// Square in the xy plane facing +z, side `size`, split into `divisions`² cells.
TriangleMesh MakePlane(double size, int divisions);

// Axis-aligned box with the given side lengths (normals are set flat: sharp edges).
TriangleMesh MakeBox(const Vec3d& size);

// Height field z = h(x, y) sampled on a grid of `columns` × `rows` vertices spanning
// size_x × size_y, row 0 at the top (+y). uv runs over [0, 1]² with v = 0 at the top row.
TriangleMesh MakeHeightField(const std::function<double(double x, double y)>& height, double size_x,
                             double size_y, int columns, int rows);
// The same from a sampled grid (one value per vertex, row-major from the top).
TriangleMesh MakeHeightField(const ImageF& heights, double size_x, double size_y);

// Built-in height functions.
struct BumpRipples {
  double amplitude = 0.3;         // Gaussian bump height
  double sigma = 0.3;             // its width
  double ripple_amplitude = 0.0;  // radial sine ripples added on top
  double ripple_wavelength = 0.2;
  double operator()(double x, double y) const;
};

}  // namespace iphong::geometry
