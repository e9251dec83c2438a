// The gather field: exact direct light at every vertex, a final gather for
// the rest, against closed forms, the exact clip, energy balance and the
// thread count.

#include "radmesh/obj_reader.h"
#include "radmesh/errors.h"
#include "radmesh/direct.h"
#include "radmesh/error_metric.h"
#include "radmesh/field.h"
#include "radmesh/form_factor.h"
#include "radiosity/transport/gather_node.h"
#include "radmesh/method.h"
#include "radmesh/run.h"
#include "radiosity/transport/occlusion.h"
#include "radiosity/transport/transport.h"
#include "radiosity/transport/visibility.h"

#include "tests/test_util.h"

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <random>

using namespace radmesh;
using radmesh::test::patch_named;

namespace {
using radmesh::test::kData;

// Form factor from a differential area to a parallel a x b rectangle at
// distance c, the area lying under one of its corners (Howell B-3).
double corner_rectangle(double a, double b, double c) {
  if (a <= 0.0 || b <= 0.0) return 0.0;
  const double A = a / c, B = b / c;
  const double sa = std::sqrt(1.0 + A * A), sb = std::sqrt(1.0 + B * B);
  return (A / sa * std::atan(B / sa) + B / sb * std::atan(A / sb)) / (2.0 * std::numbers::pi);
}

MethodResult solve(const Scene& scene, const std::string& method, double max_edge, DiscontinuityMode lines,
                   SolveOptions so = {}, const OptionValues& options = {}) {
  const Method& m = find_method(method);
  MeshingOptions mo = m.meshing(scene);
  mo.max_edge = max_edge;
  mo.discontinuity = lines;
  return run_method(m, scene, mesh_scene(scene, mo), so, options);
}

// The display vertex's patch: that of the first triangle using it.
std::vector<int> vertex_patches(const MethodResult& r) {
  std::vector<int> patch(r.solution.nodal.points.size(), -1);
  for (size_t t = 0; t < r.mesh.triangles.size(); ++t)
    for (int d : r.solution.nodal.corners[t])
      if (patch[static_cast<size_t>(d)] < 0) patch[static_cast<size_t>(d)] = r.mesh.patch[t];
  return patch;
}
}  // namespace

TEST(Field, PlatesVertexValuesAreRhoTimesTheClosedFormFormFactor) {
  // One bounce: the emitter is black, the receiver does not see itself. At a
  // receiver point (px, py, 1) the unit square below splits into four
  // rectangles with a corner under the point.
  const Scene scene = read_obj_scene(kData + "/parallel_plates/parallel_plates.obj");
  const int receiver = patch_named(scene, "receiver");
  ASSERT_GE(receiver, 0);
  const MethodResult r = solve(scene, "matrix", 0.25, DiscontinuityMode::off);
  EXPECT_EQ(r.field.mode, FieldMode::gather);
  const auto patch = vertex_patches(r);
  int checked = 0;
  for (size_t d = 0; d < r.solution.nodal.points.size(); ++d) {
    const Vec3& p = r.solution.nodal.points[d];
    const double value = r.solution.nodal.radiosity[d].x;
    if (patch[d] != receiver) {
      EXPECT_EQ(value, 1.0);  // the emitter: E, nothing reflected
      continue;
    }
    const double f = corner_rectangle(p.x, p.y, 1.0) + corner_rectangle(1.0 - p.x, p.y, 1.0) +
                     corner_rectangle(p.x, 1.0 - p.y, 1.0) + corner_rectangle(1.0 - p.x, 1.0 - p.y, 1.0);
    // The field sees the scene snapped to 2^-33 of its size (FieldEvaluator),
    // which moves a value by up to its gradient times that: ~1e-11 here.
    EXPECT_NEAR(value, 0.5 * f, 1e-10) << p.x << " " << p.y;
    ++checked;
  }
  EXPECT_GT(checked, 20);
}

TEST(Field, FloatingOccluderVertexValuesAreTheExactDirectLight) {
  // A floor under a black square and a square light: one bounce, so every
  // floor vertex is rho E times the exactly clipped visible form factor,
  // shadow lines, penumbra and umbra included, whichever path the fast
  // direct pass took.
  const Scene scene = read_obj_scene(kData + "/floating_occluder/floating_occluder.obj");
  const int floor = patch_named(scene, "floor"), light = patch_named(scene, "light");
  ASSERT_GE(floor, 0);
  ASSERT_GE(light, 0);
  const MethodResult r = solve(scene, "matrix", 0.4, DiscontinuityMode::full);
  const DirectIllumination exact(scene);
  const auto patch = vertex_patches(r);
  double top = 0.0;
  for (const Rgb& b : r.solution.nodal.radiosity) top = std::max(top, b.x);
  ASSERT_GT(top, 0.0);
  int lit = 0, dark = 0, partial = 0;
  for (size_t d = 0; d < r.solution.nodal.points.size(); ++d) {
    if (patch[d] != floor) continue;
    const Vec3& x = r.solution.nodal.points[d];
    const double f = exact.visible_form_factor(x, Vec3(0, 1, 0), floor, light);
    const double unoccluded = exact.unoccluded_form_factor(x, Vec3(0, 1, 0), light);
    // To the snap of the field's frame (up to 2e-11 of top in the penumbra).
    EXPECT_NEAR(r.solution.nodal.radiosity[d].x, 0.5 * 10.0 * f, 1e-10 * top) << x.x << " " << x.z;
    if (f == 0.0) ++dark;
    else if (f < unoccluded) ++partial;
    else ++lit;
  }
  EXPECT_GT(lit, 0);
  EXPECT_GT(dark, 0);
  EXPECT_GT(partial, 0);
  // Every path of the direct pass was taken.
  EXPECT_GT(r.field.direct.unoccluded, 0);
  EXPECT_GT(r.field.direct.hidden, 0);
  EXPECT_GT(r.field.direct.clipped, 0);
}

TEST(Field, AVertexOnAContactLineTakesTheValueOfItsOwnSide) {
  // The floor vertices along the box's foot are split in two display
  // vertices: the one under the box is dark (nothing reaches it, exactly
  // 0), the one outside lit.
  const Scene scene = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  const int floor = patch_named(scene, "floor");
  ASSERT_GE(floor, 0);
  const MethodResult r = solve(scene, "matrix", 0.5, DiscontinuityMode::contacts);
  const auto patch = vertex_patches(r);
  int under = 0, outside = 0;
  for (size_t d = 0; d < r.solution.nodal.points.size(); ++d) {
    const Vec3& x = r.solution.nodal.points[d];
    if (patch[d] != floor) continue;
    const bool on_foot = std::max(std::abs(x.x), std::abs(x.z)) == 0.5;
    const bool inside = std::max(std::abs(x.x), std::abs(x.z)) < 0.5;
    const double value = r.solution.nodal.radiosity[d].x;
    if (inside) {
      EXPECT_EQ(value, 0.0) << x.x << " " << x.z;
    }
    if (!on_foot) continue;
    if (value == 0.0)
      ++under;
    else
      ++outside;
  }
  EXPECT_GT(under, 4);
  EXPECT_EQ(under, outside);
  EXPECT_GE(r.field.on_other_surface, under + outside);
}

// The power of a patch as its field shows it (each triangle's corner values'
// mean times its area) and as its elements hold it.
std::pair<double, double> field_and_element_power(const MethodResult& r, int patch) {
  double field = 0.0, elements = 0.0;
  for (int t = 0; t < r.mesh.triangle_count(); ++t) {
    if (r.mesh.patch[static_cast<size_t>(t)] != patch) continue;
    double mean = 0.0;
    for (int d : r.solution.nodal.corners[static_cast<size_t>(t)])
      mean += r.solution.nodal.radiosity[static_cast<size_t>(d)].x / 3.0;
    field += r.mesh.area(t) * mean;
    elements += r.mesh.area(t) * r.solution.element[static_cast<size_t>(t)].x;
  }
  return {field, elements};
}

TEST(Field, BesideARugAMillimetreAboveTheFloorTheFloorKeepsItsLight) {
  // The floor is cut along the rug's outline (a contact line at the mesh's
  // scale). Its vertices there used to take the value on the outline itself,
  // half lit, and the lit side's interpolation was dark over a whole
  // element: the field's floor power came out 7% below the elements'. Each
  // side's value is now taken ten gaps into that side.
  const Scene scene = test::room_with_panel(0.001, 1.0);
  const int floor = patch_named(scene, "floor");
  const MethodResult r = solve(scene, "matrix", 0.5, DiscontinuityMode::contacts);
  const auto [field, elements] = field_and_element_power(r, floor);
  std::printf("floor power beside a rug 1 mm up: field %.5f, elements %.5f\n", field, elements);
  EXPECT_NEAR(field / elements, 1.0, 0.01);
  // On the outline: a dark vertex under the rug and a lit one beside it.
  const auto patch = vertex_patches(r);
  int dark = 0, lit = 0;
  for (size_t d = 0; d < r.solution.nodal.points.size(); ++d) {
    const Vec3& x = r.solution.nodal.points[d];
    if (patch[d] != floor || std::max(std::abs(x.x), std::abs(x.z)) != 1.0) continue;
    const double b = r.solution.nodal.radiosity[d].x;
    if (b < 0.01 * elements / 16.0) ++dark;
    if (b > 0.7 * elements / 12.0) ++lit;
  }
  EXPECT_GT(dark, 4);
  EXPECT_EQ(dark, lit);
}

TEST(Field, BesideASlabAMillimetreThickTheFloorKeepsItsLight) {
  // A 2 x 2 slab 1 mm thick lying on the floor: its sides touch the floor
  // along its outline, and the floor's vertices there took the hair's
  // value, half lit by the 1 mm side: the field's floor power came out 2.9%
  // below its elements'. A touching patch under a tenth of the element's
  // scale high is a detail below it, like a rug's gap.
  const Scene scene = test::room_with(test::box_faces("slab", 1, Vec3(-1, 0, -1), Vec3(1, 0.001, 1)));
  const int floor = patch_named(scene, "floor");
  const MethodResult r = solve(scene, "matrix", 0.5, DiscontinuityMode::contacts);
  const auto [field, elements] = field_and_element_power(r, floor);
  std::printf("floor power around a slab 1 mm thick: field %.5f, elements %.5f\n", field, elements);
  EXPECT_NEAR(field / elements, 1.0, 0.01);
}

TEST(Field, AFurnaceWithABlockInsideIsUniformAtEveryVertexEvenOnItsCreases) {
  // A closed room and a floating block, everything emitting 1 with
  // reflectance 0.8: B = 5 everywhere. Refinement leaves T-vertices on the
  // room's creases that only zero-area triangles use; gathered on the
  // crease itself (no area around them to step into) they came out 41% low.
  std::vector<RawFace> faces = test::box_faces("box", 0, {0, 0, 0}, {1, 1, 1}, false);
  for (const RawFace& f : test::box_faces("box", 0, {0.3, 0.2, 0.3}, {0.6, 0.5, 0.6})) faces.push_back(f);
  const Scene scene = build_scene(faces, {test::material("f", Rgb(0.8), Rgb(1.0))}, "furnace with a block");
  SolveOptions so;
  so.field = FieldMode::gather;
  const MethodResult r = solve(scene, "hierarchical", 0.35, DiscontinuityMode::contacts, so, {{"epsilon", "0.004"}});
  int zero_area = 0;
  for (int t = 0; t < r.mesh.triangle_count(); ++t) zero_area += r.mesh.zero_area(t) ? 1 : 0;
  EXPECT_GT(zero_area, 0);
  double lo = 1e300, hi = 0.0;
  for (const Rgb& b : r.solution.nodal.radiosity) {
    lo = std::min(lo, b.x);
    hi = std::max(hi, b.x);
  }
  std::printf("[field] furnace with a block: vertex values in [%.4f, %.4f] (exact 5)\n", lo, hi);
  // The solve's own spread (sampled visibility near the block) is a few
  // percent at reflectance 0.8; the crease vertices were 41% off.
  EXPECT_GT(lo, 0.95 * 5.0);
  EXPECT_LT(hi, 1.05 * 5.0);
}

TEST(Field, IsTheSameWithOneAndTwoThreads) {
  const Scene scene = read_obj_scene(kData + "/cornell_box/cornell_box.obj");
  SolveOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const MethodResult a = solve(scene, "hierarchical", 200.0, DiscontinuityMode::contacts, one, {{"epsilon", "0.01"}});
  const MethodResult b = solve(scene, "hierarchical", 200.0, DiscontinuityMode::contacts, two, {{"epsilon", "0.01"}});
  ASSERT_EQ(a.solution.nodal.radiosity.size(), b.solution.nodal.radiosity.size());
  for (size_t d = 0; d < a.solution.nodal.radiosity.size(); ++d)
    ASSERT_EQ(a.solution.nodal.radiosity[d], b.solution.nodal.radiosity[d]) << d;
  EXPECT_GT(a.field.rays_cast, 0);
  EXPECT_EQ(a.field.rays_cast, b.field.rays_cast);
}

TEST(Field, PatchMeansOfAClosedRoomBalanceTheEnergy) {
  // A closed room with a block and a ceiling light, every surface grey: what
  // the light emits is absorbed somewhere. A surface of reflectance rho and
  // mean radiosity B absorbs (1 - rho) / rho (B - E) per unit area, so the
  // field's patch means must account for the emitted power.
  const test::TempDir dir;
  {
    std::ofstream mtl(dir / "room.mtl");
    mtl << "newmtl grey\nKd 0.6 0.6 0.6\nnewmtl light\nKd 0.3 0.3 0.3\nKe 10 10 10\n";
    std::ofstream obj(dir / "room.obj");
    obj << "mtllib room.mtl\n"
           // the room [0,2]^3, faces pointing inwards
           "v 0 0 0\nv 2 0 0\nv 2 0 2\nv 0 0 2\nv 0 2 0\nv 2 2 0\nv 2 2 2\nv 0 2 2\n"
           // the light in the ceiling and the block [0.5,1]x[0,0.8]x[0.5,1.2]
           "v 0.8 2 0.8\nv 1.2 2 0.8\nv 1.2 2 1.2\nv 0.8 2 1.2\n"
           "v 0.5 0 0.5\nv 1 0 0.5\nv 1 0 1.2\nv 0.5 0 1.2\nv 0.5 0.8 0.5\nv 1 0.8 0.5\nv 1 0.8 1.2\nv 0.5 0.8 1.2\n"
           "usemtl grey\n"
           "o floor\nf 1 4 3 2\no back\nf 1 2 6 5\no front\nf 4 8 7 3\no left\nf 1 5 8 4\no right\nf 2 3 7 6\n"
           "o ceiling\nf 5 6 10 9\nf 6 7 11 10\nf 7 8 12 11\nf 8 5 9 12\n"
           "o block\nf 17 20 19 18\nf 13 17 18 14\nf 16 15 19 20\nf 13 16 20 17\nf 14 18 19 15\n"
           "usemtl light\no light\nf 9 10 11 12\n";
  }
  const Scene scene = read_obj_scene((dir / "room.obj").string());
  const MethodResult r = solve(scene, "matrix", 0.25, DiscontinuityMode::full);
  const std::vector<Rgb> mean = patch_mean_radiosity(scene, r.mesh, r.solution.nodal);
  double emitted = 0.0, absorbed = 0.0;
  for (size_t p = 0; p < scene.patches.size(); ++p) {
    const Material& m = scene.material_of(static_cast<int>(p));
    const double area = scene.patch_area(static_cast<int>(p));
    emitted += area * m.emission.x;
    absorbed += area * (1.0 - m.reflectance.x) / m.reflectance.x * (mean[p].x - m.emission.x);
  }
  // Measured 0.39% low (the field is linear between vertices, the gather samples
  // visibility): within 1%.
  EXPECT_NEAR(absorbed / emitted, 1.0, 1e-2);
}

TEST(Field, ModesParseAndAnUnknownOneIsAnInputError) {
  EXPECT_EQ(parse_field_mode("gather"), FieldMode::gather);
  EXPECT_EQ(parse_field_mode("fit"), FieldMode::fit);
  EXPECT_EQ(parse_field_mode("mean"), FieldMode::mean);
  for (FieldMode m : {FieldMode::gather, FieldMode::fit, FieldMode::mean}) EXPECT_EQ(parse_field_mode(to_string(m)), m);
  const test::Thrown t = test::thrown<InputError>([] { parse_field_mode("smooth"); });
  EXPECT_TRUE(t.names("field"));
  EXPECT_TRUE(test::contains(t.message, "smooth")) << t.message;
}

namespace {
// A square node of side h centred at the origin of the plane y = 0 (normal
// +y), as two triangles (split along a diagonal) reflecting r1 and r2.
struct SquareNode {
  Triangle t1, t2;
  internal::GatherNode node;
  SquareNode(double h, double r1, double r2) {
    const Vec3 up(0.0, 1.0, 0.0);
    const Vec3 a(-h / 2, 0, -h / 2), b(h / 2, 0, -h / 2), c(h / 2, 0, h / 2), d(-h / 2, 0, h / 2);
    t1 = make_triangle(a, d, c, up);
    t2 = make_triangle(a, c, b, up);
    node = internal::gather_node({&t1, &t2}, {Rgb(r1), Rgb(r2)}, up);
  }
};
}  // namespace

TEST(Field, ANodeTakenWholeIsExactToThirdOrderInItsSize) {
  // Seen from a tilted point, the node's form factor from its moments
  // (the kernel's Taylor expansion to second order) against Lambert's
  // exact formula on its two triangles: halving the node must cut the
  // error at least 8-fold (third order), where the point form factor at
  // the centroid (second order) cuts it only about 4-fold.
  const Vec3 x(0.6, 1.0, 0.3), n = glm::normalize(Vec3(-0.3, -1.0, 0.2)), up(0.0, 1.0, 0.0);
  double expanded[2], point[2];
  for (int k = 0; k < 2; ++k) {
    const SquareNode s(0.4 / (1 << k), 1.0, 1.0);
    const double exact = point_polygon_form_factor(x, n, s.t1.v.data(), 3, up) +
                         point_polygon_form_factor(x, n, s.t2.v.data(), 3, up);
    const internal::NodeTerm t = internal::node_term(s.node, x, n, up);
    ASSERT_TRUE(t.smooth);
    const Vec3 r = s.node.centre - x;
    point[k] = std::abs(glm::dot(n, r) * -glm::dot(up, r) * s.node.area / (std::numbers::pi * std::pow(glm::dot(r, r), 2)) - exact) / exact;
    expanded[k] = std::abs(t.f - exact) / exact;
  }
  EXPECT_GT(point[0] / point[1], 3.0);
  EXPECT_LT(point[0] / point[1], 5.0);
  EXPECT_GT(expanded[0] / expanded[1], 8.0);
  EXPECT_LT(expanded[0], point[0] / 4.0);
}

TEST(Field, ANodesFirstMomentTakesTheRadiosityWhereTheKernelIsLarger) {
  // The two halves of the node reflect 1 and 3: the integral of K R is
  // exact as R1 F1 + R2 F2. The node's mean radiosity times its form factor
  // is off at first order in the node's size; with the first moment's term
  // at second order (halving the node cuts the error at least 3.5-fold,
  // the mean's about 2-fold).
  const Vec3 x(0.6, 1.0, 0.3), n = glm::normalize(Vec3(-0.3, -1.0, 0.2)), up(0.0, 1.0, 0.0);
  double with[2], without[2];
  for (int k = 0; k < 2; ++k) {
    const SquareNode s(0.4 / (1 << k), 1.0, 3.0);
    const double exact = 1.0 * point_polygon_form_factor(x, n, s.t1.v.data(), 3, up) +
                         3.0 * point_polygon_form_factor(x, n, s.t2.v.data(), 3, up);
    const internal::NodeTerm t = internal::node_term(s.node, x, n, up);
    with[k] = std::abs(t.f * s.node.reflected.x + t.first.x - exact) / exact;
    without[k] = std::abs(t.f * s.node.reflected.x - exact) / exact;
  }
  EXPECT_GT(without[0] / without[1], 1.5);
  EXPECT_LT(without[0] / without[1], 2.5);
  EXPECT_GT(with[0] / with[1], 3.5);
  EXPECT_LT(with[0], without[0] / 4.0);
}

TEST(Field, AShaftClearedByTheListedOccludersHoldsNone) {
  // The gather lists once what may lie between a point and a whole source,
  // then tests each part of the source against that list only. Where that
  // says clear, no segment from the point to the part may meet a patch
  // (checked with Embree); and wherever the part's own shaft test says
  // clear, the listed test says so too. Random points on the Cornell box's
  // surfaces, random sub-triangles of the other patches' triangles.
  const Scene scene = read_obj_scene(kData + "/cornell_box/cornell_box.obj");
  const Mesh coarse = triangulate_patches(scene);
  const Occlusion occlusion(scene);
  const Visibility rays(scene);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::uniform_int_distribution<int> pick(0, coarse.triangle_count() - 1);
  auto point_in = [&](int t) {
    const auto& tri = coarse.triangles[static_cast<size_t>(t)];
    double a = u01(rng), b = u01(rng);
    if (a + b > 1.0) {
      a = 1.0 - a;
      b = 1.0 - b;
    }
    const Vec3& p0 = coarse.positions[static_cast<size_t>(tri[0])];
    return p0 + a * (coarse.positions[static_cast<size_t>(tri[1])] - p0) +
           b * (coarse.positions[static_cast<size_t>(tri[2])] - p0);
  };
  int listed_clear = 0, only_listed_clear = 0, listed = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const int tx = pick(rng), ts = pick(rng);
    const int px = coarse.patch[static_cast<size_t>(tx)], q = coarse.patch[static_cast<size_t>(ts)];
    if (px == q || !occlusion.facing(px, q) || !occlusion.may_occlude(px, q)) continue;
    const Vec3 nx = scene.patches[static_cast<size_t>(px)].normal;
    const Vec3 x = point_in(tx);
    const Triangle part = make_triangle(point_in(ts), point_in(ts), point_in(ts), scene.patches[static_cast<size_t>(q)].normal);
    if (!(part.area > 0.0)) continue;
    const Occlusion::Candidates c = occlusion.candidates(px, x, nx, q);
    listed += !c.all;
    const bool alone = occlusion.may_occlude(px, x, nx, q, part);
    const bool with_list = occlusion.may_occlude(c, px, x, nx, q, part);
    if (!alone) {
      EXPECT_FALSE(with_list) << trial;
    }
    if (with_list) continue;
    ++listed_clear;
    only_listed_clear += alone;
    for (int k = 0; k < 32; ++k) {
      double a = u01(rng), b = u01(rng);
      if (a + b > 1.0) {
        a = 1.0 - a;
        b = 1.0 - b;
      }
      const Vec3 y = part.v[0] + a * (part.v[1] - part.v[0]) + b * (part.v[2] - part.v[0]);
      // Segments between points in front of each other's planes: the only
      // ones that carry light (the shaft test's claim).
      if (glm::dot(y - x, nx) <= 0.0 || glm::dot(x - y, part.normal) <= 0.0) continue;
      ASSERT_TRUE(rays.visible_off_surfaces(x, nx, y, part.normal, px, q)) << "trial " << trial;
    }
  }
  std::printf("[field] %d of the listings short, %d parts clear by the list, %d of them not by their own test\n",
              listed, listed_clear, only_listed_clear);
  EXPECT_GT(listed, 100);
  EXPECT_GT(listed_clear, 100);
  EXPECT_GT(only_listed_clear, 0);
}

namespace {
// A grid of k x k open-bottomed boxes 0.25 wide and 0.3 tall standing on
// the floor of test::room_with (a 4 m room lit by a hanging lamp).
std::vector<RawFace> box_grid(int k) {
  std::vector<RawFace> faces;
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j) {
      const double x = -1.5 + 3.0 * i / (k - 1), z = -1.5 + 3.0 * j / (k - 1);
      std::vector<RawFace> box = test::box_faces("boxes", 1, {x - 0.125, 0.0, z - 0.125}, {x + 0.125, 0.3, z + 0.125});
      box.pop_back();  // the bottom, on the floor
      faces.insert(faces.end(), box.begin(), box.end());
    }
  return faces;
}

// test::room_with(box_grid(k)), solved by the matrix method (max edge 0.5,
// contact lines).
struct BoxRoom {
  Scene scene;
  MethodResult result;
};
BoxRoom solved_box_room(int k) {
  BoxRoom room{test::room_with(box_grid(k)), {}};
  room.result = solve(room.scene, "matrix", 0.5, DiscontinuityMode::contacts);
  return room;
}

// Every triangle of positive area of `mesh`: its centroid and patch.
std::vector<std::pair<Vec3, int>> triangle_centroids(const Mesh& mesh) {
  std::vector<std::pair<Vec3, int>> out;
  for (int t = 0; t < mesh.triangle_count(); ++t)
    if (!mesh.zero_area(t)) out.emplace_back(mesh.centroid(t), mesh.patch[static_cast<size_t>(t)]);
  return out;
}
}  // namespace

TEST(Field, TheClusteredGatherAgreesWithTheGatherOverEveryPatch) {
  // A room holding 36 boxes (187 patches), solved once; the indirect light
  // gathered at every triangle's centroid over every patch and by the
  // cluster tree over them (far clusters of patches taken whole), with 16
  // rays per node so that the rays' noise does not hide a bias. Per object
  // the two area means must agree to 0.5% (measured within 0.1%), and each
  // point to 10% of the object's mean.
  const auto [scene, r] = solved_box_room(6);
  SolveOptions so;
  so.rays = 64;
  const FieldEvaluator every(scene, r.mesh, r.solution.element, so, GatherSources::every_patch);
  const FieldEvaluator clustered(scene, r.mesh, r.solution.element, so, GatherSources::clustered);
  EXPECT_FALSE(every.clustered());
  ASSERT_TRUE(clustered.clustered());
  const auto points = triangle_centroids(r.mesh);
  std::vector<Rgb> a(points.size()), b(points.size());
  FieldReport ra, rb;
  for (size_t i = 0; i < points.size(); ++i) {
    a[i] = every.indirect(points[i].first, points[i].second, i, ra);
    b[i] = clustered.indirect(points[i].first, points[i].second, i, rb);
  }
  std::printf("[field] per point: %lld patches gathered over every patch; by clusters %lld patches and %lld clusters\n",
              ra.gather_sources, rb.gather_sources, rb.gather_clusters);
  EXPECT_EQ(ra.gather_clusters, 0);
  EXPECT_GT(rb.gather_clusters, static_cast<long long>(points.size()));
  EXPECT_LT(rb.gather_sources, ra.gather_sources / 2);
  std::map<std::string, std::array<double, 3>> sums;  // area x a, area x b, area
  for (size_t i = 0; i < points.size(); ++i) {
    const std::string& name = scene.patches[static_cast<size_t>(points[i].second)].name;
    auto& s = sums[name];
    s[0] += a[i].x;
    s[1] += b[i].x;
    s[2] += 1.0;
  }
  for (const auto& [name, s] : sums) {
    if (!(s[0] > 0.0)) continue;
    std::printf("[field] %s: indirect mean over every patch %.5f, by clusters %.5f (%+.3f%%)\n", name.c_str(),
                s[0] / s[2], s[1] / s[2], 100.0 * (s[1] / s[0] - 1.0));
    EXPECT_NEAR(s[1] / s[0], 1.0, 5e-3) << name;
  }
  for (size_t i = 0; i < points.size(); ++i) {
    const auto& s = sums[scene.patches[static_cast<size_t>(points[i].second)].name];
    EXPECT_NEAR(b[i].x, a[i].x, 0.1 * s[0] / s[2]) << i;
  }
}

TEST(Field, EachPartsShadowRaysFollowItsShareOfWhatThePointGathers) {
  // The room of 16 boxes: every part that sends light and whose shaft may
  // be blocked casts options.rays / 4 rays when the point's solved value is
  // unknown (0), one when it is so large that every part's share is
  // negligible, and options.rays / 2 when it is so small that every part's
  // is large (the lamp's parts, reflecting nothing, cast none). With the
  // solved values themselves the rays fall, and the gathered light stays
  // what the uniform rays give: the split changes the noise, not the mean.
  const auto [scene, r] = solved_box_room(4);
  SolveOptions so;
  so.rays = 16;
  const FieldEvaluator field(scene, r.mesh, r.solution.element, so, GatherSources::every_patch);
  const auto points = triangle_centroids(r.mesh);
  const std::vector<Rgb> solved = element_values(scene, r.mesh, r.solution.element, [&] {
    std::vector<SurfaceSample> at;
    for (const auto& [x, patch] : points) at.push_back({patch, x, 1.0});
    return at;
  }());
  FieldReport unknown, huge, tiny, own;
  std::map<std::string, std::array<double, 2>> sums;  // uniform, own rays
  for (size_t i = 0; i < points.size(); ++i) {
    const auto& [x, patch] = points[i];
    const Material& m = scene.material_of(patch);
    const Rgb u = field.indirect(x, patch, i, unknown, 0.0);
    field.indirect(x, patch, i, huge, 1e300);
    field.indirect(x, patch, i, tiny, 1e-300);
    const double value = max3(solved[i] - m.emission) / max3(m.reflectance);
    const Rgb o = field.indirect(x, patch, i, own, value);
    auto& s = sums[scene.patches[static_cast<size_t>(patch)].name];
    s[0] += u.x;
    s[1] += o.x;
  }
  std::printf("[field] shadow rays: uniform %lld, shares negligible %lld, large %lld, the solve's values %lld\n",
              unknown.rays_cast, huge.rays_cast, tiny.rays_cast, own.rays_cast);
  ASSERT_GT(huge.rays_cast, 1000);
  EXPECT_EQ(unknown.rays_cast, 4 * huge.rays_cast);
  EXPECT_EQ(tiny.rays_cast, 8 * huge.rays_cast);
  EXPECT_LT(own.rays_cast, unknown.rays_cast);
  EXPECT_GT(own.rays_cast, huge.rays_cast);
  for (const auto& [name, s] : sums) {
    if (!(s[0] > 0.0)) continue;
    std::printf("[field] %s: gathered with uniform rays %.5f, by shares %.5f (%+.3f%%)\n", name.c_str(), s[0], s[1],
                100.0 * (s[1] / s[0] - 1.0));
    EXPECT_NEAR(s[1] / s[0], 1.0, 0.01) << name;
  }
}

TEST(Field, TheClusteredGatherOfAFurnaceOfManyPatchesIsUniform) {
  // A closed room and 27 floating blocks, every surface emitting 1 with
  // reflectance 0.8: B = 5 everywhere. Given element radiosity 5, the
  // field at any point is 1 + 0.8 (the exact direct light of every
  // emitter, whose visible form factors sum to 1) + 0.8 x 4 x (the
  // gathered form factors, visibility included): 5 where they sum to 1.
  // The clustered gather's far clusters are point form factors at their
  // groups' centroids, not scaled to an exact sum: every point within 2%,
  // their mean within 0.5%.
  std::vector<RawFace> faces = test::box_faces("room", 0, {0, 0, 0}, {3, 3, 3}, false);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) {
        const Vec3 lo(0.6 + 0.8 * i, 0.6 + 0.8 * j, 0.6 + 0.8 * k);
        for (const RawFace& f : test::box_faces("block", 0, lo, lo + Vec3(0.3))) faces.push_back(f);
      }
  const Scene scene = build_scene(faces, {test::material("f", Rgb(0.8), Rgb(1.0))}, "furnace of blocks");
  MeshingOptions mo = find_method("matrix").meshing(scene);
  mo.max_edge = 0.25;
  mo.discontinuity = DiscontinuityMode::off;
  const Mesh mesh = mesh_scene(scene, mo);
  const std::vector<Rgb> element(mesh.triangles.size(), Rgb(5.0));
  SolveOptions so;
  so.rays = 64;
  const FieldEvaluator clustered(scene, mesh, element, so, GatherSources::clustered);
  const FieldEvaluator every(scene, mesh, element, so, GatherSources::every_patch);
  ASSERT_TRUE(clustered.clustered());
  std::vector<std::pair<Vec3, int>> points;
  const auto all = triangle_centroids(mesh);
  for (size_t i = 0; i < all.size(); i += 3) points.push_back(all[i]);
  double lo = 1e300, hi = 0.0, sum = 0.0, every_lo = 1e300, every_hi = 0.0;
  FieldReport report;
  for (size_t i = 0; i < points.size(); ++i) {
    const double b = clustered.radiosity(points[i].first, points[i].second, i, report).x;
    lo = std::min(lo, b);
    hi = std::max(hi, b);
    sum += b;
    FieldReport ignored;
    const double e = every.radiosity(points[i].first, points[i].second, i, ignored).x;
    every_lo = std::min(every_lo, e);
    every_hi = std::max(every_hi, e);
  }
  const double mean = sum / static_cast<double>(points.size());
  std::printf("[field] clustered furnace of %zu patches: %zu points in [%.4f, %.4f] (over every patch [%.4f, %.4f]), "
              "mean %.4f (exact 5), %lld clusters taken\n",
              scene.patches.size(), points.size(), lo, hi, every_lo, every_hi, mean, report.gather_clusters);
  EXPECT_GT(report.gather_clusters, static_cast<long long>(points.size()));
  EXPECT_NEAR(mean, 5.0, 0.025);
  EXPECT_GT(lo, 0.98 * 5.0);
  EXPECT_LT(hi, 1.02 * 5.0);
}

TEST(Field, PatchesNearAPointAreFoundByTheBoxTree) {
  // Occlusion::patches_near against every patch's distance: all patches
  // within r are listed, in increasing order, on the Cornell box.
  const Scene scene = read_obj_scene(kData + "/cornell_box/cornell_box.obj");
  const Occlusion occlusion(scene);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-50.0, 600.0), ur(0.0, 200.0);
  std::vector<int> near;
  long long found = 0;
  for (int trial = 0; trial < 500; ++trial) {
    const Vec3 x(u(rng), u(rng), u(rng));
    const double r = ur(rng);
    occlusion.patches_near(x, r, near);
    EXPECT_TRUE(std::is_sorted(near.begin(), near.end()));
    for (int p = 0; p < static_cast<int>(scene.patches.size()); ++p) {
      if (occlusion.distance(p, x) <= r) {
        EXPECT_TRUE(std::binary_search(near.begin(), near.end(), p)) << trial << " " << p;
      }
    }
    found += static_cast<long long>(near.size());
  }
  EXPECT_GT(found, 500);
  EXPECT_LT(found, 500LL * static_cast<long long>(scene.patches.size()));
}

// The parallel plates (the emitter at z = 0 facing up, the receiver at
// z = 1 facing down) and segments from 40 points under the lower plate,
// along a diagonal, to the mirror points at height `top`.
struct PlateSegments {
  Scene scene = read_obj_scene(kData + "/parallel_plates/parallel_plates.obj");
  int emitter = patch_named(scene, "emitter"), receiver = patch_named(scene, "receiver");
  std::vector<Vec3> from, to;
  explicit PlateSegments(double top) {
    for (int i = 0; i < 40; ++i) {
      const double s = 0.2 + 0.015 * i;
      from.emplace_back(s, 1.0 - s, -0.5);
      to.emplace_back(1.0 - s, s, top);
    }
  }
};

TEST(Field, EachSegmentIgnoresItsOwnPatch) {
  // Visibility::visible_each: segments from under the lower plate to
  // points above it, through it. Ignoring that plate for every other
  // segment, in one call, those get through and the others are blocked.
  const PlateSegments p(0.5);
  ASSERT_GE(p.emitter, 0);
  ASSERT_GE(p.receiver, 0);
  const Visibility rays(p.scene);
  std::vector<int> ignore;
  for (size_t i = 0; i < p.from.size(); ++i) ignore.push_back(i % 2 ? p.emitter : -1);
  std::vector<unsigned char> seen(p.from.size(), 2);
  rays.visible_each(p.from.data(), p.to.data(), p.from.size(), p.receiver, ignore.data(), seen.data());
  for (size_t i = 0; i < seen.size(); ++i) EXPECT_EQ(seen[i], i % 2 ? 1 : 0) << i;
}

TEST(Field, EachLiftedSegmentIgnoresItsOwnTwoPatches) {
  // Visibility::visible_off_surfaces_each: segments from under the plates
  // to points over them cross both. In one call, each segment ignores its
  // own pair of patches: both plates (either way round) lets it through,
  // one alone does not; every answer is the one the single-segment query
  // gives.
  const PlateSegments p(1.5);
  ASSERT_GE(p.emitter, 0);
  ASSERT_GE(p.receiver, 0);
  const Visibility rays(p.scene);
  const std::array<std::pair<int, int>, 4> ignored = {
      {{p.emitter, p.receiver}, {p.receiver, p.emitter}, {p.emitter, -1}, {-1, p.receiver}}};
  const size_t n = p.from.size();
  const std::vector<Vec3> up(n, Vec3(0.0, 0.0, 1.0)), down(n, Vec3(0.0, 0.0, -1.0));
  std::vector<int> a, b;
  for (size_t i = 0; i < n; ++i) {
    a.push_back(ignored[i % 4].first);
    b.push_back(ignored[i % 4].second);
  }
  std::vector<unsigned char> seen(n, 2);
  rays.visible_off_surfaces_each(p.from.data(), up.data(), p.to.data(), down.data(), a.data(), b.data(), n, seen.data());
  for (size_t i = 0; i < n; ++i) {
    EXPECT_EQ(seen[i], i % 4 < 2 ? 1 : 0) << i;
    EXPECT_EQ(seen[i] != 0, rays.visible_off_surfaces(p.from[i], up[i], p.to[i], down[i], a[i], b[i])) << i;
  }
}

TEST(Field, TheClusteredGatherOfAConvexRoomOfTilesIsUniformWithoutRays) {
  // A closed cube room whose walls are 10 x 10 tiles each (600 patches):
  // a convex enclosure, so no shadow rays at all, and the far clusters'
  // groups send their area-mean radiosity. Everything emits 1 with
  // reflectance 0.8 and element radiosity 5: the field is 5 wherever the
  // gathered form factors sum to 1. Deterministic, so a tighter bound than
  // with rays: every point within 0.3% (measured 0.02-0.09% high).
  std::vector<RawFace> faces;
  const int k = 10;
  for (int f = 0; f < 6; ++f)
    for (int i = 0; i < k; ++i)
      for (int j = 0; j < k; ++j) {
        const double a0 = static_cast<double>(i) / k, a1 = static_cast<double>(i + 1) / k;
        const double b0 = static_cast<double>(j) / k, b1 = static_cast<double>(j + 1) / k;
        // Face f: axis f / 2 at 0 or 1, the tile's corners counter-clockwise
        // seen from inside.
        const int axis = f / 2;
        const double at = f % 2;
        auto point = [&](double a, double b) {
          Vec3 p(0.0);
          p[axis] = at;
          p[(axis + 1) % 3] = a;
          p[(axis + 2) % 3] = b;
          return p;
        };
        RawFace t;
        t.name = "tile";
        t.material = 0;
        t.points = {point(a0, b0), point(a1, b0), point(a1, b1), point(a0, b1)};
        if (f % 2) std::reverse(t.points.begin(), t.points.end());
        faces.push_back(t);
      }
  const Scene scene = build_scene(faces, {test::material("f", Rgb(0.8), Rgb(1.0))}, "tiled cube");
  ASSERT_EQ(scene.patches.size(), 600u);
  MeshingOptions mo = find_method("matrix").meshing(scene);
  mo.max_edge = 0.1;
  mo.discontinuity = DiscontinuityMode::off;
  const Mesh mesh = mesh_scene(scene, mo);
  const std::vector<Rgb> element(mesh.triangles.size(), Rgb(5.0));
  const FieldEvaluator clustered(scene, mesh, element, SolveOptions{}, GatherSources::clustered);
  ASSERT_TRUE(clustered.clustered());
  const auto all = triangle_centroids(mesh);
  double lo = 1e300, hi = 0.0;
  FieldReport report;
  for (size_t i = 0; i < all.size(); i += 5) {
    const double b = clustered.radiosity(all[i].first, all[i].second, i, report).x;
    lo = std::min(lo, b);
    hi = std::max(hi, b);
  }
  std::printf("[field] clustered convex room of 600 tiles: points in [%.5f, %.5f] (exact 5), %lld clusters taken, %lld rays\n",
              lo, hi, report.gather_clusters, report.rays_cast);
  EXPECT_EQ(report.rays_cast, 0);
  EXPECT_GT(report.gather_clusters, 0);
  EXPECT_GT(lo, 0.997 * 5.0);
  EXPECT_LT(hi, 1.003 * 5.0);
}

TEST(Field, TheClusteredGatherOfAPointDoesNotDependOnThePointsBeforeIt) {
  // Per-thread scratch must not carry anything from one point to the next:
  // the same points in the opposite order, and with two threads, give the
  // same values to the bit (each point's rays come from its own streams).
  const auto [scene, r] = solved_box_room(4);
  const FieldEvaluator clustered(scene, r.mesh, r.solution.element, SolveOptions{}, GatherSources::clustered);
  ASSERT_TRUE(clustered.clustered());
  const auto points = triangle_centroids(r.mesh);
  const size_t n = points.size();
  std::vector<Rgb> forward(n), backward(n), parallel(n);
  FieldReport report;
  for (size_t i = 0; i < n; ++i) forward[i] = clustered.indirect(points[i].first, points[i].second, i, report);
  for (size_t k = n; k-- > 0;) backward[k] = clustered.indirect(points[k].first, points[k].second, k, report);
  run_in_arena(2, [&] {
    tbb::parallel_for(size_t{0}, n, [&](size_t i) {
      FieldReport own;
      parallel[i] = clustered.indirect(points[i].first, points[i].second, i, own);
    });
  });
  EXPECT_GT(report.gather_clusters, 0);
  for (size_t i = 0; i < n; ++i) {
    ASSERT_EQ(forward[i], backward[i]) << i;
    ASSERT_EQ(forward[i], parallel[i]) << i;
  }
}

TEST(Field, TheCornellBoxAMillionUnitsFromTheOriginShowsTheSameField) {
  // The field sees the scene in units of its size, snapped: moved by 1e6
  // mm, its points on a floor or at a block's foot stay on the same planes,
  // and its zero-area triangles (2e-13 of the box off their long edge by
  // rounding) stay zero-area, so every decision comes out the same. Before,
  // the gather took those triangles for sources and the exact direct light
  // found vertices at the blocks' feet dark: patch means 1.8e-3 apart.
  const Scene at = read_obj_scene(kData + "/cornell_box/cornell_box.obj");
  const Scene moved = test::transformed(at, [](const Vec3& v) { return v + Vec3(1e6, 1e6, 1e6); });
  const Result a = solve(at, HierarchicalOptions{}), b = solve(moved, HierarchicalOptions{});
  ASSERT_EQ(a.field.mode, FieldMode::gather);
  const std::vector<Rgb> ma = a.patch_means(), mb = b.patch_means();
  ASSERT_EQ(ma.size(), mb.size());
  for (size_t p = 0; p < ma.size(); ++p)
    for (int c = 0; c < 3; ++c)
      if (ma[p][c] > 0.0) EXPECT_NEAR(mb[p][c] / ma[p][c], 1.0, 1e-5) << at.patches[p].name;
}

// ---------------------------------------------------------------- the refined display

TEST(DisplayRefinement, ThePlatesMeanMeetsTheClosedFormThatTheSolversMeshMisses) {
  // Howell's C-11: two unit squares 1 apart, F = 0.199825, the receiver's
  // B = rho E F = 0.0999124. The gather field on the solver's mesh
  // integrates the vertex values' linear interpolation, which lies below
  // this concave field (-0.17%); the refined display's means take each
  // triangle's edge midpoints (a rule exact for quadratics).
  const Scene scene = read_obj_scene(kData + "/parallel_plates/parallel_plates.obj");
  SolveOptions so;
  so.field = FieldMode::gather;
  const int receiver = test::patch_named(scene, "receiver");
  const double exact = 0.0999124;
  const MethodResult plain = solve(scene, "matrix", 0.0, DiscontinuityMode::off, so);
  EXPECT_GT(std::abs(patch_mean_radiosity(scene, plain.mesh, plain.solution.nodal)[receiver].x / exact - 1.0), 1e-3);
  so.display_tolerance = 0.005;
  const MethodResult shown = solve(scene, "matrix", 0.0, DiscontinuityMode::off, so);
  EXPECT_NEAR(patch_mean_radiosity(scene, shown.mesh, shown.solution.nodal)[receiver].x / exact, 1.0, 1e-5);
  EXPECT_GT(shown.field.display_splits, 0);
  // The solver's element means are reported as they were.
  EXPECT_EQ(element_patch_means(scene, shown.mesh, shown.solution)[receiver],
            patch_mean_radiosity(scene, plain.mesh, plain.solution.element)[receiver]);
  // The display covers each patch exactly, and its per-triangle fields follow it.
  const auto areas = test::patch_areas(scene, shown.mesh);
  for (size_t p = 0; p < scene.patches.size(); ++p)
    EXPECT_NEAR(areas[p], scene.patch_area(static_cast<int>(p)), 1e-12);
  EXPECT_EQ(shown.solution.element.size(), shown.mesh.triangles.size());
  for (const auto& [name, values] : shown.cell_fields) EXPECT_EQ(values.size(), shown.mesh.triangles.size()) << name;
}

TEST(DisplayRefinement, TheMeansHoldWhereTheRefinementStops) {
  // Where the display stops splitting, at its budget (the parallel plates
  // at T = 1e-4) or at kDisplayLevels (two unit squares at a right angle
  // sharing an edge, whose field bends ever more towards the edge; Howell's
  // C-14, F = 0.2000438), each triangle still takes its mean by its edge
  // midpoints. Those rounds fell back to the vertices' linear interpolation
  // and were further off than a coarser tolerance: -2.6e-4 and +1.7e-4.
  SolveOptions so;
  so.field = FieldMode::gather;
  so.display_tolerance = 1e-4;
  const Scene parallel = read_obj_scene(kData + "/parallel_plates/parallel_plates.obj");
  const MethodResult p = solve(parallel, "matrix", 0.0, DiscontinuityMode::off, so);
  const int receiver = test::patch_named(parallel, "receiver");
  EXPECT_NEAR(patch_mean_radiosity(parallel, p.mesh, p.solution.nodal)[static_cast<size_t>(receiver)].x / 0.0999124, 1.0, 1e-5);
  std::vector<RawFace> faces;
  test::add_face(faces, "emitter", 0, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});
  test::add_face(faces, "receiver", 1, {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}});
  const Scene corner = build_scene(faces, {test::material("lamp", Rgb(0.0), Rgb(1.0)), test::material("grey", Rgb(0.5))},
                                   "corner");
  so.display_tolerance = 0.001;
  const MethodResult c = solve(corner, "hierarchical", 0.0, DiscontinuityMode::off, so);
  EXPECT_EQ(c.field.display_rounds, kDisplayLevels + 1);
  EXPECT_NEAR(patch_mean_radiosity(corner, c.mesh, c.solution.nodal)[1].x / (0.5 * 0.2000438), 1.0, 1e-5);
}

TEST(DisplayRefinement, TheDisplayKeepsToItsBudget) {
  // Past twice the solver's triangles no leaf is split: a round that would
  // pass it splits the largest misses first, up to what is left. Rounds
  // that split all they flagged once took the floating occluder's display
  // to 1.6 times its budget at T = 0.001.
  const Scene scene = read_obj_scene(kData + "/floating_occluder/floating_occluder.obj");
  SolveOptions so;
  so.field = FieldMode::gather;
  const OptionValues coarse = {{"epsilon", "0.01"}};
  auto with_area = [](const Mesh& m) {
    int n = 0;
    for (int t = 0; t < m.triangle_count(); ++t) n += m.zero_area(t) ? 0 : 1;
    return n;
  };
  const Method& method = find_method("hierarchical");
  MeshingOptions mo = method.meshing(scene);
  const Mesh initial = mesh_scene(scene, mo);
  const MethodResult plain = run_method(method, scene, initial, so, coarse);
  const int budget = 2 * std::max(with_area(initial), with_area(plain.mesh));
  so.display_tolerance = 0.0005;
  const MethodResult shown = run_method(method, scene, initial, so, coarse);
  EXPECT_GT(with_area(shown.mesh), budget * 9 / 10);
  EXPECT_LE(with_area(shown.mesh), budget);
}

TEST(DisplayRefinement, AFurnaceIsNotSplitAndAShadowIs) {
  // In the furnace every point is E / (1 - rho): no midpoint misses, no
  // split. Under the floating occluder the field bends at the penumbra:
  // the display splits there, over more than one round.
  SolveOptions so;
  so.field = FieldMode::gather;
  so.display_tolerance = 0.002;
  so.tolerance = 1e-10;
  const Scene furnace = read_obj_scene(kData + "/furnace_cube/furnace_cube.obj");
  const MethodResult f = solve(furnace, "matrix", 0.3, DiscontinuityMode::off, so);
  EXPECT_EQ(f.field.display_splits, 0);
  for (const Rgb& b : f.solution.nodal.radiosity) EXPECT_NEAR(b.x, 2.0, 1e-6);
  const Scene occluded = read_obj_scene(kData + "/floating_occluder/floating_occluder.obj");
  const MethodResult o = solve(occluded, "hierarchical", 0.0, DiscontinuityMode::off, so);
  EXPECT_GT(o.field.display_splits, 0);
  EXPECT_GT(o.field.display_rounds, 1);
  // One and two threads give the same display and values.
  so.threads = 1;
  const MethodResult one = solve(occluded, "hierarchical", 0.0, DiscontinuityMode::off, so);
  so.threads = 2;
  const MethodResult two = solve(occluded, "hierarchical", 0.0, DiscontinuityMode::off, so);
  EXPECT_EQ(one.mesh.triangles, two.mesh.triangles);
  EXPECT_EQ(one.solution.nodal.radiosity, two.solution.nodal.radiosity);
}

TEST(DisplayRefinement, AFieldThatIsNotTheGatherIsNotRefinedAndTheRunSaysSo) {
  const Scene scene = read_obj_scene(kData + "/parallel_plates/parallel_plates.obj");
  SolveOptions so;
  so.field = FieldMode::mean;
  so.display_tolerance = 0.01;
  const MethodResult r = solve(scene, "matrix", 0.0, DiscontinuityMode::off, so);
  EXPECT_EQ(r.field.display_rounds, 0);
  ASSERT_FALSE(r.solution.stats.skips.empty());
  EXPECT_TRUE(test::contains(r.solution.stats.skips.back(), "display refinement")) << r.solution.stats.skips.back();
}
