// Scene reading and validation: the bundled scenes and every bad input.

#include "radmesh/obj_reader.h"
#include "radmesh/errors.h"
#include "radmesh/mesh.h"

#include <gtest/gtest.h>

#include "tests/test_util.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <limits>
#include <string>


using namespace radmesh;
namespace fs = std::filesystem;
using radmesh::test::contains;
using radmesh::test::message_of;

namespace {
using radmesh::test::kData;

}  // namespace

TEST(Scene, CornellBoxReadsWithItsPatchesAndOneSplitWall) {
  const Scene s = read_obj_scene(kData + "/cornell_box/cornell_box.obj");
  // floor, back, green, front, light, 4 ceiling pieces, 10 block faces = 19
  // faces planar, plus the red wall split into 2 triangles.
  EXPECT_EQ(s.report.faces_read, 20);
  EXPECT_EQ(s.patches.size(), 21u);
  EXPECT_EQ(s.report.nonplanar_faces_split, 1);
  ASSERT_FALSE(s.report.warnings.empty());
  EXPECT_TRUE(contains(s.report.warnings[0], "left_wall_red")) << s.report.warnings[0];
  EXPECT_TRUE(contains(s.report.warnings[0], "cornell_box.obj:")) << s.report.warnings[0];
  EXPECT_TRUE(s.has_emitter());
  // The ceiling pieces and the light tile the published ceiling exactly.
  double ceiling = 0.0;
  for (size_t p = 0; p < s.patches.size(); ++p)
    if (s.patches[p].name == "ceiling" || s.patches[p].name == "light") ceiling += s.patch_area(static_cast<int>(p));
  EXPECT_NEAR(ceiling, 556.0 * 559.2, 1e-6);
  // Every normal is unit length and the light faces down.
  for (const Patch& p : s.patches) {
    EXPECT_NEAR(glm::length(p.normal), 1.0, 1e-12);
    if (p.name == "light") {
      EXPECT_NEAR(p.normal.y, -1.0, 1e-12);
    }
  }
}

TEST(Scene, RepeatedVerticesAreWelded) {
  const Scene s = read_obj_scene(kData + "/furnace_cube/furnace_cube.obj");
  EXPECT_EQ(s.vertices.size(), 8u);
  EXPECT_EQ(s.patches.size(), 6u);
}

struct BadCase {
  const char* file;
  const char* type;  // the error's class
  const char* where;
  const char* value;
};

class BadInput : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadInput, ErrorNamesFileLineAndValue) {
  const BadCase c = GetParam();
  const test::Thrown t = test::thrown<Error>([&] { read_obj_scene(kData + "/bad/" + c.file); });
  EXPECT_EQ(t.type, c.type) << t.message;
  EXPECT_TRUE(t.says({c.where, c.value}));
}

INSTANTIATE_TEST_SUITE_P(
    AllCases, BadInput,
    ::testing::Values(BadCase{"nan_coordinate.obj", "InputError", "nan_coordinate.obj:6", "nan"},
                      BadCase{"inf_coordinate.obj", "InputError", "inf_coordinate.obj:6", "inf"},
                      BadCase{"reflectance_one.obj", "InputError", "reflectance_one.mtl:3", "1 1 1"},
                      BadCase{"reflectance_negative.obj", "InputError", "reflectance_negative.mtl:3", "-0.25"},
                      BadCase{"negative_emission.obj", "InputError", "negative_emission.mtl:4", "-1"},
                      BadCase{"degenerate_face.obj", "InputError", "degenerate_face.obj:9", "2 distinct"},
                      BadCase{"missing_material.obj", "InputError", "missing_material.obj:9", "no_such_material"},
                      BadCase{"missing_mtl_file.obj", "InputError", "missing_mtl_file.obj:2", "does_not_exist.mtl"},
                      BadCase{"parse_error.obj", "InputError", "parse_error.obj:7", "'x'"},
                      BadCase{"bad_index.obj", "InputError", "bad_index.obj:8", "9"},
                      BadCase{"kd_nan.obj", "InputError", "kd_nan.mtl:3", "'nan'"},
                      BadCase{"ke_inf.obj", "InputError", "ke_inf.mtl:4", "'inf'"},
                      BadCase{"duplicate_material.obj", "InputError", "duplicate_material.mtl:5", "'light'"},
                      BadCase{"vertical_tab.obj", "InputError", "vertical_tab.obj:6", "0x0B"},
                      BadCase{"self_crossing_face.obj", "InputError", "self_crossing_face.obj:8", "not a simple polygon"}),
    [](const auto& info) {
      std::string n = info.param.file;
      return n.substr(0, n.find('.'));
    });

TEST(Scene, OneValueKdIsGreyAndAMissingKdIsSaid) {
  // The MTL format's one-value Kd means the same value in every channel.
  const test::TempDir dir;
  std::ofstream(dir / "s.mtl") << "newmtl lamp\nKd 0.25\nKe 2\nnewmtl dark\nKe 0 0 0\n";
  std::ofstream(dir / "s.obj") << "mtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl lamp\nf 1 2 3\n"
                                  "usemtl dark\nf 2 4 3\n";
  const Scene s = read_obj_scene((dir / "s.obj").string());
  ASSERT_EQ(s.patches.size(), 2u);
  EXPECT_EQ(s.material_of(0).reflectance, Rgb(0.25));
  EXPECT_EQ(s.material_of(0).emission, Rgb(2.0));
  EXPECT_EQ(s.material_of(1).reflectance, Rgb(0.0));
  int said = 0;
  for (const std::string& w : s.report.warnings)
    if (contains(w, "s.mtl:4") && contains(w, "'dark' has no Kd")) ++said;
  EXPECT_EQ(said, 1);
}

TEST(Scene, UnreadableFileIsAnIoError) {
  const std::string msg = message_of<IoError>([&] { read_obj_scene(kData + "/no/such/file.obj"); });
  EXPECT_TRUE(contains(msg, "file.obj")) << msg;
}

TEST(Scene, NoEmitterWarns) {
  const Scene s = read_obj_scene(kData + "/bad/no_emitter.obj");
  EXPECT_FALSE(s.has_emitter());
  bool warned = false;
  for (const auto& w : s.report.warnings) warned = warned || contains(w, "emit");
  EXPECT_TRUE(warned);
}

TEST(Scene, ZeroAreaFaceIsDroppedAndCounted) {
  const Scene s = read_obj_scene(kData + "/bad/zero_area.obj");
  EXPECT_EQ(s.report.zero_area_faces_dropped, 1);
  EXPECT_EQ(s.patches.size(), 1u);
  ASSERT_FALSE(s.report.warnings.empty());
  EXPECT_TRUE(contains(s.report.warnings[0], "zero_area.obj:9")) << s.report.warnings[0];
}

TEST(Scene, FacesThinnerThanTheWeldToleranceAreDroppedAsZeroArea) {
  // A 2 x 2 floor (scene size 2 x sqrt(2), weld tolerance 2.8e-9) with two
  // slivers on it: a triangle 1e-10 high over a base of 1, whose vertices
  // stay distinct (meshing it found no triangle and stopped the run), and
  // a quad 1e-9 wide whose vertices weld into 2 (refused as a face of 2
  // distinct vertices). Both have no inside at the scene's resolution and
  // are dropped with a warning, as faces of zero area are; a triangle 1e-8
  // high is kept.
  const test::TempDir dir;
  std::ofstream(dir / "s.mtl") << "newmtl lamp\nKd 0 0 0\nKe 1 1 1\n";
  std::ofstream(dir / "s.obj") << "mtllib s.mtl\nusemtl lamp\nv 0 0 0\nv 2 0 0\nv 2 2 0\nv 0 2 0\n"
                                  "v 0.5 0.5 0\nv 1.5 0.5 0\nv 1 0.5000000001 0\nv 1.5 0.500000001 0\n"
                                  "v 0.5 0.500000001 0\nv 1 0.50000001 0\n"
                                  "o floor\nf 1 2 3 4\no tri\nf 5 6 7\no quad\nf 5 6 8 9\no kept\nf 5 6 10\n";
  const Scene s = read_obj_scene((dir / "s.obj").string());
  EXPECT_EQ(s.report.zero_area_faces_dropped, 2);
  ASSERT_EQ(s.patches.size(), 2u);
  EXPECT_EQ(s.patches[1].name, "kept");
  ASSERT_EQ(s.report.warnings.size(), 3u);  // the third: 'kept' is cut out of the floor
  EXPECT_TRUE(test::mentions(s.report.warnings[0], {"s.obj:16: face 'tri'", "1.00000008e-10 wide", "weld tolerance"}));
  EXPECT_TRUE(test::mentions(s.report.warnings[1], {"s.obj:18: face 'quad'", "welded into 2"}));
  // What is left meshes: the floor around its thin hole and the kept
  // triangle in it cover the floor's area.
  const Mesh m = mesh_scene(s, {});
  const std::vector<double> area = test::patch_areas(s, m);
  EXPECT_NEAR(area[0] + area[1], 4.0, 1e-12);
  EXPECT_NEAR(area[1], 5e-9, 5e-11);
}

TEST(Scene, AFaceWhoseVerticesDoubleCannotTellApartSaysItIsTooFarFromTheOrigin) {
  // A 4 x 4 square moved 1e49 along x (a JSON transform can do it): in
  // double 1e49 + 4 is 1e49, and its 4 vertices are 2. The error says why;
  // a face naming one point twice near the origin gets no such hint.
  RawFace far;
  far.name = "far";
  far.material = 0;
  far.points = {{1e49, 0, 0}, {1e49, 0, 4}, {1e49 + 4.0, 0, 4}, {1e49 + 4.0, 0, 0}};
  const test::Thrown t = test::thrown<InputError>([&] { build_scene({far}, {test::material("grey", Rgb(0.5))}, "far"); });
  EXPECT_TRUE(t.says({"face 'far'", "2 distinct vertices", "1e+49", "origin", "double precision"}));
  RawFace twice;
  twice.name = "twice";
  twice.material = 0;
  twice.points = {{0, 0, 0}, {1, 0, 0}, {0, 0, 0}};
  const test::Thrown near =
      test::thrown<InputError>([&] { build_scene({twice}, {test::material("grey", Rgb(0.5))}, "twice"); });
  EXPECT_TRUE(near.says({"face 'twice'", "2 distinct vertices"}));
  EXPECT_FALSE(contains(near.message, "origin")) << near.message;
}

TEST(Scene, ASubnormalEmissionIsRefusedNamingTheMaterialAndTheLimit) {
  // 5e-324 keeps one significant bit: the light it gave was dark, with
  // 99.5% of the power unaccounted for. 0 and the smallest normal number
  // are accepted.
  std::vector<RawFace> faces = test::box_faces("room", 0, Vec3(0.0), Vec3(1.0), false);
  for (const double e : {5e-324, 1e-310}) {
    const test::Thrown t = test::thrown<InputError>(
        [&] { build_scene(faces, {test::material("lamp", Rgb(0.5), Rgb(e))}, "room"); });
    EXPECT_TRUE(t.says({"material 'lamp'", "emission", "2.22507386e-308"}));
  }
  EXPECT_NO_THROW(build_scene(faces, {test::material("lamp", Rgb(0.5), Rgb(0.0))}, "room"));
  EXPECT_NO_THROW(
      build_scene(faces, {test::material("lamp", Rgb(0.5), Rgb(std::numeric_limits<double>::min()))}, "room"));
}

TEST(Scene, AnObjectTheWeldLeavesNothingOfIsNamedWithItsExtent) {
  // A room 4 across and a box 1e6 across moved 1e20 away: the scene spans
  // 1e20, points within 1e-9 of that weld, and the whole room vanished
  // ("the scene has no faces with area", naming nothing).
  std::vector<RawFace> faces = test::box_faces("room", 0, Vec3(0.0), Vec3(4.0), false);
  const std::vector<RawFace> far = test::box_faces("far", 0, Vec3(1e20, 0, 0), Vec3(1e20 + 1e6, 1e6, 1e6));
  faces.insert(faces.end(), far.begin(), far.end());
  const test::Thrown t =
      test::thrown<InputError>([&] { build_scene(faces, {test::material("grey", Rgb(0.5), Rgb(1.0))}, "far"); });
  EXPECT_TRUE(t.says({"object 'room'", "6 faces", "1e+11", "1e+20"}));
}

TEST(Scene, FacesWithoutAnObjectNameAreNamedAfterTheFile) {
  // No o or g line: the patch takes the file's stem (it was named '').
  const test::TempDir dir;
  std::ofstream(dir / "plain.mtl") << "newmtl m\nKd 0.5 0.5 0.5\nKe 1 1 1\n";
  std::ofstream(dir / "plain.obj") << "mtllib plain.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  const Scene s = read_obj_scene((dir / "plain.obj").string());
  ASSERT_EQ(s.patches.size(), 1u);
  EXPECT_EQ(s.patches[0].name, "plain");
}

TEST(Scene, AMaterialLibraryAtAnAbsolutePathIsReadFromAnyDirectory) {
  // The OBJ names its library by an absolute path and is read by a path
  // with a directory part: its materials were lost ("face has no material")
  // when the OBJ's directory was put before the absolute path.
  const test::TempDir dir;
  fs::create_directories(dir / "lib");
  const fs::path library = fs::absolute(dir / "lib" / "m.mtl");
  std::ofstream(library) << "newmtl m\nKd 0.25 0.5 0.75\nKe 1 1 1\n";
  std::ofstream(dir / "s.obj") << "mtllib " << library.string() << "\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  const Scene s = read_obj_scene((dir / "s.obj").string());
  ASSERT_EQ(s.patches.size(), 1u);
  const Material& m = s.material_of(s.patches[0]);
  EXPECT_EQ(m.name, "m");
  EXPECT_EQ(m.reflectance, Rgb(0.25, 0.5, 0.75));
  EXPECT_EQ(m.emission, Rgb(1.0));
}

TEST(Scene, HolesAreOrientedAgainstTheOuterLoop) {
  RawFace f;
  f.name = "plate";
  f.material = 0;
  f.points = {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}};
  f.holes = {{{1, 1, 0}, {3, 1, 0}, {3, 3, 0}, {1, 3, 0}}};  // same orientation as outer: gets reversed
  Material m;
  m.name = "m";
  m.reflectance = Rgb(0.5);
  const Scene s = build_scene({f}, {m}, "test");
  ASSERT_EQ(s.patches.size(), 1u);
  EXPECT_DOUBLE_EQ(s.patch_area(0), 12.0);
  EXPECT_LT(glm::dot(newell_normal(s.loop_points(s.patches[0].holes[0])), s.patches[0].normal), 0.0);
}

// Guards the mesher's endless refinement on a duplicated `v` line in the
// Cornell box (issue 10): the shifted indices made planar ceiling quads whose
// edges crossed, and CGAL refined towards the crossing it had to invent.
TEST(Scene, FacesWhoseEdgesCrossAreRefusedAndSimpleOnesAreNot) {
  Material m;
  m.name = "m";
  m.reflectance = Rgb(0.5);
  m.emission = Rgb(1.0);
  auto face = [](std::vector<Vec3> points, std::vector<std::vector<Vec3>> holes = {}) {
    RawFace f;
    f.name = "plate";
    f.material = 0;
    f.points = std::move(points);
    f.holes = std::move(holes);
    return f;
  };
  auto error = [&](const RawFace& f) { return message_of<InputError>([&] { build_scene({f}, {m}, "test"); }); };
  // A bow tie (lopsided, so that its signed area is not zero): the edges
  // (2 0 0)->(0 1 0) and (1 1.5 0)->(0 0 0) cross at (0.5 0.75 0).
  const std::string bow = error(face({{0, 0, 0}, {2, 0, 0}, {0, 1, 0}, {1, 1.5, 0}}));
  EXPECT_TRUE(contains(bow, "not a simple polygon")) << bow;
  EXPECT_TRUE(contains(bow, "2 0 0 -> 0 1 0")) << bow;
  // A symmetric bow tie: its two lobes cancel, so its signed area is zero,
  // but it is not a zero-area face (its vertices are not on one line).
  const std::string even = error(face({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}}));
  EXPECT_TRUE(contains(even, "not a simple polygon")) << even;
  // A hole over the outline.
  const std::string hole = error(face({{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}},
                                      {{{3, 1, 0}, {5, 1, 0}, {5, 3, 0}, {3, 3, 0}}}));
  EXPECT_TRUE(contains(hole, "hole 1 edge")) << hole;
  // An outline doubling back over itself along a line (collinear overlap).
  const std::string back = error(face({{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0}, {1, 0, 0}, {3, 0, 0},
                                       {3, 2, 0}, {0, 2, 0}}));
  EXPECT_TRUE(contains(back, "not a simple polygon")) << back;
  // Concave outlines, and a hole touching the outline at a vertex, are simple.
  EXPECT_EQ(build_scene({face({{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0}, {1, 2, 0}, {0, 2, 0}})}, {m}, "test")
                .patches.size(),
            1u);
  EXPECT_NEAR(build_scene({face({{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}}, {{{0, 0, 0}, {2, 1, 0}, {1, 2, 0}}})},
                          {m}, "test")
                  .patch_area(0),
              16.0 - 1.5, 1e-12);
}

// Found by fuzz_assimp_reader: a glTF translation of 2e307 overflowed the
// welder's cell index (undefined behaviour); and fuzz_obj_reader: an mtllib
// name longer than the system allows threw std::filesystem_error, an
// internal error. Both are now InputErrors that say what is wrong.
TEST(Scene, HugeCoordinatesAndEmissionAndOverlongLibraryNamesAreInputErrors) {
  RawFace f;
  f.name = "far";
  f.material = 0;
  f.points = {{0, 0, 0}, {1, 0, 0}, {2e307, 1, 0}};
  Material m;
  m.name = "m";
  m.reflectance = Rgb(0.5);
  m.emission = Rgb(1.0);
  const std::string far = message_of<InputError>([&] { build_scene({f}, {m}, "test"); });
  EXPECT_TRUE(contains(far, "is beyond +-1e+50")) << far;
  // An emission whose radiosity and power would overflow: Ke 1e308 gave
  // null energies and a radiosity of 1e308 where 2e308 was due.
  f.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.emission = Rgb(1.0, 1e308, 1.0);
  const test::Thrown bright = test::thrown<InputError>([&] { build_scene({f}, {m}, "test"); });
  EXPECT_TRUE(bright.says({"emission (Ke)", "1 1e+308 1", "1e+50"}));
  m.emission = Rgb(1e50);
  EXPECT_NO_THROW(build_scene({f}, {m}, "test"));

  const test::TempDir dir;
  const std::string name(300, 'a');
  std::ofstream(dir / "scene.obj") << "mtllib " << name << ".mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  const std::string lib = message_of<InputError>([&] { read_obj_scene((dir / "scene.obj").string()); });
  EXPECT_TRUE(contains(lib, "scene.obj:1")) << lib;
  EXPECT_TRUE(contains(lib, "not found")) << lib;
}

TEST(Scene, DevicesAndDirectoriesAreRefusedNotReadForever) {
  // /dev/zero as a material library would be read forever: only regular
  // files are read, and the message names the library's line.
  const test::TempDir dir;
  std::ofstream(dir / "s.obj") << "mtllib /dev/zero\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  std::string msg = message_of<Error>([&] { read_obj_scene((dir / "s.obj").string()); });
  EXPECT_TRUE(contains(msg, "s.obj:1")) << msg;
  EXPECT_TRUE(contains(msg, "not a regular file")) << msg;
  msg = message_of<IoError>([&] { read_obj_scene("/dev/zero"); });
  EXPECT_TRUE(test::mentions(msg, {"/dev/zero: ", "regular file"}));
  msg = message_of<IoError>([&] { read_obj_scene(dir.string()); });
  EXPECT_TRUE(contains(msg, "is a directory")) << msg;
}

TEST(Scene, AFaceWrittenTwiceIsAnErrorButTheTwoSidesOfAPanelAreNot) {
  // A duplicated face line made two coincident patches; the mesher then
  // crashed in run (issue 10's "two vertex lines swapped and one face line
  // duplicated"). The same vertices in reverse order are a panel's back.
  const test::TempDir dir;
  std::ofstream(dir / "s.mtl") << "newmtl lamp\nKd 0.5 0.5 0.5\nKe 1 1 1\n";
  const std::string head = "mtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl lamp\n";
  std::ofstream(dir / "twice.obj") << head << "f 1 2 3 4\nf 2 3 4 1\n";
  std::ofstream(dir / "panel.obj") << head << "f 1 2 3 4\nf 4 3 2 1\n";
  const std::string msg = message_of<InputError>([&] { read_obj_scene((dir / "twice.obj").string()); });
  EXPECT_TRUE(contains(msg, "twice.obj:8")) << msg;
  EXPECT_TRUE(contains(msg, "twice.obj:7")) << msg;
  const Scene panel = read_obj_scene((dir / "panel.obj").string());
  ASSERT_EQ(panel.patches.size(), 2u);
  EXPECT_EQ(glm::dot(panel.patches[0].normal, panel.patches[1].normal), -1.0);
}

TEST(Scene, FacesFacingEachOtherAcrossAWeldedGapAreRefused) {
  // Two unit squares 1e-9 apart, front to front: welding (1e-9 of the scene
  // size) made them one surface seen from both sides, and the lower one got
  // no light at all while the summary said the light escaped.
  const test::TempDir dir;
  std::ofstream(dir / "s.mtl") << "newmtl lamp\nKd 0 0 0\nKe 1 1 1\nnewmtl grey\nKd 0.5 0.5 0.5\n";
  std::ofstream(dir / "s.obj") << "mtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                  "v 0 0 1e-9\nv 1 0 1e-9\nv 1 1 1e-9\nv 0 1 1e-9\n"
                                  "o lower\nusemtl grey\nf 1 2 3 4\no upper\nusemtl lamp\nf 5 8 7 6\n";
  const std::string msg = message_of<InputError>([&] { read_obj_scene((dir / "s.obj").string()); });
  EXPECT_TRUE(contains(msg, "s.obj:15")) << msg;
  EXPECT_TRUE(contains(msg, "s.obj:12")) << msg;
  EXPECT_TRUE(contains(msg, "gap of 1e-09")) << msg;
}

namespace {
// A rectangle [x0, x1] x [z0, z1] in the plane y, facing up (+y) or down.
RawFace rect(const std::string& name, int material, double x0, double z0, double x1, double z1, double y, bool up) {
  RawFace f;
  f.name = name;
  f.material = material;
  f.points = {{x0, y, z0}, {x0, y, z1}, {x1, y, z1}, {x1, y, z0}};
  if (!up) std::reverse(f.points.begin(), f.points.end());
  return f;
}
}  // namespace

TEST(Scene, AFaceLyingInAnotherOfItsPlaneIsCutOutOfIt) {
  // A lamp lying in an uncut ceiling, a rug on the floor, and a tile on a
  // mat on the floor: each is cut out of the smallest face it lies in (the
  // tile out of the mat, not the floor), since what a face covers is
  // hidden; the cuts are counted and said.
  const std::vector<RawFace> faces = {rect("floor", 0, 0, 0, 4, 4, 0, true),
                                      rect("rug", 0, 1, 1, 2, 2, 0, true),
                                      rect("tile", 0, 2.8, 2.8, 3.2, 3.2, 0, true),
                                      rect("mat", 0, 2.5, 2.5, 3.5, 3.5, 0, true),
                                      rect("ceiling", 0, 0, 0, 4, 4, 3, false),
                                      rect("lamp", 1, 1.5, 1.5, 2.5, 2.5, 3, false)};
  const Scene s = build_scene(
      faces, {test::material("white", Rgb(0.5)), test::material("lamp", Rgb(0.0), Rgb(10.0))}, "cuts");
  EXPECT_EQ(s.report.faces_cut_out, 4);
  const int floor = test::patch_named(s, "floor"), mat = test::patch_named(s, "mat");
  const int ceiling = test::patch_named(s, "ceiling");
  EXPECT_EQ(s.patches[static_cast<size_t>(floor)].holes.size(), 2u);
  EXPECT_EQ(s.patches[static_cast<size_t>(mat)].holes.size(), 1u);
  EXPECT_NEAR(s.patch_area(floor), 16.0 - 1.0 - 1.0, 1e-12);
  EXPECT_NEAR(s.patch_area(mat), 1.0 - 0.16, 1e-12);
  EXPECT_NEAR(s.patch_area(ceiling), 15.0, 1e-12);
  bool said = false;
  for (const std::string& w : s.report.warnings)
    said = said || (contains(w, "face 'lamp'") && contains(w, "lies in") && contains(w, "face 'ceiling'"));
  EXPECT_TRUE(said);
  // The mesh covers each patch once, and nothing is left overlapping.
  const Mesh m = mesh_scene(s, {});
  const std::vector<double> area = test::patch_areas(s, m);
  for (size_t p = 0; p < s.patches.size(); ++p) EXPECT_NEAR(area[p], s.patch_area(static_cast<int>(p)), 1e-9);
}

TEST(Scene, FacesJoinedAlongEdgesInAnotherOfTheirPlaneAreCutOutAsOneHole) {
  // A rug of 2 x 2 tiles on the floor and a row of three lamp panels in an
  // uncut ceiling: each group is cut out of the face it lies in as one
  // hole, its joined outline (the tiles' shared edges are inside it).
  std::vector<RawFace> faces = {rect("floor", 0, 0, 0, 4, 4, 0, true), rect("ceiling", 0, 0, 0, 4, 4, 3, false)};
  for (int i = 0; i < 2; ++i)
    for (int k = 0; k < 2; ++k) faces.push_back(rect("rug", 0, 1 + i, 1 + k, 2 + i, 2 + k, 0, true));
  for (int i = 0; i < 3; ++i) faces.push_back(rect("lamp", 1, 0.5 + i, 1.5, 1.5 + i, 2.5, 3, false));
  const Scene s = build_scene(
      faces, {test::material("white", Rgb(0.5)), test::material("lamp", Rgb(0.0), Rgb(10.0))}, "tiles");
  EXPECT_EQ(s.report.faces_cut_out, 7);
  const int floor = test::patch_named(s, "floor"), ceiling = test::patch_named(s, "ceiling");
  ASSERT_EQ(s.patches[static_cast<size_t>(floor)].holes.size(), 1u);
  EXPECT_EQ(s.patches[static_cast<size_t>(floor)].holes[0].size(), 8u);  // the 2 x 2 rug's outline
  ASSERT_EQ(s.patches[static_cast<size_t>(ceiling)].holes.size(), 1u);
  EXPECT_EQ(s.patches[static_cast<size_t>(ceiling)].holes[0].size(), 8u);  // the row of three's
  EXPECT_NEAR(s.patch_area(floor), 16.0 - 4.0, 1e-12);
  EXPECT_NEAR(s.patch_area(ceiling), 16.0 - 3.0, 1e-12);
  const Mesh m = mesh_scene(s, {});
  const std::vector<double> area = test::patch_areas(s, m);
  for (size_t p = 0; p < s.patches.size(); ++p) EXPECT_NEAR(area[p], s.patch_area(static_cast<int>(p)), 1e-9);
}

TEST(Scene, ItsSizeIsTheSmallestEnclosingSphereWhicheverWayItIsTurned) {
  // Scene::diagonal sets the defaults that scale with the scene (mesh
  // sizes, the hierarchical method's minimum area, texel sizes). It was the
  // bounding box's diagonal, which grows when a scene is turned: this room
  // turned 37 degrees about (1, 2, 3) got a 1.51x larger one, so 2.3x the
  // minimum area (a turned Cornell box: 35% fewer leaves).
  const double diagonal = std::sqrt(48.0);  // the room [-2, 2] x [0, 4] x [-2, 2]
  const Scene room = test::room_with({});
  EXPECT_NEAR(room.diagonal(), diagonal, 1e-12 * diagonal);
  const Vec3 axis = glm::normalize(Vec3(1.0, 2.0, 3.0));
  const double angle = 37.0 * std::numbers::pi / 180.0;
  const Scene turned = test::transformed(room, [&](const Vec3& v) {
    const Vec3 r = v * std::cos(angle) + glm::cross(axis, v) * std::sin(angle) +
                   axis * glm::dot(axis, v) * (1.0 - std::cos(angle));
    return r + Vec3(1000.0, -2000.0, 500.0);
  });
  EXPECT_NEAR(turned.diagonal(), diagonal, 1e-12 * diagonal);
  Vec3 lo, hi;
  turned.bounds(lo, hi);
  EXPECT_GT(glm::length(hi - lo), 1.5 * diagonal);  // what the bounding box would have said
  // One triangle: an acute one's circumcircle, an obtuse one's longest edge.
  auto triangle = [](std::vector<Vec3> points) {
    RawFace f;
    f.name = "t";
    f.material = 0;
    f.points = std::move(points);
    return build_scene({f}, {test::material("lamp", Rgb(0.5), Rgb(1.0))}, "triangle");
  };
  const double h = std::sqrt(3.0);
  EXPECT_NEAR(triangle({{0, 0, 0}, {2, 0, 0}, {1, h, 0}}).diagonal(), 4.0 / h, 1e-12);
  EXPECT_NEAR(triangle({{0, 0, 0}, {10, 0, 0}, {5, 1, 0}}).diagonal(), 10.0, 1e-12);
}
