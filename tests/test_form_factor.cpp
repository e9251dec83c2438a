// Form factors against closed forms (Howell's catalogue) and physical identities.

#include "radmesh/form_factor.h"
#include "radiosity/transport/lambert_kernel.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

using namespace radmesh;

namespace {

// Howell's catalogue, differential area parallel to an a x b rectangle at
// distance c, on the normal through one of its corners.
double corner_closed_form(double a, double b, double c) {
  const double A = a / c, B = b / c;
  return (A / std::sqrt(1 + A * A) * std::atan(B / std::sqrt(1 + A * A)) +
          B / std::sqrt(1 + B * B) * std::atan(A / std::sqrt(1 + B * B))) /
         (2.0 * std::numbers::pi);
}

// A quad as two triangles.
std::vector<Triangle> quad(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const Vec3 n = glm::normalize(glm::cross(b - a, c - a));
  return {make_triangle(a, b, c, n), make_triangle(a, c, d, n)};
}

// Area-weighted F between two triangle sets.
double set_form_factor(const std::vector<Triangle>& recv, const std::vector<Triangle>& src) {
  double num = 0.0, area = 0.0;
  for (const Triangle& r : recv) {
    area += r.area;
    for (const Triangle& s : src) num += r.area * element_form_factor(r, s);
  }
  return num / area;
}

}  // namespace

TEST(PointPolygon, UnderRectangleCornerMatchesClosedForm) {
  for (double c : {0.1, 1.0, 7.5}) {
    const double a = 2.0, b = 0.5;
    // Rectangle in z = c facing down; the point at the origin facing up, under a corner.
    const Vec3 pts[4] = {{0, 0, c}, {0, b, c}, {a, b, c}, {a, 0, c}};
    const double f = point_polygon_form_factor(Vec3(0), Vec3(0, 0, 1), pts, 4, Vec3(0, 0, -1));
    EXPECT_NEAR(f, corner_closed_form(a, b, c), 1e-14) << "c = " << c;
  }
}

TEST(PointPolygon, BackOfSourceAndBehindReceiverGiveZero) {
  const Vec3 pts[4] = {{0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1}};
  // The source faces up, away from the point below it.
  EXPECT_EQ(point_polygon_form_factor(Vec3(0), Vec3(0, 0, 1), pts, 4, Vec3(0, 0, 1)), 0.0);
  // The point faces down, away from the source.
  EXPECT_EQ(point_polygon_form_factor(Vec3(0), Vec3(0, 0, -1), pts, 4, Vec3(0, 0, -1)), 0.0);
}

TEST(PointPolygon, HalfSpaceClippingOfAStraddlingSource) {
  // A huge square source in the plane x = 1 facing -x; a point at the origin
  // facing +z sees only the half above z = 0: F = 1/2 of F to the full wall
  // for a point facing the wall... here: a wall perpendicular to the
  // receiver, infinite in extent, gives F = 1/2.
  const double L = 1e7;
  const Vec3 pts[4] = {{1, -L, -L}, {1, -L, L}, {1, L, L}, {1, L, -L}};
  const double f = point_polygon_form_factor(Vec3(0), Vec3(0, 0, 1), pts, 4, Vec3(-1, 0, 0));
  EXPECT_NEAR(f, 0.5, 1e-6);
}

namespace {

// A regular polygon of `count` vertices and circumradius r in the plane z =
// h, centred on the z axis, facing down (-z): vertices clockwise seen from
// above, counter-clockwise around its normal.
std::vector<Vec3> regular_polygon(int count, double r, double h, double phase = 0.0) {
  std::vector<Vec3> pts;
  for (int k = 0; k < count; ++k) {
    const double a = phase - 2.0 * std::numbers::pi * k / count;
    pts.emplace_back(r * std::cos(a), r * std::sin(a), h);
  }
  return pts;
}

// F from x to the polygon as the sum over its triangle fan from vertex 0,
// each triangle clipped on its own: an independent route to the same number
// (clipping and the contour integral are both additive over a partition).
double fan_form_factor(const Vec3& x, const Vec3& n, const std::vector<Vec3>& poly, const Vec3& normal) {
  double f = 0.0;
  for (size_t k = 1; k + 1 < poly.size(); ++k) {
    const Vec3 tri[3] = {poly[0], poly[k], poly[k + 1]};
    f += point_polygon_form_factor(x, n, tri, 3, normal);
  }
  return f;
}

}  // namespace

TEST(PointPolygon, ThousandVertexPolygonMatchesFanAndCoaxialDisk) {
  // Coaxial disk of radius r at height h: F = r^2 / (h^2 + r^2). The
  // inscribed 1000-gon has (1 - 6.6e-6) of the disk's area.
  for (double h : {0.5, 1.0, 3.0}) {
    const double r = 1.0;
    const auto poly = regular_polygon(1000, r, h);
    const double f = point_polygon_form_factor(Vec3(0), Vec3(0, 0, 1), poly.data(), poly.size(), Vec3(0, 0, -1));
    EXPECT_NEAR(f, fan_form_factor(Vec3(0), Vec3(0, 0, 1), poly, Vec3(0, 0, -1)), 1e-12) << "h = " << h;
    EXPECT_NEAR(f, r * r / (h * h + r * r), 1e-5) << "h = " << h;
  }
}

TEST(PointPolygon, ManyVertexPolygonStraddlingTheTangentPlaneIsClipped) {
  // The polygon lies in the plane x = 1 (facing -x) and straddles the
  // receiver's tangent plane z = 0: only its upper half may count. The old
  // implementation kept 32 vertices and clipped into a fixed array (a
  // 32-vertex polygon straddling the plane overflowed it).
  for (int count : {32, 33, 100, 1000}) {
    std::vector<Vec3> poly;
    for (int k = 0; k < count; ++k) {
      const double a = 2.0 * std::numbers::pi * k / count + 0.1;
      poly.emplace_back(1.0, 0.8 * std::cos(a), 0.8 * std::sin(a));  // counter-clockwise around -x seen from x < 1
    }
    const Vec3 x(0.0), n(0, 0, 1), normal(-1, 0, 0);
    const double f = point_polygon_form_factor(x, n, poly.data(), poly.size(), normal);
    const double fan = fan_form_factor(x, n, poly, normal);
    EXPECT_NEAR(f, fan, 1e-13) << count << " vertices";
    // The clipped value is strictly between zero and the unclipped one
    // (the same polygon seen by a receiver facing it, which clips nothing).
    const double unclipped = point_polygon_form_factor(x, Vec3(1, 0, 0), poly.data(), poly.size(), normal);
    EXPECT_GT(f, 0.05 * unclipped) << count;
    EXPECT_LT(f, 0.95 * unclipped) << count;
  }
}

TEST(ElementFormFactor, ParallelUnitSquaresHowellC11) {
  const auto bottom = quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0});  // faces +z
  const auto top = quad({0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1});     // faces -z
  const double f = set_form_factor(bottom, top);
  EXPECT_NEAR(f / 0.199825 - 1.0, 0.0, 1e-4) << f;
}

TEST(ElementFormFactor, PerpendicularSquaresSharingAnEdgeHowellC14) {
  const auto floor = quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0});  // faces +z
  const auto wall = quad({0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0});   // y = 0, faces +y
  const double f = set_form_factor(floor, wall);
  EXPECT_NEAR(f / 0.200044 - 1.0, 0.0, 1e-3) << f;
  // Reciprocity between equal areas: F(wall -> floor) = F(floor -> wall).
  EXPECT_NEAR(set_form_factor(wall, floor) / f - 1.0, 0.0, 1e-3);
}

TEST(ElementFormFactor, FacingAwayIsExactlyZero) {
  const auto a = quad({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0});   // faces +z
  const auto b = quad({0, 0, -1}, {1, 0, -1}, {1, 1, -1}, {0, 1, -1});  // faces +z, below a
  EXPECT_TRUE(facing_away(a[0], b[0]));
  EXPECT_TRUE(facing_away(a[0], a[1]));  // coplanar
}

TEST(Distance, PolygonInsideAndOutside) {
  const std::vector<Vec3> sq = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  EXPECT_DOUBLE_EQ(distance_to_polygon({0.5, 0.5, 2.0}, sq, {0, 0, 1}), 2.0);
  EXPECT_DOUBLE_EQ(distance_to_polygon({2.0, 0.5, 0.0}, sq, {0, 0, 1}), 1.0);
  EXPECT_NEAR(distance_to_polygon({2.0, 2.0, 1.0}, sq, {0, 0, 1}), std::sqrt(3.0), 1e-15);
}

TEST(SubtendedAngle, MatchesAtan2AcrossDecadesAndAtTheAxes) {
  // The table-free atan2 of Lambert's sums against libm: two ulp.
  uint64_t state = 12345;
  auto uniform = [&] {  // SplitMix64
    uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return static_cast<double>((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
  };
  double worst = 0.0;
  for (int i = 0; i < 200000; ++i) {
    const double s = std::exp(14.0 * uniform() - 7.0);
    const double d = (uniform() < 0.5 ? -1.0 : 1.0) * std::exp(14.0 * uniform() - 7.0);
    worst = std::max(worst, std::abs(radmesh::internal::subtended_angle(s, d) - std::atan2(s, d)) / std::atan2(s, d));
  }
  EXPECT_LT(worst, 5e-16);
  EXPECT_EQ(radmesh::internal::subtended_angle(0.0, 2.0), 0.0);
  EXPECT_EQ(radmesh::internal::subtended_angle(0.0, -2.0), std::numbers::pi);
  EXPECT_EQ(radmesh::internal::subtended_angle(3.0, 0.0), 0.5 * std::numbers::pi);
  EXPECT_EQ(radmesh::internal::subtended_angle(0.0, 0.0), 0.0);
  // The nearest sixteenth-turn boundaries (tan(k pi / 32)) on both sides.
  for (int k = 1; k < 8; k += 2) {
    const double t = std::tan(k * std::numbers::pi / 32.0);
    for (double a : {std::nextafter(t, 0.0), t, std::nextafter(t, 1.0)})
      EXPECT_NEAR(radmesh::internal::subtended_angle(a, 1.0), std::atan2(a, 1.0), 4e-16 * std::atan2(a, 1.0)) << k;
  }
}

TEST(ElementFormFactor, ManySourcesAtOnceEqualOneByOne) {
  // form_factors (the vectorized pass) against Lambert's scalar formula
  // point by point, on sources in front, straddling the receiver's tangent
  // plane (clipped), behind it and facing away. Many sources go point by
  // point (lambert_point_sums), one source pair by pair: the same sums.
  const Triangle receiver = make_triangle(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, -1), Vec3(0, 1, 0));
  const ReceiverPoints pts = receiver_points(receiver, [](const Vec3&) { return 0.0; }, {1.0, 2});
  ASSERT_EQ(pts.x.size(), 48u);
  std::vector<Triangle> sources;
  for (int i = 0; i < 40; ++i) {
    const double a = 0.37 * i, h = -0.6 + 0.05 * i;
    const Vec3 p(std::cos(a), h, std::sin(a) - 0.5), q = p + Vec3(0.4, 0.3, 0.1 * std::sin(3 * a)),
               r = p + Vec3(-0.2, 0.35, 0.5);
    const Vec3 normal = glm::normalize(glm::cross(q - p, r - p));
    sources.push_back(make_triangle(p, q, r, i % 3 == 0 ? -normal : normal));
  }
  std::vector<const Triangle*> ptrs;
  for (const Triangle& t : sources) ptrs.push_back(&t);
  std::vector<double> batch(sources.size());
  form_factors(pts, ptrs.data(), ptrs.size(), batch.data());
  int clipped = 0, zero = 0;
  for (size_t j = 0; j < sources.size(); ++j) {
    double expected = 0.0;
    for (size_t q = 0; q < pts.x.size(); ++q) {
      expected += pts.w[q] * point_polygon_form_factor(pts.x[q], pts.normal, sources[j].v.data(), 3, sources[j].normal);
      bool straddles = false;
      for (const Vec3& v : sources[j].v) straddles = straddles || glm::dot(v - pts.x[q], pts.normal) < 0.0;
      clipped += straddles;
    }
    zero += expected == 0.0;
    // A clipped quad goes through the kernel as two triangles, whose shared
    // edge's terms cancel to rounding (1.5e-13 of F here, 1e-14 unclipped).
    EXPECT_NEAR(batch[j], expected, 1e-12 * expected) << j;
    EXPECT_EQ(batch[j], form_factor(pts, sources[j])) << j;
  }
  EXPECT_GT(clipped, 100);  // the set covers the clipped path ...
  EXPECT_GT(zero, 5);       // ... and sources seen from behind
  EXPECT_LT(zero, 30);
}

TEST(ReceiverPoints, AConstantDistanceTakesTheWholeReceiverToUniformLevel) {
  // receiver_points with the same distance bound everywhere splits every
  // piece alike: the points of uniform_points at uniform_level's level,
  // 3 x 4^level of them, the same points in the same order.
  const Triangle t = make_triangle(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0.5, 1.5, 0), Vec3(0, 0, 1));
  const QuadratureOptions opt{1.0, 3};
  int seen[4] = {0, 0, 0, 0};
  for (double d = 0.0; d < 8.0; d += 0.05) {
    const ReceiverPoints graded = receiver_points(t, [d](const Vec3&) { return d; }, opt);
    const int level = uniform_level(t, d, opt);
    ASSERT_GE(level, 0);
    ASSERT_LE(level, 3);
    ++seen[level];
    const ReceiverPoints uniform = uniform_points(t, level);
    ASSERT_EQ(graded.x.size(), size_t{3} << (2 * level)) << d;
    ASSERT_EQ(uniform.x.size(), graded.x.size()) << d;
    double sum = 0.0;
    for (size_t i = 0; i < uniform.x.size(); ++i) {
      EXPECT_EQ(uniform.x[i], graded.x[i]) << d << " " << i;
      EXPECT_EQ(uniform.w[i], graded.w[i]) << d << " " << i;
      sum += uniform.w[i];
    }
    EXPECT_NEAR(sum, 1.0, 1e-14);
  }
  for (int level = 0; level <= 3; ++level) EXPECT_GT(seen[level], 0) << level;  // every level met
}
