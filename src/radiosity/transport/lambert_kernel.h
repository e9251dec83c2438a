// Lambert's contour sum of many (point, triangle) pairs at once: the inner
// loop of every quadrature of form factors. Internal to the radiosity module
// (not installed).
#pragma once

#include <cmath>
#include <cstddef>
#include <numbers>

namespace radmesh::internal {

// Struct of arrays: item i is the triangle with corners (a, b, c) relative
// to the point (a = corner - point, ...), all three on or in front of the
// point's tangent plane (normal n), so that nothing is clipped. out[i] is
// the signed contour sum: sum over the edges (a, b), (b, c), (c, a) of the
// angle the edge subtends times the n-component of the unit normal of the
// plane through the point and the edge. Its absolute value over 2 pi is the
// form factor.
struct LambertItems {
  const double* ax;
  const double* ay;
  const double* az;
  const double* bx;
  const double* by;
  const double* bz;
  const double* cx;
  const double* cy;
  const double* cz;
};
void lambert_triangle_sums(size_t count, const LambertItems& items, double nx, double ny, double nz, double* out);

// Struct of arrays of source triangles: corners a, b, c (absolute, not
// relative to a point) and the plane's unit normal m.
struct LambertSources {
  LambertItems corners;
  const double* mx;
  const double* my;
  const double* mz;
};
// What a point sees of one source, for lambert_point_sums.
constexpr double kSourceBehind = 0.0;   // the point lies on or behind the source's plane: it sends the point nothing
constexpr double kSourceInFront = 1.0;  // the source lies wholly on or in front of the point's tangent plane
constexpr double kSourceCrosses = 2.0;  // the source crosses that plane: it must be clipped first
// One point p (tangent-plane normal n) against `count` sources: kind[i] says
// which of the three cases above source i is, and out[i] is its contour sum
// relative to p (as lambert_triangle_sums would give for the corners less p)
// where kind[i] is kSourceInFront, anything finite otherwise. The corners
// less p, the heights over the tangent plane and the side of the source's
// plane are computed here as the scalar code would (same operations, same
// order), so the sums equal those of the corners packed one pair at a time.
void lambert_point_sums(size_t count, const LambertSources& s, double px, double py, double pz, double nx, double ny,
                        double nz, double* out, double* kind);

// tan(k pi / 16), k = 0..4, and the midpoints tan((2k + 1) pi / 32) between them.
constexpr double kTan[5] = {0.0, 0.19891236737965800691, 0.41421356237309504880, 0.66817863791929891999, 1.0};
constexpr double kMid[4] = {0.098491403357164253078, 0.30334668360734239167, 0.53451113595079149367,
                            0.82067879082866033568};

// atan2(s, d) for s >= 0: the angle between two vectors from the length s
// of their cross product and their dot product d. The octant reduction
// leaves a in [0, 1]; with c the nearest tan(k pi / 16), atan(a) =
// k pi / 16 + atan(u), u = (a - c) / (1 + a c), |u| <= tan(pi / 32) <
// 0.0985, where eight terms of the Taylor series leave u^17 / 17 < 1e-18,
// far below double rounding: the result agrees with libm's to a few ulp.
// No table and no branch (every select a blend), so that the
// kernel's loop vectorizes; the scalar Lambert sums use the same function.
inline double subtended_angle(double s, double d) {
  const double ad = std::abs(d);
  const bool steep = s > ad;
  const double big = steep ? s : ad;
  const double small = steep ? ad : s;
  const double a = big > 0.0 ? small / big : 0.0;
  double c = 0.0, k = 0.0;
  c = a > kMid[0] ? kTan[1] : c;
  k = a > kMid[0] ? 1.0 : k;
  c = a > kMid[1] ? kTan[2] : c;
  k = a > kMid[1] ? 2.0 : k;
  c = a > kMid[2] ? kTan[3] : c;
  k = a > kMid[2] ? 3.0 : k;
  c = a > kMid[3] ? kTan[4] : c;
  k = a > kMid[3] ? 4.0 : k;
  const double u = (a - c) / (1.0 + a * c);
  const double u2 = u * u;
  const double p =
      u * (1.0 + u2 * (-1.0 / 3.0 +
                       u2 * (1.0 / 5.0 +
                             u2 * (-1.0 / 7.0 +
                                   u2 * (1.0 / 9.0 + u2 * (-1.0 / 11.0 + u2 * (1.0 / 13.0 + u2 * (-1.0 / 15.0))))))));
  double r = k * (std::numbers::pi / 16.0) + p;
  r = steep ? 0.5 * std::numbers::pi - r : r;
  r = d < 0.0 ? std::numbers::pi - r : r;
  return big > 0.0 ? r : 0.0;
}

// One edge (p, q) of a contour, both relative to the point: the angle the
// edge subtends times the n-component of the unit normal of the plane
// through the point and the edge (0 for an edge seen end-on). The kernel
// and the scalar contour sum (form_factor.cpp) share it.
inline double lambert_edge(double px, double py, double pz, double qx, double qy, double qz, double nx, double ny,
                           double nz) {
  const double cx = py * qz - pz * qy, cy = pz * qx - px * qz, cz = px * qy - py * qx;
  const double s = std::sqrt(cx * cx + cy * cy + cz * cz);
  const double t = subtended_angle(s, px * qx + py * qy + pz * qz) * (nx * cx + ny * cy + nz * cz) / s;
  return s > 0.0 ? t : 0.0;
}

}  // namespace radmesh::internal
