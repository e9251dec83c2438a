// The exact direct-illumination reference against closed forms and
// hand-computed shadows.

#include "radmesh/obj_reader.h"
#include "radmesh/mesh.h"
#include "radmesh/direct.h"
#include "radmesh/error_metric.h"

#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>

using namespace radmesh;
using radmesh::test::patch_named;

namespace {
using radmesh::test::kData;

// Form factor from a differential area to a parallel a x b rectangle at
// distance c, the area lying under one of its corners (Howell's catalogue B-3).
double corner_rectangle(double a, double b, double c) {
  const double A = a / c, B = b / c;
  const double sa = std::sqrt(1.0 + A * A), sb = std::sqrt(1.0 + B * B);
  return (A / sa * std::atan(B / sa) + B / sb * std::atan(A / sb)) / (2.0 * std::numbers::pi);
}
// A point at (px, 0, 0) under a rectangle x in [x0, x1], |z| <= h at height c:
// sums and differences of corner rectangles.
double strip(double px, double x0, double x1, double h, double c) {
  auto f = [&](double x) {  // signed: rectangle from px to x
    const double a = std::abs(x - px);
    return (x >= px ? 1.0 : -1.0) * 2.0 * corner_rectangle(a, h, c);
  };
  return std::abs(f(x1) - f(x0));
}
}  // namespace

class BoxOnFloor : public ::testing::Test {
protected:
  BoxOnFloor() : s(read_obj_scene(kData + "/box_on_floor/box_on_floor.obj")), direct(s) {
    floor = patch_named(s, "floor");
    light = patch_named(s, "light");
  }
  void SetUp() override {
    ASSERT_GE(floor, 0);  // a misnamed patch would make every light value 0
    ASSERT_GE(light, 0);
  }
  Scene s;
  DirectIllumination direct;
  int floor = -1, light = -1;
  const Vec3 up{0.0, 1.0, 0.0};
};

TEST_F(BoxOnFloor, UnoccludedPointsMatchTheClosedForm) {
  // Light |x|, |z| <= 0.1 at height 3. Beyond x = 0.8 nothing occludes.
  for (double px : {0.85, 1.0, 1.5, 1.99}) {
    const Vec3 x(px, 0.0, 0.0);
    const double expected = strip(px, -0.1, 0.1, 0.1, 3.0);
    EXPECT_NEAR(direct.visible_form_factor(x, up, floor, light), expected, 1e-15) << px;
    EXPECT_NEAR(direct.unoccluded_form_factor(x, up, light), expected, 1e-15) << px;
  }
  // Straight under the light the box hides all of it; unoccluded it is four corners.
  EXPECT_NEAR(direct.unoccluded_form_factor(Vec3(0.0, 0.0, 0.0), up, light), 4.0 * corner_rectangle(0.1, 0.1, 3.0),
              1e-15);
}

TEST_F(BoxOnFloor, UmbraIsExactlyBlack) {
  // Also within a hair of the box's foot (x = 0.5), where the box's side
  // comes within 1e-4 of the light's height of the apex of the pyramid from
  // x: its shadow is clipped in exact arithmetic there, in double elsewhere.
  for (double px : {0.5 + 1e-12, 0.5 + 1e-7, 0.55, 0.6, 0.69})
    EXPECT_EQ(direct.visible_form_factor(Vec3(px, 0.0, 0.0), up, floor, light), 0.0) << px;
  EXPECT_EQ(direct.visible_form_factor(Vec3(0.6, 0.0, 0.3), up, floor, light), 0.0);
}

TEST_F(BoxOnFloor, PenumbraMatchesTheHandComputedVisiblePart) {
  // From (0.75, 0, 0) the box's top edge (x = 0.5, y = 1) projects onto the
  // light's plane at x = 0.75 - 3 * 0.25 = 0: only the strip x in [0, 0.1]
  // of the light is visible (the box spans |z| <= 0.5, wider than the shadow).
  const double f = direct.visible_form_factor(Vec3(0.75, 0.0, 0.0), up, floor, light);
  EXPECT_NEAR(f, strip(0.75, 0.0, 0.1, 0.1, 3.0), 1e-15);
  // General point: from (px, 0, 0) the edge projects to x = px - 3 (px - 0.5).
  for (double px : {0.71, 0.73, 0.78, 0.79}) {
    const double cut = px - 3.0 * (px - 0.5);
    EXPECT_NEAR(direct.visible_form_factor(Vec3(px, 0.0, 0.0), up, floor, light), strip(px, cut, 0.1, 0.1, 3.0), 1e-15)
        << px;
  }
  // Reflected radiosity: rho * E * F.
  const Rgb b = direct.reflected(Vec3(0.75, 0.0, 0.0), floor);
  const Material& white = s.material_of(floor);
  const Material& lamp = s.material_of(light);
  EXPECT_NEAR(b.x, white.reflectance.x * lamp.emission.x * f, 1e-13);
}

TEST_F(BoxOnFloor, LinearInterpolantErrorFallsWithTheMesh) {
  // The meshing error measured against the exact reference: a finer mesh
  // must be closer, and a mesh with the shadow lines closer than one without.
  const auto samples = surface_samples(s, 400);
  std::vector<Rgb> exact;
  for (const SurfaceSample& q : samples) exact.push_back(direct.reflected(q.x, q.patch));
  auto error = [&](double edge, DiscontinuityMode mode) {
    MeshingOptions o;
    o.max_edge = edge;
    o.discontinuity = mode;
    const Mesh m = mesh_scene(s, o);
    return field_error(samples, interpolate_nodal(s, m, direct_field(direct, m), samples), exact).l2;
  };
  const double coarse = error(0.5, DiscontinuityMode::contacts), fine = error(0.25, DiscontinuityMode::contacts);
  const double full = error(0.5, DiscontinuityMode::full);
  EXPECT_LT(fine, coarse);
  EXPECT_LT(full, coarse);
}

TEST_F(BoxOnFloor, AQuadOccluderCastsTheShadowOfItsTwoTriangles) {
  // A convex, exactly planar patch is clipped as one polygon; split into two
  // triangle patches (the box's faces here) it is clipped as two. The union of the two triangles'
  // shadows is the quad's shadow, so every visible form factor agrees to
  // rounding: on a grid over the floor's penumbrae and umbra.
  const test::TempDir dir;
  const std::string split = test::write_edited_obj(kData + "/box_on_floor/box_on_floor", dir.path(),
                                                   [](const std::string& line, int) -> std::string {
                                                     int a, b, c, d;
                                                     if (std::sscanf(line.c_str(), "f %d %d %d %d", &a, &b, &c, &d) != 4 || a < 5 || a > 12)
                                                       return line;
                                                     return "f " + std::to_string(a) + " " + std::to_string(b) + " " +
                                                            std::to_string(c) + "\nf " + std::to_string(a) + " " +
                                                            std::to_string(c) + " " + std::to_string(d);
                                                   });
  const Scene t = read_obj_scene(split);
  ASSERT_EQ(t.patches.size(), s.patches.size() + 5);  // the box's five faces, each two triangles
  const DirectIllumination triangles(t);
  const int t_floor = patch_named(t, "floor"), t_light = patch_named(t, "light");
  ASSERT_GE(t_floor, 0);
  ASSERT_GE(t_light, 0);
  int penumbra = 0;
  for (double px = -1.3; px <= 1.3; px += 0.1)
    for (double pz = -1.25; pz <= 1.3; pz += 0.15) {
      if (std::abs(px) < 0.5 && std::abs(pz) < 0.5) continue;  // under the box
      const Vec3 x(px, 0.0, pz);
      const double f = direct.visible_form_factor(x, up, floor, light);
      const double free = direct.unoccluded_form_factor(x, up, light);
      penumbra += f > 0.0 && f < free;
      EXPECT_NEAR(triangles.visible_form_factor(x, up, t_floor, t_light), f, 1e-16 + 1e-13 * f) << px << " " << pz;
    }
  EXPECT_GT(penumbra, 20);  // the grid crosses the penumbrae
}

namespace {
// An octahedron-like closed solid: a cube's six faces split into triangles,
// about `centre` with half-size h, facing out (or in).
void closed_cube(std::vector<RawFace>& faces, const std::string& name, const Vec3& centre, double h, bool outward) {
  for (RawFace f : test::box_faces(name, 1, centre - Vec3(h), centre + Vec3(h), outward)) {
    // Two triangles per face, sharing the face's diagonal (every edge of
    // the surface then joins exactly two faces, once each way).
    RawFace a = f, b = f;
    a.points = {f.points[0], f.points[1], f.points[2]};
    b.points = {f.points[0], f.points[2], f.points[3]};
    faces.push_back(a);
    faces.push_back(b);
  }
}
// A 6 x 6 floor "floor" (material 0, white 0.5) under `faces` (material 1
// is grey 0.5, material 2 a lamp emitting 1).
Scene on_a_floor(std::vector<RawFace> faces, const std::string& name) {
  RawFace floor;
  floor.name = "floor";
  floor.material = 0;
  floor.points = {{-3, 0, -3}, {-3, 0, 3}, {3, 0, 3}, {3, 0, -3}};
  faces.insert(faces.begin(), floor);
  return build_scene(
      faces, {test::material("white", Rgb(0.5)), test::material("grey", Rgb(0.5)), test::material("lamp", Rgb(0.0), Rgb(1.0))},
      name);
}
}  // namespace

TEST(Direct, FacesOfAClosedSolidTurnedAwayAreLeftOutOfTheClipAndTheLightIsTheSame) {
  // A floor lit by a 1 x 1 lamp 3 m up, with three closed surfaces between:
  // a cube floating (closed, facing out: its faces turned away from a floor
  // point are left out of the clip), a cube standing on the floor (closed,
  // its bottom on the floor: floor points under and beside it lie in its
  // box, where nothing is left out), and a cube whose faces face in (closed
  // but enclosing a negative volume: nothing left out). At points in light,
  // penumbra and umbra of all three, the fast path (reflected) must equal
  // the visible form factor over every occluder to 1e-12.
  std::vector<RawFace> faces;
  RawFace lamp;
  lamp.name = "lamp";
  lamp.material = 2;
  lamp.points = {{-0.5, 3, -0.5}, {0.5, 3, -0.5}, {0.5, 3, 0.5}, {-0.5, 3, 0.5}};
  faces.push_back(lamp);
  closed_cube(faces, "floating", Vec3(-1.0, 1.2, 0.0), 0.3, true);
  closed_cube(faces, "standing", Vec3(1.0, 0.25, 0.0), 0.25, true);
  closed_cube(faces, "inside_out", Vec3(0.0, 1.5, 1.0), 0.3, false);
  // A second lamp shut inside the inside-out cube: none of its light may
  // reach the floor (a face turned away from a floor point is what hides it
  // there: the cube's faces face in).
  RawFace shut;
  shut.name = "shut_lamp";
  shut.material = 2;
  shut.points = {{-0.1, 1.5, 0.9}, {0.1, 1.5, 0.9}, {0.1, 1.5, 1.1}, {-0.1, 1.5, 1.1}};
  faces.push_back(shut);
  const Scene scene = on_a_floor(faces, "closed solids");
  const DirectIllumination direct(scene);
  const int floor_patch = patch_named(scene, "floor"), light = patch_named(scene, "lamp"),
            shut_light = patch_named(scene, "shut_lamp");
  ASSERT_GE(floor_patch, 0);
  ASSERT_GE(light, 0);
  ASSERT_GE(shut_light, 0);
  const Vec3 up(0.0, 1.0, 0.0);
  int shaded = 0, dark = 0;
  for (int i = 0; i <= 60; ++i)
    for (int k = 0; k <= 20; ++k) {
      const Vec3 x(-2.9 + 5.8 * i / 60.0, 0.0, -2.0 + 4.0 * k / 20.0);
      const double brute = direct.visible_form_factor(x, up, floor_patch, light);
      ASSERT_EQ(direct.visible_form_factor(x, up, floor_patch, shut_light), 0.0);
      const double fast = direct.reflected(x, floor_patch).x / 0.5;
      ASSERT_NEAR(fast, brute, 1e-12 * std::max(brute, 1e-3)) << x.x << " " << x.z;
      const double open = direct.unoccluded_form_factor(x, up, light);
      shaded += brute < open - 1e-9 ? 1 : 0;
      dark += brute == 0.0 ? 1 : 0;
    }
  std::printf("[direct] closed solids: %d of 1281 floor points shaded, %d dark\n", shaded, dark);
  EXPECT_GT(shaded, 100);
  EXPECT_GT(dark, 5);
}

TEST(Direct, ARoundLampOverARoundTableIsLitExactlyByTheCheapPath) {
  // A lamp of 48 corners (radius 0.3, 2.9 m up, facing down) over a table
  // top of 200 (radius 0.8, 0.75 m up, facing up). The shaft test over
  // such polygons cost a pass over the base's corners per corner, and one
  // per pair of pyramid and occluder edges: the direct pass took 1.2 s at
  // 64 corners each, 65 s at 256 and over 300 s at 1,024. Past 16 corners
  // the pyramid stands on the lamp's box, and an occluder whose edge pairs
  // would cost too much goes to the exact clip: at floor points in light,
  // penumbra and umbra, and on the table, the cheap path (reflected) must
  // equal the visible form factor over every occluder to 1e-12.
  auto disc = [](const std::string& name, int material, int corners, double r, double y, bool up) {
    RawFace f;
    f.name = name;
    f.material = material;
    for (int k = 0; k < corners; ++k) {
      const double a = 2.0 * std::numbers::pi * (up ? -k : k) / corners;
      f.points.emplace_back(r * std::cos(a), y, r * std::sin(a));
    }
    return f;
  };
  const Scene scene =
      on_a_floor({disc("lamp", 2, 48, 0.3, 2.9, false), disc("table", 1, 200, 0.8, 0.75, true)}, "round table");
  const DirectIllumination direct(scene);
  const int floor_patch = patch_named(scene, "floor"), table = patch_named(scene, "table"),
            light = patch_named(scene, "lamp");
  ASSERT_GE(table, 0);
  const Vec3 up(0.0, 1.0, 0.0);
  int shaded = 0, dark = 0;
  DirectCounts counts;
  for (int i = 0; i <= 40; ++i)
    for (int k = 0; k <= 10; ++k) {
      const Vec3 x(-1.5 + 3.0 * i / 40.0, 0.0, -0.5 + 1.0 * k / 10.0);
      const double brute = direct.visible_form_factor(x, up, floor_patch, light);
      const double fast = direct.reflected(x, floor_patch, &counts).x / 0.5;
      ASSERT_NEAR(fast, brute, 1e-12 * std::max(brute, 1e-3)) << x.x << " " << x.z;
      shaded += brute < direct.unoccluded_form_factor(x, up, light) - 1e-9 ? 1 : 0;
      dark += brute == 0.0 ? 1 : 0;
    }
  for (int i = 0; i <= 10; ++i) {
    const Vec3 x(-0.7 + 1.4 * i / 10.0, 0.75, 0.1);
    EXPECT_NEAR(direct.reflected(x, table).x / 0.5, direct.unoccluded_form_factor(x, up, light), 1e-12);
  }
  std::printf("[direct] round table: %d of 451 floor points shaded, %d dark, %lld clipped exactly\n", shaded, dark,
              static_cast<long long>(counts.clipped));
  EXPECT_GT(shaded, 100);
  EXPECT_GT(dark, 50);
  EXPECT_GT(counts.clipped, 50);
}
