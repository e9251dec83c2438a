// Form factors: Lambert's exact point-to-polygon formula and the quadrature
// of it over a receiving triangle.
#pragma once

#include "radmesh/geometry.h"

#include <algorithm>
#include <array>
#include <functional>
#include <vector>

namespace radmesh {

// Lambert's contour sum of one closed loop of vertices pts[0..count), any
// count, clipped to the half-space in front of x's tangent plane (unit
// normal n): sum over the clipped loop's edges of the angle the edge
// subtends at x times the n-component of the edge plane's unit normal. Its
// absolute value over 2 pi is the form factor from x to a planar polygon.
// Signed (the sign follows the loop's orientation), so that the loops of a
// polygon with holes can be summed one by one.
double lambert_contour_sum(const Vec3& x, const Vec3& n, const Vec3* pts, size_t count);

// Unoccluded form factor from a differential area at x with unit normal n to
// a planar polygon (vertices pts[0..count), any count) with unit normal
// `poly_normal`. Only the front of the polygon (the side its normal points
// to) emits; the part of the polygon behind x's tangent plane is clipped
// away. Exact (Lambert's contour integral).
double point_polygon_form_factor(const Vec3& x, const Vec3& n, const Vec3* pts, size_t count,
                                 const Vec3& poly_normal);

// A flat triangle with its unit normal, area and radius (made by make_triangle,
// so that pair loops do not recompute them).
struct Triangle {
  std::array<Vec3, 3> v;
  Vec3 normal{0.0};
  double area = 0.0;
  double radius = 0.0;  // largest distance from the centroid to a vertex
  Vec3 centroid() const { return (v[0] + v[1] + v[2]) / 3.0; }
};

Triangle make_triangle(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& normal);

// Quadrature of the point form factor over a receiving triangle: a 3-point
// degree-2 rule on a graded subdivision of the receiver. A piece is split in
// four while its size exceeds `closeness` times its distance to the nearest
// surface that can send it light, up to `max_level` levels: pieces next to a
// contact get many points, pieces far from everything get three.
//
// All sources of one receiver integrated at the same points make a row of
// form factors that sums to 1 up to rounding in a closed scene (Lambert's
// formula is exact at every point and the point form factors to a closed
// enclosure add up to 1): the matrix method does so. The hierarchical
// solver's leaves take each source at the level its own distance asks for
// (uniform_level), and allow for the quadrature in their rows.
struct QuadratureOptions {
  double closeness = 1.0;
  int max_level = 2;
};
constexpr int kMaxQuadratureLevel = 10;  // the largest max_level accepted (check_solve_options)

struct ReceiverPoints {
  Vec3 normal{0.0};
  std::vector<Vec3> x;
  std::vector<double> w;  // weights, summing to 1 (fractions of the receiver's area)
};

// `distance(p)` returns a lower bound of the distance from p to the nearest
// surface that can send light to the receiver.
ReceiverPoints receiver_points(const Triangle& receiver, const std::function<double(const Vec3&)>& distance,
                               const QuadratureOptions& options);

// Whether receiver_points splits a piece of longest edge `size` whose centre
// lies at least `distance` from the nearest source.
bool splits_piece(double size, double distance, const QuadratureOptions& options);
// Where every piece's distance bound is the same `distance`, receiver_points
// takes all of `receiver` to one level: this one.
int uniform_level(const Triangle& receiver, double distance, const QuadratureOptions& options);
// The points of `receiver` split `level` times everywhere (3 x 4^level).
ReceiverPoints uniform_points(const Triangle& receiver, int level);

// Unoccluded F(receiver -> source) = sum_q w_q F(x_q -> source).
double form_factor(const ReceiverPoints& receiver, const Triangle& source);

// The same for many sources at the same points at once: out[j] =
// form_factor(receiver, *sources[j]), j < count (all pairs in one
// vectorized pass: the cheaper way when a receiver has many sources).
void form_factors(const ReceiverPoints& receiver, const Triangle* const* sources, size_t count, double* out);

// The point form factors F(x_q -> source) at each point of `receiver` (its
// weights unused) into out[q], in the same vectorized pass.
void point_form_factors(const ReceiverPoints& receiver, const Triangle& source, double* out);

// F(receiver -> source) for one pair, with the points graded toward `source`.
double element_form_factor(const Triangle& receiver, const Triangle& source,
                           const QuadratureOptions& options = {});

// Distance from p to a triangle, and to a planar polygon (holes ignored: a lower bound).
double distance_to_triangle(const Vec3& p, const Triangle& t);

// The point form factor's kernel between x (normal n) and y (normal m),
// without its 1 / pi: max(0, n . r) max(0, -m . r) / |r|^4, r = y - x.
inline double point_kernel(const Vec3& x, const Vec3& n, const Vec3& y, const Vec3& m) {
  const Vec3 r = y - x;
  const double d2 = glm::dot(r, r);
  return std::max(0.0, glm::dot(n, r)) * std::max(0.0, -glm::dot(m, r)) / (d2 * d2);
}
double distance_to_polygon(const Vec3& p, const std::vector<Vec3>& poly, const Vec3& normal);

// True when no point of `source` lies strictly in front of `receiver`'s plane
// or no point of `receiver` lies strictly in front of `source`'s plane:
// then F is exactly zero in both directions.
bool facing_away(const Triangle& receiver, const Triangle& source);

}  // namespace radmesh
