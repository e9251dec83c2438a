// Internal to the MGF reader (mgf_reader.cpp): its colour science
// (mgf_color.cpp) and the tessellation of its curved primitives
// (mgf_shapes.cpp). docs/scenes.md ("MGF") says what each does for users.
#pragma once

#include "radmesh/geometry.h"

#include <functional>
#include <string>
#include <vector>

namespace radmesh::internal::mgf {

// ---------------------------------------------------------------- colour

// A colour as MGF keeps it: a CIE 1931 (x, y) chromaticity; its luminance
// comes from what it modifies (rd, ed). The default is the equal-energy
// white (1/3, 1/3).
struct Chromaticity {
  double x = 1.0 / 3.0;
  double y = 1.0 / 3.0;
};

// The chromaticity of a relative spectrum sampled at `values.size()` evenly
// spaced wavelengths from lo to hi nm (MGF cspec: linear between samples,
// zero outside them), through the CIE 1931 2-degree colour matching
// functions over 380-780 nm. "" and *out set, or why not (no light in the
// visible range).
std::string spectrum_chromaticity(double lo, double hi, const std::vector<double>& values, Chromaticity* out);

// The chromaticity of a black body at `kelvin` (MGF cct, Planck's law).
// "" and *out set, or why not.
std::string black_body_chromaticity(double kelvin, Chromaticity* out);

// The chromaticity of colours added with weights of luminance (MGF cmix):
// the sum of their XYZ, each scaled to luminance weights[i].
Chromaticity mix(const std::vector<Chromaticity>& colors, const std::vector<double>& weights);

// The RGB, in Radiance's standard primaries (R 0.640 0.330, G 0.290 0.600,
// B 0.150 0.060, white the equal-energy 1/3 1/3), of the colour with
// chromaticity c and luminance Y. A chromaticity within 1e-12 of the
// white is grey, (Y, Y, Y) exactly. Negative components (outside the
// primaries' gamut) are set to 0, and *clipped says so where one was more
// than rounding (1e-12 of Y).
Rgb to_rgb(const Chromaticity& c, double luminance, bool* clipped);

// Radiance's luminous efficacy of white light (WHTEFFICACY), lm/W: MGF's
// ed (lm/m^2) divided by it is radiant exitance (W/m^2).
inline constexpr double kWhiteEfficacy = 179.0;

// ---------------------------------------------------------------- shapes

// One planar face of a tessellated primitive, in the primitive's own
// coordinates: its outline (counter-clockwise around its outward normal)
// and holes.
struct ShapeFace {
  std::vector<Vec3> outer;
  std::vector<std::vector<Vec3>> holes;
};
using FaceSink = std::function<void(ShapeFace&&)>;

// A face MGF writes as one loop with seams (f): around the outline, along
// a seam edge into a hole, around it and back along the same edge. Each
// pair of edges a -> b and b -> a is cut out, splitting the loop in two,
// until none is left; of the loops of 3 or more vertices, the largest is
// the outline, one inside it a hole (either way round), one outside it a
// face of its own (an island). False when no loop is left.
struct Seamed {
  std::vector<Vec3> outer;
  std::vector<std::vector<Vec3>> holes, islands;
};
bool split_at_seams(std::vector<Vec3> loop, Seamed* out);

// Segments that cut a full circle (2 pi) into chords whose sagitta is at
// most `deviation` times the radius (at least 3).
int circle_segments(double deviation);

// Each primitive's faces, given to `sink` one at a time (a sink may throw
// to stop). Radii are the primitive's as MGF gives them: a negative radius
// (length, for prism) turns the faces inward. Inputs are valid (the reader
// checks them): a positive tolerance, non-zero radii where needed, a unit
// `normal`, axis ends apart.
//
// A sphere: latitude bands about the z axis, quads between them and
// triangles at the poles; every face within tolerance x |radius| of the
// sphere.
void sphere(const Vec3& center, double radius, double tolerance, const FaceSink& sink);
// A truncated cone (cylinder: equal radii) from `a` (radius ra) to `b`
// (radius rb), open at both ends: one quad per segment (a triangle where a
// radius is 0).
void cone(const Vec3& a, double ra, const Vec3& b, double rb, double tolerance, const FaceSink& sink);
// A disc (rmin 0) or ring around `center` in the plane of `normal`, facing
// it: one face, the inner circle its hole.
void ring(const Vec3& center, const Vec3& normal, double rmin, double rmax, double tolerance, const FaceSink& sink);
// A torus around `center` in the plane of `normal`, from radius rmin to rmax
// (the tube's radius (rmax - rmin) / 2): one quad per segment of the ring
// and of the tube, each within tolerance x the tube's and the ring's radius.
void torus(const Vec3& center, const Vec3& normal, double rmin, double rmax, double tolerance, const FaceSink& sink);
// A closed prism: the polygon `base` (normal n by the right-hand rule),
// its copy moved by -length * n, and a quad per edge between them; faces
// outward for a positive length.
void prism(const std::vector<Vec3>& base, double length, const FaceSink& sink);

}  // namespace radmesh::internal::mgf
