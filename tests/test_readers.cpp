// Scene readers: every mesh format gives the same scene, the JSON scene's
// transforms, paths and materials, every error's message, the bundled bunny,
// and loading a million triangles.

#include "io/readers/json_parse.h"
#include "radmesh/probe_file.h"
#include "radmesh/scene_reader.h"
#include "radmesh/errors.h"
#include "bench/mesh_writers.h"

#include <gtest/gtest.h>

#include "tests/test_util.h"

#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

using namespace radmesh;
using radmesh::test::GltfMaterial;
using radmesh::test::PolyMesh;
namespace fs = std::filesystem;
using radmesh::test::contains;
using radmesh::test::message_of;

namespace {
using radmesh::test::kData;

void write_text(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

// A JSON scene giving one mesh file the material "grey" (emitting, so that the
// scene is complete).
std::string grey_scene(const std::string& file) {
  return "{\"materials\": {\"grey\": {\"reflectance\": [0.5, 0.5, 0.5], \"emission\": [1, 1, 1]}},\n"
         " \"objects\": [{\"file\": \"" + file + "\", \"material\": \"grey\"}]}\n";
}

// An octahedron (8 triangles, outward), coordinates exact in float and in decimal.
PolyMesh octahedron() {
  PolyMesh m;
  m.positions = {{1.75f, 0.25f, 0.5f}, {-1.25f, 0.25f, 0.5f}, {0.25f, 2.25f, 0.5f},
                 {0.25f, -1.75f, 0.5f}, {0.25f, 0.25f, 1.25f}, {0.25f, 0.25f, -0.25f}};
  // +x 0, -x 1, +y 2, -y 3, +z 4, -z 5; counter-clockwise seen from outside.
  m.faces = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return m;
}

// The unit cube scaled by 2, 6 quads facing outward.
PolyMesh cube_quads() {
  PolyMesh m;
  for (int i = 0; i < 8; ++i)
    m.positions.push_back({static_cast<float>(2 * (i & 1)), static_cast<float>(2 * ((i >> 1) & 1)),
                           static_cast<float>(2 * ((i >> 2) & 1))});
  m.faces = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  return m;
}

// Same patches (count, loops, points to `rel` of the diagonal, materials' values) and vertices.
void expect_same_scene(const Scene& a, const Scene& b, double rel, const std::string& what) {
  SCOPED_TRACE(what);
  ASSERT_EQ(a.patches.size(), b.patches.size());
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  const double tol = rel * a.diagonal();
  for (size_t p = 0; p < a.patches.size(); ++p) {
    const Patch& pa = a.patches[p];
    const Patch& pb = b.patches[p];
    ASSERT_EQ(pa.outer.size(), pb.outer.size()) << "patch " << p;
    EXPECT_EQ(pa.outer, pb.outer) << "patch " << p;
    for (size_t k = 0; k < pa.outer.size(); ++k) {
      const Vec3 d = a.vertices[static_cast<size_t>(pa.outer[k])] - b.vertices[static_cast<size_t>(pb.outer[k])];
      EXPECT_LE(glm::length(d), tol) << "patch " << p << " point " << k;
    }
    EXPECT_LE(glm::length(pa.normal - pb.normal), 1e-12) << "patch " << p;
    const Material& ma = a.materials[static_cast<size_t>(pa.material)];
    const Material& mb = b.materials[static_cast<size_t>(pb.material)];
    EXPECT_EQ(ma.reflectance, mb.reflectance) << "patch " << p;
    EXPECT_EQ(ma.emission, mb.emission) << "patch " << p;
  }
}

// Bitwise the same vertices, loops and materials.
void expect_identical_scene(const Scene& a, const Scene& b, const std::string& what) {
  SCOPED_TRACE(what);
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  ASSERT_EQ(a.patches.size(), b.patches.size());
  size_t vertex_diffs = 0, patch_diffs = 0;
  for (size_t v = 0; v < a.vertices.size(); ++v) vertex_diffs += a.vertices[v] != b.vertices[v];
  for (size_t p = 0; p < a.patches.size(); ++p)
    patch_diffs += a.patches[p].outer != b.patches[p].outer || a.patches[p].normal != b.patches[p].normal ||
                   a.materials[static_cast<size_t>(a.patches[p].material)].name !=
                       b.materials[static_cast<size_t>(b.patches[p].material)].name;
  EXPECT_EQ(vertex_diffs, 0u);
  EXPECT_EQ(patch_diffs, 0u);
}

Vec3 point(const Scene& s, size_t patch, size_t k) {
  return s.vertices[static_cast<size_t>(s.patches[patch].outer[k])];
}

void expect_point(const Vec3& got, const Vec3& want, double tol) {
  EXPECT_NEAR(got.x, want.x, tol);
  EXPECT_NEAR(got.y, want.y, tol);
  EXPECT_NEAR(got.z, want.z, tol);
}

// Face 0 of octahedron() mirrored in x: its points' x negated and its last
// two swapped, so that it still faces out of the (mirrored) octahedron.
void expect_octahedron_face0_mirrored_in_x(const Scene& s) {
  expect_point(point(s, 0, 0), {-1.75, 0.25, 0.5}, 0.0);
  expect_point(point(s, 0, 1), {-0.25, 0.25, 1.25}, 0.0);
  expect_point(point(s, 0, 2), {-0.25, 2.25, 0.5}, 0.0);
  expect_point(s.patches[0].normal, glm::normalize(Vec3(-1 / 1.5, 1 / 2.0, 1 / 0.75)), 1e-15);
}

}  // namespace

// ---------------------------------------------------------------- formats

TEST(Readers, AGlbHeaderCannotAskForMoreThanTheFileHolds) {
  // The JSON chunk's length is a 4-byte field: 0xFFFFFFF0 must not allocate 4 GiB.
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  const uint32_t words[5] = {0x46546C67u, 2u, 40u, 0xFFFFFFF0u, 0x4E4F534Au};
  std::ofstream(dir / "big.glb", std::ios::binary).write(reinterpret_cast<const char*>(words), sizeof words);
  const test::Thrown t = test::thrown<InputError>([&] { read_scene((dir / "big.glb").string()); });
  EXPECT_TRUE(t.says({(dir / "big.glb").string(), "4294967280 bytes"}));
}

TEST(Readers, EveryFormatGivesTheSameSceneOfTriangles) {
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  const PolyMesh m = octahedron();
  const auto files = test::write_every_format(dir, m, "octa");
  std::vector<Scene> scenes;
  for (const std::string& f : files) {
    write_text(dir / (f + ".json"), grey_scene(f));
    scenes.push_back(read_scene((dir / (f + ".json")).string()));
  }
  // The binary PLY is the reference: its floats are the numbers exactly (the
  // OBJ reader's parser, tinyobjloader's, can be 1 ulp off: 1.75 reads as
  // 1.7500000000000002).
  const Scene& ref = scenes[2];
  ASSERT_EQ(ref.patches.size(), 8u);
  ASSERT_EQ(ref.vertices.size(), 6u);
  // Face 0 is (+x, +y, +z) in file order, facing out of the octahedron: with
  // half-axes 1.5, 2 and 0.75 its normal is along (1/1.5, 1/2, 1/0.75).
  expect_point(point(ref, 0, 0), {1.75, 0.25, 0.5}, 0.0);
  expect_point(point(ref, 0, 1), {0.25, 2.25, 0.5}, 0.0);
  expect_point(point(ref, 0, 2), {0.25, 0.25, 1.25}, 0.0);
  const Vec3 n0 = glm::normalize(Vec3(1 / 1.5, 1 / 2.0, 1 / 0.75));
  expect_point(ref.patches[0].normal, n0, 1e-15);
  for (size_t i = 0; i < files.size(); ++i) expect_same_scene(ref, scenes[i], 1e-12, files[i]);
}

TEST(Readers, PolygonsStayPolygonsInPlyOffAndObj) {
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  const PolyMesh m = cube_quads();
  test::write_obj(dir / "cube.obj", m, "cube");
  test::write_ply(dir / "cube.ply", m, false);
  test::write_ply(dir / "cube_bin.ply", m, true);
  test::write_off(dir / "cube.off", m);
  std::vector<Scene> scenes;
  for (const char* f : {"cube.obj", "cube.ply", "cube_bin.ply", "cube.off"}) {
    write_text(dir / (std::string(f) + ".json"), grey_scene(f));
    scenes.push_back(read_scene((dir / (std::string(f) + ".json")).string()));
  }
  ASSERT_EQ(scenes[0].patches.size(), 6u);
  ASSERT_EQ(scenes[0].vertices.size(), 8u);
  for (const Patch& p : scenes[0].patches) EXPECT_EQ(p.outer.size(), 4u);
  // Face 0 is x = 0, facing -x (outward).
  expect_point(scenes[0].patches[0].normal, {-1, 0, 0}, 0.0);
  for (size_t i = 1; i < scenes.size(); ++i)
    expect_same_scene(scenes[0], scenes[i], 0.0, "format " + std::to_string(i));
}

TEST(Readers, ObjWithMtlAndGltfCarryTheSameMaterials) {
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  const PolyMesh m = octahedron();
  test::write_obj(dir / "octa.obj", m, "octa", "octa.mtl", "lamp");
  write_text(dir / "octa.mtl", "newmtl lamp\nKd 0.5 0.25 0.125\nKe 8 4 2\n");
  // KHR_materials_emissive_strength 8: emission = 8 * emissiveFactor.
  const GltfMaterial lamp{
      .name = "lamp", .base = {0.5, 0.25, 0.125, 1.0}, .emissive = {1.0, 0.5, 0.25}, .strength = 8.0};
  test::write_gltf(dir / "octa.gltf", m, "octa", false, &lamp);
  test::write_gltf(dir / "octa.glb", m, "octa", true, &lamp);
  const Scene obj = read_scene((dir / "octa.obj").string());
  for (const char* f : {"octa.gltf", "octa.glb"}) {
    const Scene g = read_scene((dir / f).string());
    ASSERT_EQ(g.materials.size(), 1u);
    EXPECT_EQ(g.materials[0].name, "lamp");
    EXPECT_EQ(g.materials[0].reflectance, Rgb(0.5, 0.25, 0.125));
    EXPECT_EQ(g.materials[0].emission, Rgb(8, 4, 2));
    EXPECT_EQ(g.patches[0].name, "octa");
    expect_same_scene(obj, g, 1e-12, f);
  }
}

TEST(Readers, GltfNodeTransformIsAppliedAndAMirrorKeepsFacesFacingOut) {
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  const PolyMesh m = octahedron();
  const GltfMaterial grey{.name = "grey", .emissive = {1, 1, 1}};
  test::write_gltf(dir / "moved.gltf", m, "moved", false, &grey, "\"translation\": [10, 0, 0]");
  test::write_gltf(dir / "mirrored.gltf", m, "mirrored", false, &grey, "\"scale\": [-1, 1, 1]");
  // A turn of 0.5 degrees about z, small enough for assimp's own identity test
  // (entries within 1e-2 of the identity's off the diagonal): applied all the same.
  const double half = 0.25 * 3.14159265358979323846 / 180.0;
  std::ostringstream q;
  q.precision(17);
  q << "\"rotation\": [0, 0, " << std::sin(half) << ", " << std::cos(half) << "]";
  test::write_gltf(dir / "turned.gltf", m, "turned", false, &grey, q.str());
  const double c = std::cos(2 * half), sn = std::sin(2 * half);
  expect_point(point(read_scene((dir / "turned.gltf").string()), 0, 0),
               {1.75 * c - 0.25 * sn, 1.75 * sn + 0.25 * c, 0.5}, 1e-6);
  const Scene moved = read_scene((dir / "moved.gltf").string());
  const Scene mirrored = read_scene((dir / "mirrored.gltf").string());
  expect_point(point(moved, 0, 0), {11.75, 0.25, 0.5}, 0.0);
  expect_point(moved.patches[0].normal, glm::normalize(Vec3(1 / 1.5, 1 / 2.0, 1 / 0.75)), 1e-15);
  // Mirrored in x: face 0's points have x negated, and its last two are
  // swapped so that it still faces out of the (mirrored) octahedron.
  expect_octahedron_face0_mirrored_in_x(mirrored);
}

TEST(Readers, GltfTextureIsNamedInAWarning) {
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  const GltfMaterial grey{.name = "grey", .emissive = {1, 1, 1}};
  test::write_gltf(dir / "t.gltf", octahedron(), "t", false, &grey);
  std::ifstream in(dir / "t.gltf");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string key = "\"pbrMetallicRoughness\": {";
  text.replace(text.find(key), key.size(), key + "\"baseColorTexture\": {\"index\": 0}, ");
  const std::string meshes = " \"meshes\"";
  text.replace(text.find(meshes), meshes.size(),
               " \"textures\": [{\"source\": 0}], \"images\": [{\"uri\": \"wood.png\"}],\n" + meshes);
  write_text(dir / "t.gltf", text);
  const Scene s = read_scene((dir / "t.gltf").string());
  ASSERT_FALSE(s.report.warnings.empty());
  EXPECT_TRUE(test::mentions(s.report.warnings[0], {"t.gltf: materials[0] 'grey'", "baseColorTexture", "ignored"}));
}

// ---------------------------------------------------------------- JSON scenes

TEST(JsonScene, ScaleThenRotateXThenYThenZThenTranslate) {
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  PolyMesh tri;
  tri.positions = {{1, 1, 1}, {2, 1, 1}, {1, 2, 1}};
  tri.faces = {{0, 1, 2}};
  test::write_ply(dir / "tri.ply", tri, false);
  write_text(dir / "s.json",
             "{\"materials\": {\"m\": {\"reflectance\": [0.5, 0.5, 0.5], \"emission\": [1, 1, 1]}},\n"
             " \"objects\": [{\"file\": \"tri.ply\", \"material\": \"m\", \"transform\": {\"scale\": [1, 2, 3],"
             " \"rotate_deg\": [90, 90, 90], \"translate\": [10, 20, 30]}},\n"
             "  {\"file\": \"tri.ply\", \"material\": \"m\",\n"
             "   \"transform\": {\"scale\": 2, \"rotate_deg\": [0, 0, 30]}},\n"
             "  {\"file\": \"tri.ply\", \"material\": \"m\", \"transform\": {\"translate\": [0.5, 0, 0.5]}}]}\n");
  const Scene s = read_scene((dir / "s.json").string());
  ASSERT_EQ(s.patches.size(), 3u);
  // (1,1,1) scaled: (1,2,3); about x by 90: (1,-3,2); about y: (2,-3,-1);
  // about z: (3,2,-1); translated: (13,22,29). (z, y, x order would give (13,18,31).)
  expect_point(point(s, 0, 0), {13, 22, 29}, 0.0);
  // (2,1,1): (2,2,3) -> (2,-3,2) -> (2,-3,-2) -> (3,2,-2) -> (13,22,28).
  expect_point(point(s, 0, 1), {13, 22, 28}, 0.0);
  // (1,1,1) scaled by 2, about z by 30 degrees: (2cos30 - 2sin30, 2sin30 + 2cos30, 2).
  const double c = std::sqrt(3.0) / 2.0, sn = 0.5;
  expect_point(point(s, 1, 0), {2 * c - 2 * sn, 2 * sn + 2 * c, 2}, 1e-15);
  expect_point(point(s, 2, 0), {1.5, 1, 1.5}, 0.0);
  expect_point(point(s, 2, 2), {1.5, 2, 1.5}, 0.0);
}

TEST(JsonScene, MirroringScaleReversesFacesSoTheyKeepFacingOut) {
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  test::write_ply(dir / "octa.ply", octahedron(), false);
  write_text(dir / "s.json",
             "{\"materials\": {\"m\": {\"reflectance\": [0.5, 0.5, 0.5], \"emission\": [1, 1, 1]}},\n"
             " \"objects\": [{\"file\": \"octa.ply\", \"material\": \"m\",\n"
             "              \"transform\": {\"scale\": [-1, 1, 1]}}]}\n");
  const Scene s = read_scene((dir / "s.json").string());
  ASSERT_EQ(s.patches.size(), 8u);
  expect_octahedron_face0_mirrored_in_x(s);
}

TEST(JsonScene, PathsAreRelativeToTheJsonFile) {
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  fs::create_directories(dir / "scenes" / "meshes");
  test::write_ply(dir / "scenes" / "meshes" / "a.ply", octahedron(), true);
  fs::create_directories(dir / "other");
  test::write_off(dir / "other" / "b.off", cube_quads());
  write_text(dir / "scenes" / "s.json",
             "{\"materials\": {\"m\": {\"reflectance\": [0.5, 0.5, 0.5], \"emission\": [1, 1, 1]}},\n"
             " \"objects\": [{\"file\": \"meshes/a.ply\", \"material\": \"m\"},\n"
             "             {\"file\": \"../other/b.off\", \"material\": \"m\"},\n"
             "             {\"file\": \"" + (dir / "other" / "b.off").string() + "\", \"material\": \"m\","
             " \"transform\": {\"translate\": [5, 0, 0]}}]}\n");
  const fs::path cwd = fs::current_path();
  fs::current_path(dir);  // not the JSON file's directory (scenes/)
  const Scene s = read_scene((dir / "scenes" / "s.json").string());
  fs::current_path(cwd);
  EXPECT_EQ(s.patches.size(), 8u + 6u + 6u);
  EXPECT_EQ(s.vertices.size(), 6u + 8u + 8u);
  expect_point(point(s, 14, 0), {5, 0, 0}, 0.0);
  EXPECT_TRUE(contains(s.patches[8].file, "other/b.off (face 0)")) << s.patches[8].file;
}

TEST(JsonScene, ObjectsKeepTheirFilesMaterialsUnlessTheyNameOne) {
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  const PolyMesh m = octahedron();
  test::write_obj(dir / "room.obj", m, "room", "room.mtl", "white");
  write_text(dir / "room.mtl", "newmtl white\nKd 0.7 0.7 0.7\nnewmtl unused\nKd 0.1 0.1 0.1\n");
  const GltfMaterial lamp{.name = "lamp", .base = {0, 0, 0, 1}, .emissive = {1, 1, 1}, .strength = 10};
  test::write_gltf(dir / "lamp.glb", m, "lamp", true, &lamp);
  write_text(dir / "s.json",
             "{\"materials\": {\"clay\": {\"reflectance\": [0.6, 0.5, 0.4]}},\n"
             " \"objects\": [{\"file\": \"room.obj\"},\n"
             "             {\"file\": \"lamp.glb\", \"transform\": {\"translate\": [2.5, 0, 0]}},\n"
             "             {\"file\": \"room.obj\", \"transform\": {\"translate\": [5, 0, 0]}},\n"
             "             {\"file\": \"lamp.glb\", \"material\": \"clay\",\n"
             "              \"transform\": {\"translate\": [9, 0, 0]}}]}\n");
  const Scene s = read_scene((dir / "s.json").string());
  // clay (the JSON's), then white and lamp as the files carry them; the same
  // file twice adds nothing; "unused" is not taken.
  ASSERT_EQ(s.materials.size(), 3u);
  EXPECT_EQ(s.materials[0].name, "clay");
  EXPECT_EQ(s.materials[1].name, "white");
  EXPECT_EQ(s.materials[1].reflectance.x, 0.7);  // read by our MTL scan (tinyobjloader's was 1 ulp off)
  EXPECT_EQ(s.materials[2].name, "lamp");
  EXPECT_EQ(s.materials[2].emission, Rgb(10));
  ASSERT_EQ(s.patches.size(), 32u);
  for (size_t p = 0; p < 32; ++p) {
    const int want = p < 8 ? 1 : p < 16 ? 2 : p < 24 ? 1 : 0;
    EXPECT_EQ(s.patches[p].material, want) << "patch " << p;
  }
}

TEST(JsonScene, OneMaterialNameWithTwoValuesNamesBoth) {
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  test::write_obj(dir / "room.obj", octahedron(), "room", "room.mtl", "white");
  write_text(dir / "room.mtl", "# room\nnewmtl white\nKd 0.7 0.7 0.7\nKe 1 1 1\n");
  write_text(dir / "s.json",
             "{\"materials\": {\"white\": {\"reflectance\": [0.5, 0.5, 0.5]}},\n"
             " \"objects\": [{\"file\": \"room.obj\"}]}\n");
  const test::Thrown t = test::thrown<InputError>([&] { read_scene((dir / "s.json").string()); });
  EXPECT_TRUE(t.says({"s.json: objects[0]", "'white'", "twice"}));
  EXPECT_TRUE(t.says({"s.json: materials.white", "reflectance 0.5 0.5 0.5", "emission 0 0 0"}));
  EXPECT_TRUE(t.says({"room.mtl:2", "reflectance 0.7 0.7 0.7", "emission 1 1 1"}));
}

// ---------------------------------------------------------------- errors

struct JsonErrorCase {
  const char* name;
  const char* json;  // objects refer to octa.ply (no materials), room.obj (+ mtl), lamp.gltf
  const char* type;  // the error's class
  const char* key;   // where in the JSON, after "<dir>/scene.json: " ("" for the document)
  std::vector<std::string> values;  // what it names there: the bad value, the key missing
};

class JsonErrors : public ::testing::TestWithParam<JsonErrorCase> {};

TEST_P(JsonErrors, MessageNamesTheFileAndTheKey) {
  const JsonErrorCase c = GetParam();
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  test::write_ply(dir / "octa.ply", octahedron(), false);
  test::write_obj(dir / "room.obj", octahedron(), "room", "room.mtl", "white");
  write_text(dir / "room.mtl", "newmtl white\nKd 0.7 0.7 0.7\nKe 1 1 1\n");
  write_text(dir / "scene.json", c.json);
  const test::Thrown t = test::thrown<Error>([&] { read_scene((dir / "scene.json").string()); });
  EXPECT_EQ(t.type, c.type) << t.message;
  EXPECT_TRUE(t.says({(dir / "scene.json").string() + ": " + c.key}));
  for (const std::string& v : c.values) EXPECT_TRUE(t.says({v}));
}

#define GREY "\"materials\": {\"grey\": {\"reflectance\": [0.5, 0.5, 0.5]}}"

INSTANTIATE_TEST_SUITE_P(
    AllCases, JsonErrors,
    ::testing::Values(
        JsonErrorCase{"scale_string",
                      "{" GREY ", \"objects\": [{\"file\": \"room.obj\"}, {\"file\": \"octa.ply\", \"material\": "
                      "\"grey\", \"transform\": {\"scale\": \"big\"}}]}",
                      "InputError", "objects[1].transform.scale", {"got \"big\""}},
        JsonErrorCase{"scale_two",
                      "{" GREY ", \"objects\": [{\"file\": \"room.obj\", \"transform\": {\"scale\": [1, 2]}}]}",
                      "InputError", "objects[0].transform.scale", {"got [1,2]"}},
        JsonErrorCase{"scale_zero", "{\"objects\": [{\"file\": \"room.obj\", \"transform\": {\"scale\": [1, 0, 1]}}]}",
                      "InputError", "objects[0].transform.scale", {"[1,0,1]", "flatten"}},
        JsonErrorCase{"rotate_two",
                      "{\"objects\": [{\"file\": \"room.obj\", \"transform\": {\"rotate_deg\": [90, 0]}}]}",
                      "InputError", "objects[0].transform.rotate_deg", {"got [90,0]"}},
        JsonErrorCase{"translate_bool",
                      "{\"objects\": [{\"file\": \"room.obj\", \"transform\": {\"translate\": [true, 0, 0]}}]}",
                      "InputError", "objects[0].transform.translate", {"got [true,0,0]"}},
        JsonErrorCase{"transform_key",
                      "{\"objects\": [{\"file\": \"room.obj\", \"transform\": {\"rotate\": [0, 0, 0]}}]}",
                      "InputError", "objects[0].transform.rotate", {"unknown key", "\"rotate_deg\""}},
        JsonErrorCase{"object_key", "{\"objects\": [{\"file\": \"room.obj\", \"colour\": \"red\"}]}", "InputError",
                      "objects[0].colour", {"unknown key", "\"material\""}},
        JsonErrorCase{"top_key", "{\"objects\": [{\"file\": \"room.obj\"}], \"camera\": {}}", "InputError",
                      "\"camera\"", {"unknown key", "\"objects\""}},
        JsonErrorCase{"file_number", "{\"objects\": [{\"file\": 3}]}", "InputError", "objects[0].file", {"got 3"}},
        JsonErrorCase{"no_file", "{\"objects\": [{\"material\": \"grey\"}]}", "InputError", "objects[0]",
                      {"missing \"file\""}},
        JsonErrorCase{"no_objects", "{" GREY "}", "InputError", "", {"missing \"objects\""}},
        JsonErrorCase{"objects_empty", "{\"objects\": []}", "InputError", "objects", {"non-empty"}},
        JsonErrorCase{"material_number", "{" GREY ", \"objects\": [{\"file\": \"octa.ply\", \"material\": 5}]}",
                      "InputError", "objects[0].material", {"got 5"}},
        JsonErrorCase{"unknown_material", "{" GREY ", \"objects\": [{\"file\": \"octa.ply\", \"material\": \"gold\"}]}",
                      "InputError", "objects[0].material", {"\"gold\"", "defines grey"}},
        JsonErrorCase{"file_material_not_referable",
                      "{\"objects\": [{\"file\": \"room.obj\"}, {\"file\": \"octa.ply\", \"material\": \"white\"}]}",
                      "InputError", "objects[1].material", {"\"white\"", "defines none"}},
        JsonErrorCase{"ply_without_material", "{\"objects\": [{\"file\": \"room.obj\"}, {\"file\": \"octa.ply\"}]}",
                      "InputError", "objects[1]: 'octa.ply'", {"no materials", "\"material\""}},
        JsonErrorCase{"reflectance_high",
                      "{\"materials\": {\"white\": {\"reflectance\": [1.5, 0.5, 0.5]}}, \"objects\": [{\"file\": "
                      "\"room.obj\"}]}",
                      "InputError", "materials.white.reflectance", {"1.5 0.5 0.5", "[0, 1)"}},
        JsonErrorCase{"reflectance_string",
                      "{\"materials\": {\"white\": {\"reflectance\": \"white\"}}, \"objects\": [{\"file\": "
                      "\"room.obj\"}]}",
                      "InputError", "materials.white.reflectance", {"got \"white\""}},
        JsonErrorCase{"no_reflectance",
                      "{\"materials\": {\"lamp\": {\"emission\": [1, 1, 1]}}, \"objects\": [{\"file\": \"room.obj\"}]}",
                      "InputError", "materials.lamp", {"missing \"reflectance\""}},
        JsonErrorCase{"emission_negative",
                      "{\"materials\": {\"lamp\": {\"reflectance\": [0, 0, 0], \"emission\": [1, -1, 1]}}, "
                      "\"objects\": [{\"file\": \"room.obj\"}]}",
                      "InputError", "materials.lamp.emission", {"1 -1 1", ">= 0"}},
        JsonErrorCase{"material_key",
                      "{\"materials\": {\"lamp\": {\"reflectance\": [0, 0, 0], \"Ke\": [1, 1, 1]}}, "
                      "\"objects\": [{\"file\": \"room.obj\"}]}",
                      "InputError", "materials.lamp.Ke", {"unknown key", "\"emission\""}},
        JsonErrorCase{"missing_file", "{\"objects\": [{\"file\": \"meshes/bunny.ply\"}]}", "IoError",
                      "objects[0].file", {"'meshes/bunny.ply'", "not found"}},
        JsonErrorCase{"unknown_extension", "{\"objects\": [{\"file\": \"room.dae\"}]}", "InputError",
                      "objects[0].file: 'room.dae'", {"'.dae'"}},
        JsonErrorCase{"nested_json", "{\"objects\": [{\"file\": \"scene.json\"}]}", "InputError",
                      "objects[0].file: 'scene.json'", {"JSON scene"}},
        JsonErrorCase{"syntax", "{\"objects\": [{\"file\": \"room.obj\"},\n  ]}", "InputError", "",
                      {"line 2, column 3"}},
        JsonErrorCase{"not_object", "[1, 2]", "InputError", "", {"got [1,2]"}}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(JsonScene, NestingPastTheBoundIsAnErrorNotACrash) {
  // 100,000 levels overflowed the stack when the parsed value was printed
  // or destroyed; the parse now stops at kMaxJsonDepth. At the bound
  // itself the file parses and is refused for what it holds.
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  auto nested = [](int depth) { return std::string(static_cast<size_t>(depth), '[') + std::string(static_cast<size_t>(depth), ']'); };
  write_text(dir / "deep.json", nested(100000));
  const test::Thrown deep = test::thrown<InputError>([&] { read_scene((dir / "deep.json").string()); });
  EXPECT_TRUE(deep.says({(dir / "deep.json").string() + ": ", "256 levels"}));
  write_text(dir / "bound.json", nested(kMaxJsonDepth));
  const test::Thrown bound = test::thrown<InputError>([&] { read_scene((dir / "bound.json").string()); });
  EXPECT_TRUE(bound.says({(dir / "bound.json").string() + ": ", "got [["}));  // parsed, and not an object
}

TEST(JsonScene, AnArrayOfManyObjectsParsesInLinearTime) {
  // nlohmann's parse callback scanned an array's elements at the end of
  // each object in it: 100,000 glTF nodes took 2 s to parse, 300,000 about
  // 20 s, a million hours. Four times the objects take about four times the
  // time now, sixteen times when quadratic: the ratio, not a time, is
  // checked, so that a slow or busy machine cannot fail it.
  auto seconds = [](int n) {
    std::string text = "[";
    for (int i = 0; i < n; ++i) text += i ? ", {}" : "{}";
    text += "]";
    double best = INFINITY;
    for (int run = 0; run < 2; ++run) {
      const auto start = std::chrono::steady_clock::now();
      const nlohmann::json parsed = parse_json_bounded(text, "many.json");
      best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      EXPECT_EQ(parsed.size(), static_cast<size_t>(n));
    }
    return best;
  };
  const double small = seconds(75000), large = seconds(300000);
  EXPECT_LT(large, 8.0 * small) << small << " s for 75,000 objects, " << large << " s for 300,000";
}

TEST(JsonScene, AKeyWrittenTwiceInOneObjectIsAnError) {
  // The last value stood silently: two "materials" lost the first list, a
  // material's second "reflectance" replaced its first. Keys of different
  // objects may repeat.
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  write_text(dir / "s.json",
             "{\"materials\": {\"a\": {\"reflectance\": [0.5, 0.5, 0.5]}},\n"
             " \"objects\": [{\"file\": \"x.ply\", \"material\": \"a\"}],\n"
             " \"materials\": {\"b\": {\"reflectance\": [0.2, 0.2, 0.2]}}}");
  const test::Thrown top = test::thrown<InputError>([&] { read_scene((dir / "s.json").string()); });
  EXPECT_TRUE(top.says({(dir / "s.json").string() + ": key 'materials'", "twice", "depth 1"}));
  write_text(dir / "t.json",
             "{\"materials\": {\"a\": {\"reflectance\": [0.5, 0.5, 0.5], \"reflectance\": [0.2, 0.2, 0.2]}},\n"
             " \"objects\": []}");
  const test::Thrown inner = test::thrown<InputError>([&] { read_scene((dir / "t.json").string()); });
  EXPECT_TRUE(inner.says({(dir / "t.json").string() + ": key 'reflectance'", "twice", "depth 3"}));
  // The same key in sibling objects is no repeat: the scene is refused for
  // its missing file, not for its keys.
  write_text(dir / "u.json",
             "{\"materials\": {\"a\": {\"reflectance\": [0.5, 0.5, 0.5]}, \"b\": {\"reflectance\": [0.2, 0.2, 0.2]}},\n"
             " \"objects\": [{\"file\": \"x.ply\", \"material\": \"a\"}]}");
  const std::string missing = message_of<IoError>([&] { read_scene((dir / "u.json").string()); });
  EXPECT_TRUE(contains(missing, "not found")) << missing;
}

TEST(JsonScene, MissingFileIsAnIoErrorNamingTheResolvedPath) {
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  write_text(dir / "s.json", "{\"objects\": [{\"file\": \"sub/none.ply\", \"material\": \"m\"}]}");
  const test::Thrown t = test::thrown<IoError>([&] { read_scene((dir / "s.json").string()); });
  EXPECT_TRUE(t.says({(dir / "s.json").string() + ": objects[0].file", "'sub/none.ply'", "not found",
                      (dir / "sub" / "none.ply").string()}));
  const std::string direct = message_of<IoError>([&] { read_scene((dir / "none.json").string()); });
  EXPECT_TRUE(contains(direct, "none.json: no such file")) << direct;
}

struct FileErrorCase {
  const char* name;
  const char* file;     // written into a fresh directory
  const char* content;  // text of the file
  const char* element;  // where in the file: what follows "<dir>/<file>" (": " for the file as a whole)
  std::vector<std::string> values;  // what it names there
};

class FileErrors : public ::testing::TestWithParam<FileErrorCase> {};

TEST_P(FileErrors, MessageNamesTheFileAndTheElement) {
  const FileErrorCase c = GetParam();
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  write_text(dir / c.file, c.content);
  const test::Thrown t = test::thrown<InputError>([&] { read_scene((dir / c.file).string()); });
  EXPECT_TRUE(t.says({(dir / c.file).string() + c.element}));
  for (const std::string& v : c.values) EXPECT_TRUE(t.says({v}));
}

#define PLY_HEAD(nv, nf)                                                                                       \
  "ply\nformat ascii 1.0\nelement vertex " #nv "\nproperty float x\nproperty float y\nproperty float z\n"     \
  "element face " #nf "\nproperty list uchar int vertex_indices\nend_header\n"

#define GLTF_TRI(materials, material)                                                                         \
  "{\"asset\": {\"version\": \"2.0\"}, \"buffers\": [{\"byteLength\": 48, \"uri\": "                          \
  "\"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAEAAAACAAAA\"}],"  \
  " \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 36}, {\"buffer\": 0, \"byteOffset\": 36, "                \
  "\"byteLength\": 12}], \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": " \
  "\"VEC3\", \"min\": [0, 0, 0], \"max\": [1, 1, 0]}, {\"bufferView\": 1, \"componentType\": 5125, \"count\": 3,"\
  " \"type\": \"SCALAR\"}]" materials ", \"meshes\": [{\"name\": \"tri\", \"primitives\": [{\"attributes\": "     \
  "{\"POSITION\": 0}, \"indices\": 1" material "}]}], \"nodes\": [{\"mesh\": 0}], \"scenes\": [{\"nodes\": [0]}]}"

TEST(FileErrors, BinaryStlShorterThanItsFacetCountIsRefused) {
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  std::string bytes(84 + 50 * 2, '\0');  // a header, 2 facets stated, their 100 bytes...
  bytes[80] = 2;
  bytes.resize(bytes.size() - 30);        // ...of which 30 are missing
  write_text(dir / "mesh.stl", bytes);
  const test::Thrown t = test::thrown<InputError>([&] { read_scene((dir / "mesh.stl").string()); });
  EXPECT_TRUE(t.says({(dir / "mesh.stl").string() + ": ", "2 facets", "184 bytes", "has 154"}));
}

TEST(FileErrors, BinaryPlyLongerThanItsElementsIsRefused) {
  // Little- and big-endian, two triangles in the body, one declared: the
  // walk over the lists finds the second's 13 bytes (a count byte, three
  // 4-byte indices) beyond the declared elements. As declared, both read.
  for (const bool big : {false, true}) {
    const test::TempDir tmp(big ? "big_endian" : "little_endian");
    const fs::path& dir = tmp.path();
    auto body = [big](int faces) {
      std::string b = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
                      " 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                      "element face " + std::to_string(faces) + "\nproperty list uchar int vertex_indices\nend_header\n";
      auto put = [&](uint32_t v) {
        for (int k = 0; k < 4; ++k) b += static_cast<char>((v >> (8 * (big ? 3 - k : k))) & 0xFF);
      };
      const float xyz[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
      for (const auto& v : xyz)
        for (const float c : v) {
          uint32_t u = 0;
          std::memcpy(&u, &c, 4);
          put(u);
        }
      for (const auto& f : {std::array<uint32_t, 3>{0, 1, 2}, std::array<uint32_t, 3>{1, 3, 2}}) {
        b += static_cast<char>(3);
        for (const uint32_t i : f) put(i);
      }
      return b;
    };
    write_text(dir / "long.ply", body(1));
    const test::Thrown t = test::thrown<InputError>([&] { read_scene((dir / "long.ply").string()); });
    EXPECT_TRUE(t.says({(dir / "long.ply").string() + ": ", "13 bytes", "5 elements"}));
    write_text(dir / "right.ply", body(2));
    const test::Thrown right = test::thrown<InputError>([&] { read_scene((dir / "right.ply").string()); });
    EXPECT_TRUE(right.says({"right.ply", "no materials"}));  // read whole, then refused for its missing material
  }
}

INSTANTIATE_TEST_SUITE_P(
    AllCases, FileErrors,
    ::testing::Values(
        FileErrorCase{"ply_needs_material", "mesh.ply", PLY_HEAD(3, 1) "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                      ": ", {"PLY", "no materials", "{\"file\": \"mesh.ply\", \"material\": \"grey\"}"}},
        FileErrorCase{"stl_needs_material", "mesh.stl",
                      "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
                      "endfacet\nendsolid s\n",
                      ": ", {"STL", "no materials"}},
        // Truncated text files: assimp read them up to the break without a
        // word (STL) or reported a coincident face (PLY).
        FileErrorCase{"stl_ascii_truncated", "mesh.stl",
                      "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
                      "endfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n",
                      ": ", {"line 9", "'endfacet'"}},
        FileErrorCase{"stl_ascii_no_endsolid", "mesh.stl",
                      "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
                      "endfacet\n",
                      ": ", {"'endsolid'"}},
        FileErrorCase{"ply_ascii_truncated", "mesh.ply", PLY_HEAD(3, 2) "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                      ": ", {"5 elements", "4 lines"}},
        // More than the header declares: assimp dropped the rest silently.
        FileErrorCase{"ply_ascii_more_than_declared", "mesh.ply",
                      PLY_HEAD(4, 1) "0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n3 1 3 2\n\n",
                      ": line 15", {"5 elements"}},
        // Found by fuzz_assimp_reader: assimp allocated 413 M indices for
        // this count (4.9 GB, 20 s) before refusing it.
        FileErrorCase{"ply_list_count_beyond_its_line", "mesh.ply",
                      PLY_HEAD(3, 1) "0 0 0\n1 0 0\n0 1 0\n30000000000000000000 0 1 2\n",
                      ": line 13", {"'30000000000000000000'", "3 more"}},
        // Found by fuzz_assimp_reader: assimp allocated what a face count of
        // 46 digits declared (7.6 GB) before reading the body.
        FileErrorCase{"off_face_count_beyond_the_file", "mesh.off",
                      "OFF\n3 5000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                      ": OFF header line 2", {"3 vertices", "5e+09 faces", "4e+10 bytes", "has 29"}},
        // Blank lines: long enough for the counts, one face short all the same.
        FileErrorCase{"off_fewer_faces_than_stated", "mesh.off",
                      "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n\n\n\n\n\n\n",
                      ": ", {"2 face lines", "ends after 3 and 1"}},
        FileErrorCase{"ply_index", "mesh.ply", PLY_HEAD(3, 1) "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
                      ": line 13", {"index 7", "out of range", "3 vertices"}},
        FileErrorCase{"off_index", "mesh.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n",
                      ": OFF", {"Vertex index", "out of range"}},
        // assimp said "Faces with zero indices aren't allowed" of a face of 10.
        FileErrorCase{"off_face_of_ten_vertices", "mesh.off",
                      "OFF\n10 1 0\n0 0 0\n1 0 0\n2 0 0\n3 0 1\n3 0 2\n2 0 3\n1 0 3\n0 0 3\n-1 0 2\n-1 0 1\n"
                      "10 0 1 2 3 4 5 6 7 8 9\n",
                      ": OFF", {"more than 9"}},
        FileErrorCase{"ply_parse", "mesh.ply", PLY_HEAD(3, 1) "0 0 0\nx 0 0\n0 1 0\n3 0 1 2\n",
                      ": line 11", {"'x'", "not a number"}},
        // Headers assimp would loop on without end (found by fuzz_assimp_reader), or
        // allocate for before reading the body: refused before assimp sees them.
        // Found by fuzz_json_scene: a number beyond double threw nlohmann's
        // out_of_range, an internal error.
        FileErrorCase{"json_number_beyond_double", "scene.json", "{\"objects\": [{\"file\": \"a.obj\", "
                      "\"transform\": {\"scale\": 7E777}}]}",
                      ": ", {"overflow", "'7E777'"}},
        FileErrorCase{"ply_unknown_type", "mesh.ply",
                      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                      "element face 1\nproperty list u\x01" "char int vertex_indices\nend_header\n"
                      "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                      ": PLY header line 8", {"'u\\x01char'"}},
        FileErrorCase{"ply_no_end_header", "mesh.ply",
                      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                      "element face 1\nproperty list uchar int vertex_indices\nen'_header\n0 0 0\n",
                      ": PLY header line 9", {"'en'_header'"}},
        FileErrorCase{"ply_count_beyond_the_file", "mesh.ply", PLY_HEAD(3000000000, 1) "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                      ": ", {"18000000002 bytes", "has 26"}},
        FileErrorCase{"gltf_base_colour", "tri.gltf",
                      GLTF_TRI(", \"materials\": [{\"name\": \"paint\", \"pbrMetallicRoughness\": {\"baseColorFactor\":"
                               " [1, 0.5, 0.5, 1]}}]", ", \"material\": 0"),
                      ": materials[0] 'paint'", {"baseColorFactor 1 0.5 0.5", "[0, 1)"}},
        FileErrorCase{"gltf_default_base_colour", "tri.gltf",
                      GLTF_TRI(", \"materials\": [{\"emissiveFactor\": [1, 1, 1]}]", ", \"material\": 0"),
                      ": materials[0] 'materials[0]'", {"baseColorFactor 1 1 1", "glTF default", "[0, 1)"}},
        FileErrorCase{"gltf_strength", "tri.gltf",
                      GLTF_TRI(", \"materials\": [{\"name\": \"lamp\", \"emissiveFactor\": [1, 1, 1], \"extensions\": "
                               "{\"KHR_materials_emissive_strength\": {\"emissiveStrength\": \"high\"}}}]",
                               ", \"material\": 0"),
                      ": materials[0] 'lamp'",
                      {"extensions.KHR_materials_emissive_strength.emissiveStrength", "got \"high\""}},
        FileErrorCase{"gltf_no_material", "tri.gltf", GLTF_TRI("", ""),
                      ": ", {"mesh 'tri'", "no material"}},
        FileErrorCase{"gltf_version", "tri.gltf", "{\"asset\": {\"version\": \"1.0\"}}",
                      ": asset.version", {"\"1.0\"", "glTF 2.0"}},
        FileErrorCase{"glb_header", "tri.glb", "not a binary glTF file at all",
                      ": ", {"'glTF' header"}},
        FileErrorCase{"unknown_extension", "scene.dae", "<COLLADA/>",
                      ": ", {"'.dae'", ".obj, .ply"}},
        FileErrorCase{"no_extension", "scene", "", ": ", {"no file extension", ".obj, .ply"}}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(Readers, BadFaceInAPlyNamesTheFaceIndex) {
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  write_text(dir / "nan.ply", PLY_HEAD(4, 2) "0 0 0\n1 0 0\n0 1 0\nnan 1 1\n3 0 1 2\n3 0 1 3\n");
  write_text(dir / "degenerate.ply", PLY_HEAD(3, 2) "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 0\n");
  write_text(dir / "nan.json", grey_scene("nan.ply"));
  write_text(dir / "degenerate.json", grey_scene("degenerate.ply"));
  const test::Thrown nan = test::thrown<InputError>([&] { read_scene((dir / "nan.json").string()); });
  EXPECT_TRUE(nan.says({(dir / "nan.ply").string() + ": line 13", "'nan'", "not finite"}));  // not a number it reads
  const test::Thrown deg = test::thrown<InputError>([&] { read_scene((dir / "degenerate.json").string()); });
  EXPECT_TRUE(deg.says({(dir / "degenerate.ply").string() + " (face 1): face 'degenerate'", "2 distinct vertices"}));
}

TEST(Readers, ObjStaysAsItWasAndMissingFilesAreIoErrors) {
  // .obj goes to the OBJ reader unchanged: its line-numbered messages.
  const std::string msg = message_of<InputError>([&] { read_scene(kData + "/bad/nan_coordinate.obj"); });
  EXPECT_TRUE(contains(msg, "nan_coordinate.obj:6")) << msg;
  const Scene cornell = read_scene(kData + "/cornell_box/cornell_box.obj");
  EXPECT_EQ(cornell.patches.size(), 21u);
  for (const char* f : {"none.ply", "none.stl", "none.off", "none.gltf", "none.glb", "none.obj", "none.json"}) {
    const std::string m = message_of<IoError>([&] { read_scene(kData + "/" + f); });
    EXPECT_TRUE(contains(m, std::string(f) + ": no such file")) << m;
  }
}

TEST(Readers, ObjAndMtlStatementsGoOnPastABackslashAtTheLineEnd) {
  // The OBJ and MTL formats continue a statement ending in a backslash on
  // the next line; a comment ending in one does not swallow what follows.
  // tinyobjloader knows no continuation, and the face below used to be an
  // error ("face vertex index '\' is not a valid index").
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  const std::string mtl_plain = "newmtl white\nKd 0.7 0.6 0.5\nnewmtl lamp\nKe 10 10 10\n";
  const std::string obj_plain =
      "mtllib m.mtl\nusemtl white\nv 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf 1 4 3 2\n"
      "usemtl lamp\nv 0.25 1 0.25\nv 0.75 1 0.25\nv 0.75 1 0.75\nv 0.25 1 0.75\nf 5 6 7 8\n";
  write_text(dir / "plain" / "m.mtl", mtl_plain);
  write_text(dir / "plain" / "s.obj", obj_plain);
  write_text(dir / "cont" / "m.mtl", "newmtl white\nKd 0.7 \\\n 0.6 0.5\nnewmtl lamp\nKe 10 10 10\n");
  write_text(dir / "cont" / "s.obj",
             "# made in C:\\models\\\nmtllib m.mtl\nusemtl white\nv 0 0 0\nv 1 \\\n0 0\nv 1 0 1\nv 0 0 1\n"
             "f 1 4 \\\n 3 \\\n 2\nusemtl lamp\nv 0.25 1 0.25\nv 0.75 1 0.25\nv 0.75 1 0.75\nv 0.25 1 0.75\n"
             "f 5 6 7 8\n");
  const Scene plain = read_scene((dir / "plain" / "s.obj").string());
  const Scene cont = read_scene((dir / "cont" / "s.obj").string());
  ASSERT_EQ(cont.patches.size(), 2u);
  expect_same_scene(plain, cont, 0.0, "continued");
  EXPECT_EQ(cont.materials[0].reflectance, Rgb(0.7, 0.6, 0.5));
  // The lamp's face starts on line 17 of the continued file: messages name
  // the line a statement starts on.
  EXPECT_EQ(cont.patches[1].line, 17);
  write_text(dir / "bad" / "m.mtl", mtl_plain);
  write_text(dir / "bad" / "s.obj", "mtllib m.mtl\nusemtl white\nv 0 0 0\nv 1 0 \\\n0\nv 1 0 1\nf 1 2 \\\n9\n");
  const test::Thrown t = test::thrown<InputError>([&] { read_scene((dir / "bad" / "s.obj").string()); });
  EXPECT_TRUE(t.says({"s.obj:7", "index 9"}));
}

TEST(Readers, AnObjFaceOfMoreThan255VerticesKeepsThemAllAndTheFacesAfterIt) {
  // tinyobjloader counts a face's vertices in an unsigned char: a round
  // lamp of 300 vertices came out with 44 of them (1.9% of its area, no
  // word said), and the faces after it could be shifted. The lamp here is
  // written with negative indices and v//vn pairs, its vertices with a
  // colour each (x y z r g b, as MeshLab writes them), and a triangle of
  // another object and material follows it.
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  write_text(dir / "m.mtl", "newmtl white\nKd 0.7 0.7 0.7\nnewmtl lamp\nKe 10 10 10\nnewmtl grey\nKd 0.5 0.5 0.5\n");
  const int n = 300;
  const double r = 0.3;
  std::ostringstream obj;
  obj << "mtllib m.mtl\nvn 0 -1 0\no floor\nusemtl white\nv -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\nf 1 4 3 2\n";
  obj << "o lamp\nusemtl lamp\n";
  obj.precision(17);
  for (int k = 0; k < n; ++k) {
    const double a = 2.0 * std::numbers::pi * k / n;
    obj << "v " << r * std::cos(a) << " 2.9 " << r * std::sin(a) << " 1 0.5 0.25\n";
  }
  obj << "f";
  for (int k = 0; k < n; ++k) obj << " " << k - n << "//1";
  obj << "\no shelf\nusemtl grey\nv 0 1 0\nv 1 1 0\nv 0 1 1\nf -3 -1 -2\n";
  write_text(dir / "s.obj", obj.str());
  const Scene s = read_scene((dir / "s.obj").string());
  ASSERT_EQ(s.patches.size(), 3u);
  const Patch& lamp = s.patches[1];
  EXPECT_EQ(lamp.name, "lamp");
  EXPECT_EQ(s.material_of(lamp).name, "lamp");
  ASSERT_EQ(lamp.outer.size(), static_cast<size_t>(n));
  const double area = 0.5 * n * r * r * std::sin(2.0 * std::numbers::pi / n);
  EXPECT_NEAR(s.patch_area(1), area, 1e-12 * area);
  EXPECT_NEAR(glm::length(s.vertices[static_cast<size_t>(lamp.outer[0])] - Vec3(r, 2.9, 0.0)), 0.0, 1e-12);
  const Patch& shelf = s.patches[2];
  EXPECT_EQ(shelf.name, "shelf");
  EXPECT_EQ(s.material_of(shelf).name, "grey");
  EXPECT_NEAR(s.patch_area(2), 0.5, 1e-12);
  EXPECT_EQ(shelf.line, 318);  // 9 lines, then the lamp's 2 + 300 + 1, then 2 + 3 before it
}

TEST(Readers, ExtensionIsCaseInsensitive) {
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  test::write_ply(dir / "octa.PLY", octahedron(), true);
  write_text(dir / "s.JSON", grey_scene("octa.PLY"));
  EXPECT_EQ(read_scene((dir / "s.JSON").string()).patches.size(), 8u);
}

// ---------------------------------------------------------------- the bunny

namespace {
// The bundled bunny.ply, parsed here without assimp (its header is known).
PolyMesh read_bunny_ply() {
  std::ifstream in(kData + "/bunny/bunny.ply");
  std::string line;
  size_t nv = 0, nf = 0;
  while (std::getline(in, line) && line != "end_header") {
    std::istringstream l(line);
    std::string a, b;
    l >> a >> b;
    if (a == "element" && b == "vertex") l >> nv;
    if (a == "element" && b == "face") l >> nf;
  }
  PolyMesh m;
  for (size_t i = 0; i < nv; ++i) {
    std::array<float, 3> p{};
    in >> p[0] >> p[1] >> p[2];
    m.positions.push_back(p);
  }
  for (size_t i = 0; i < nf; ++i) {
    size_t n = 0;
    in >> n;
    std::vector<uint32_t> f(n);
    for (auto& v : f) in >> v;
    m.faces.push_back(f);
  }
  return m;
}
}  // namespace

TEST(Bunny, SceneStandsOnTheFloorOfItsRoom) {
  const Scene s = read_scene(kData + "/bunny/bunny_room.json");
  // Room: floor, 4 walls, 4 ceiling pieces, the light; bunny: 3674 triangles.
  EXPECT_EQ(s.report.faces_read, 10 + 3674);
  ASSERT_EQ(s.patches.size(), 10u + 3674u);
  EXPECT_EQ(s.vertices.size(), 16u + 1839u);
  EXPECT_EQ(s.report.zero_area_faces_dropped, 0);
  EXPECT_EQ(s.report.nonplanar_faces_split, 0);
  EXPECT_TRUE(s.has_emitter());
  ASSERT_EQ(s.materials.size(), 5u);  // clay, then white, red, green, light from room.mtl
  EXPECT_EQ(s.materials[0].name, "clay");
  Vec3 lo(1e300), hi(-1e300);
  double area = 0.0;
  for (size_t p = 10; p < s.patches.size(); ++p) {
    EXPECT_EQ(s.patches[p].name, "bunny");
    EXPECT_EQ(s.patches[p].material, 0);
    area += s.patch_area(static_cast<int>(p));
    for (int v : s.patches[p].outer) {
      lo = glm::min(lo, s.vertices[static_cast<size_t>(v)]);
      hi = glm::max(hi, s.vertices[static_cast<size_t>(v)]);
    }
  }
  // Lowest point exactly on the floor; 9654748 + 3149 units of 5e-8 m tall; centred on x = z = 1.
  EXPECT_EQ(lo.y, 0.0);
  EXPECT_NEAR(hi.y, 9657897 * 5e-8, 1e-15);
  EXPECT_NEAR((lo.x + hi.x) / 2, 1.0, 1e-8);
  EXPECT_NEAR((lo.z + hi.z) / 2, 1.0, 1e-8);
  // Its area, summed over the PLY's triangles scaled by 5e-8 (in Python, as a check).
  EXPECT_NEAR(area, 0.5467231782172347, 1e-12);
}

TEST(Bunny, EveryFormatOfTheSameMeshGivesIdenticalPatches) {
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  const PolyMesh bunny = read_bunny_ply();
  ASSERT_EQ(bunny.positions.size(), 1839u);
  ASSERT_EQ(bunny.faces.size(), 3674u);
  const auto files = test::write_every_format(dir, bunny, "bunny");
  std::ifstream in(kData + "/bunny/bunny_room.json");
  const std::string json((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const Scene ply = read_scene(kData + "/bunny/bunny_room.json");
  for (const std::string& f : files) {
    std::string text = json;
    text.replace(text.find("\"room.obj\""), 10, "\"" + kData + "/bunny/room.obj\"");
    text.replace(text.find("\"bunny.ply\""), 11, "\"" + f + "\"");
    write_text(dir / (f + ".json"), text);
    expect_identical_scene(ply, read_scene((dir / (f + ".json")).string()), f);
  }
}

// ---------------------------------------------------------------- size

namespace {
}  // namespace

TEST(Readers, MillionTrianglePlyLoadsWhole) {
  // Nothing lost at scale: every face and vertex of a 10^6-triangle binary
  // PLY. (Load times per format: radmesh_bench --load-times.)
  const test::TempDir tmp;
  const fs::path& dir = tmp.path();
  const int n = 708;  // 2 * 708^2 = 1002528 triangles, 709^2 = 502681 vertices
  test::write_ply(dir / "grid.ply", test::grid(n), true);
  write_text(dir / "grid.json", grey_scene("grid.ply"));
  const Scene s = read_scene((dir / "grid.json").string());
  EXPECT_EQ(s.patches.size(), 1002528u);
  EXPECT_EQ(s.vertices.size(), 502681u);
  EXPECT_EQ(s.report.vertices_welded, 3 * 1002528 - 502681);
}

// ---------------------------------------------------------------- hostile files
//
// Classes of defects found by hostile runs of `radmesh run`: scene graphs
// that crash or stall the importer, numbers that two parsers read two ways,
// readers that drop data, counts that allocate what the file cannot hold,
// and messages that mislead.

namespace {

std::string base64(const std::string& bytes) {
  static const char* const k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const size_t n = std::min<size_t>(3, bytes.size() - i);
    uint32_t v = 0;
    for (size_t b = 0; b < 3; ++b) v = v << 8 | (b < n ? static_cast<uint8_t>(bytes[i + b]) : 0u);
    for (size_t c = 0; c < 4; ++c) out += c <= n ? k[(v >> (18 - 6 * c)) & 63] : '=';
  }
  return out;
}

template <class T>
void append(std::string& bytes, T v) {
  char c[sizeof(T)];
  std::memcpy(c, &v, sizeof c);
  bytes.append(c, sizeof c);
}

// A glTF of one mesh (a unit square of two triangles, with a grey emitting
// material), its positions and then its u32 indices in one buffer; each
// field below is spliced into its JSON to make it hostile.
struct GltfSpec {
  std::vector<float> positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  std::vector<uint32_t> indices = {0, 1, 2, 1, 3, 2};
  std::string position_view;      // keys added to bufferViews[0] (", \"byteStride\": 4")
  std::string position_accessor;  // keys added to accessors[0]
  std::string position_type = "5126";
  std::string index_accessor;     // keys added to accessors[1]
  std::string indices_key = "1";  // the primitive's "indices"
  std::string nodes = "[{\"mesh\": 0}]";
  std::string scenes = "[{\"nodes\": [0]}]";
  std::string top;  // keys added to the document
};

// The buffer's bytes: the positions, then the indices.
std::string gltf_bin(const GltfSpec& s) {
  std::string bin;
  for (const float f : s.positions) append(bin, f);
  for (const uint32_t i : s.indices) append(bin, i);
  return bin;
}

// The glTF JSON: its buffer in a data URI, or (glb) in the BIN chunk.
std::string gltf_json(const GltfSpec& s, bool glb = false) {
  const std::string bin = gltf_bin(s);
  const size_t pos_bytes = 4 * s.positions.size(), index_bytes = 4 * s.indices.size();
  std::ostringstream j;
  j << "{\"asset\": {\"version\": \"2.0\"},\n \"buffers\": [{\"byteLength\": " << bin.size();
  if (!glb) j << ", \"uri\": \"data:application/octet-stream;base64," << base64(bin) << "\"";
  const bool indexed = !s.indices.empty();
  j << "}],\n \"bufferViews\": [{\"buffer\": 0, \"byteLength\": " << pos_bytes << s.position_view << "}";
  if (indexed) j << ", {\"buffer\": 0, \"byteOffset\": " << pos_bytes << ", \"byteLength\": " << index_bytes << "}";
  j << "],\n \"accessors\": [{\"bufferView\": 0, \"componentType\": " << s.position_type
    << ", \"count\": " << s.positions.size() / 3 << ", \"type\": \"VEC3\"" << s.position_accessor << "}";
  if (indexed)
    j << ",\n   {\"bufferView\": 1, \"componentType\": 5125, \"count\": " << s.indices.size()
      << ", \"type\": \"SCALAR\"" << s.index_accessor << "}";
  j << "],\n"
    << " \"materials\": [{\"name\": \"grey\", \"pbrMetallicRoughness\": {\"baseColorFactor\": [0.5, 0.5, 0.5, 1]},"
    << " \"emissiveFactor\": [1, 1, 1]}],\n"
    << " \"meshes\": [{\"name\": \"square\", \"primitives\": [{\"attributes\": {\"POSITION\": 0}"
    << (indexed ? ", \"indices\": " + s.indices_key : "") << ", \"material\": 0}]}],\n"
    << " \"nodes\": " << s.nodes << ",\n \"scenes\": " << s.scenes << s.top << "}\n";
  return j.str();
}

// A binary glTF of `json` and `bin`; `tail` is written after what its
// header declares.
std::string glb_bytes(std::string json, std::string bin, const std::string& tail = "") {
  while (json.size() % 4) json += ' ';
  while (bin.size() % 4) bin += '\0';
  std::string out;
  append(out, 0x46546C67u);
  append(out, 2u);
  append(out, static_cast<uint32_t>(12 + 8 + json.size() + 8 + bin.size()));
  append(out, static_cast<uint32_t>(json.size()));
  append(out, 0x4E4F534Au);
  out += json;
  append(out, static_cast<uint32_t>(bin.size()));
  append(out, 0x004E4942u);
  return out + bin + tail;
}

// A chain of n nodes, each the only child of the one before; the last holds the mesh.
std::string node_chain(int n) {
  std::string nodes = "[";
  for (int i = 0; i + 1 < n; ++i) nodes += "{\"children\": [" + std::to_string(i + 1) + "]}, ";
  return nodes + "{\"mesh\": 0}]";
}

}  // namespace

TEST(HostileGltf, NodesNestedPastTheDepthBoundAreRefusedBeforeTheImporterRecurses) {
  // 20,000 levels overflowed the stack in assimp's importer (a segmentation
  // fault). Up to the bound, 256 levels, the square is read.
  const test::TempDir tmp;
  GltfSpec s;
  s.nodes = node_chain(20000);
  write_text(tmp / "deep.gltf", gltf_json(s));
  const test::Thrown t = test::thrown<InputError>([&] { read_scene((tmp / "deep.gltf").string()); });
  EXPECT_TRUE(t.says({(tmp / "deep.gltf").string() + ": nodes[256]", "256 levels"}));
  s.nodes = node_chain(256);
  write_text(tmp / "bound.gltf", gltf_json(s));
  EXPECT_EQ(read_scene((tmp / "bound.gltf").string()).patches.size(), 2u);
}

TEST(HostileGltf, MoreNodesThanTheBoundAreRefused) {
  // assimp keeps 2 KB a node: a million nodes, 12 MB of JSON, took 2 GB.
  const test::TempDir tmp;
  GltfSpec s;
  s.nodes = "[{\"mesh\": 0}";
  for (int i = 0; i < 100000; ++i) s.nodes += ", {}";
  s.nodes += "]";
  write_text(tmp / "wide.gltf", gltf_json(s));
  const test::Thrown t = test::thrown<InputError>([&] { read_scene((tmp / "wide.gltf").string()); });
  EXPECT_TRUE(t.says({(tmp / "wide.gltf").string() + ": nodes", "100001 nodes", "100000"}));
}

TEST(HostileGltf, ANodeTreeThatIsNotATreeIsRefusedNamingTheNode) {
  // A node that is its own child, a cycle, a node with two parents (which
  // assimp read twice, doubling its faces), a child or scene root that is
  // not a node (assimp skipped a child written 1.0 without a word).
  struct Case {
    const char* name;
    std::string nodes, scenes, top;
    std::vector<std::string> says;
  };
  const std::vector<Case> cases = {
      {"self", "[{\"mesh\": 0, \"children\": [0]}]", "[{\"nodes\": [0]}]", "", {"nodes[0]", "cycle"}},
      {"cycle", "[{\"children\": [1]}, {\"children\": [2]}, {\"mesh\": 0, \"children\": [1]}]", "[{\"nodes\": [0]}]",
       "", {"nodes[1]", "cycle"}},
      {"two_parents", "[{\"children\": [2]}, {\"children\": [2]}, {\"mesh\": 0}]", "[{\"nodes\": [0, 1]}]", "",
       {"nodes[2]", "nodes[0]", "nodes[1]"}},
      {"child_out_of_range", "[{\"mesh\": 0, \"children\": [3]}]", "[{\"nodes\": [0]}]", "",
       {"nodes[0].children", "3", "1 node"}},
      {"child_fraction", "[{\"children\": [1.0]}, {\"mesh\": 0}]", "[{\"nodes\": [0]}]", "",
       {"nodes[0].children", "1.0"}},
      {"root_out_of_range", "[{\"mesh\": 0}]", "[{\"nodes\": [0, 7]}]", "", {"scenes[0].nodes", "7"}},
      {"root_is_a_child", "[{\"children\": [1]}, {\"mesh\": 0}]", "[{\"nodes\": [0, 1]}]", "",
       {"nodes[1]", "scenes[0]"}},
      {"scene_out_of_range", "[{\"mesh\": 0}]", "[{\"nodes\": [0]}]", ", \"scene\": 3", {"scene", "3", "1 scene"}}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const test::TempDir tmp(c.name);
    GltfSpec s;
    s.nodes = c.nodes;
    s.scenes = c.scenes;
    s.top = c.top;
    write_text(tmp / "g.gltf", gltf_json(s));
    const test::Thrown t = test::thrown<InputError>([&] { read_scene((tmp / "g.gltf").string()); });
    EXPECT_TRUE(t.says({(tmp / "g.gltf").string() + ": "}));
    for (const std::string& part : c.says) EXPECT_TRUE(t.says({part}));
  }
}

TEST(HostileGltf, PrimitivesThatWouldLoseOrMisreadTrianglesAreRefused) {
  // assimp dropped a triangle with an index out of range and the last
  // indices short of a triangle, read a stride shorter than its element or
  // an accessor reaching past its view as other bytes, and took "indices":
  // 1.0 for no indices at all, each without a word.
  struct Case {
    const char* name;
    GltfSpec spec;
    std::vector<std::string> says;
  };
  std::vector<Case> cases;
  GltfSpec s;
  s.indices = {0, 1, 2, 1, 9, 2};
  cases.push_back({"index_out_of_range", s, {"accessors[1]", "index 9", "4 vertices"}});
  s = GltfSpec();
  s.indices = {0, 1, 2, 1};
  cases.push_back({"partial_triangle", s, {"accessors[1]", "4 indices", "multiple of 3"}});
  s = GltfSpec();
  s.indices.clear();
  s.positions.resize(15, 0.5f);  // 5 vertices, no indices
  cases.push_back({"partial_triangle_without_indices", s, {"accessors[0]", "5 vertices", "multiple of 3"}});
  s = GltfSpec();
  s.position_view = ", \"byteStride\": 4";
  cases.push_back({"stride_shorter_than_its_element", s, {"bufferViews[0]", "byteStride 4", "12"}});
  s = GltfSpec();
  s.position_accessor = ", \"byteOffset\": 12";
  cases.push_back({"accessor_past_its_view", s, {"accessors[0]", "byteOffset 12", "60", "48"}});
  s = GltfSpec();
  s.indices_key = "1.0";
  cases.push_back({"indices_as_a_fraction", s, {"meshes[0].primitives[0].indices", "1.0"}});
  s = GltfSpec();
  s.position_type = "5123";
  cases.push_back({"positions_not_float", s, {"accessors[0]", "5123"}});
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const test::TempDir tmp(c.name);
    write_text(tmp / "g.gltf", gltf_json(c.spec));
    const test::Thrown t = test::thrown<InputError>([&] { read_scene((tmp / "g.gltf").string()); });
    EXPECT_TRUE(t.says({(tmp / "g.gltf").string() + ": "}));
    for (const std::string& part : c.says) EXPECT_TRUE(t.says({part}));
  }
}

TEST(HostileGltf, CountsCannotAskForMoreThanTheFileHolds) {
  // A sparse accessor of 4e9 vertices without a view had assimp allocate
  // 48 GB; a GLB's BIN chunk shorter than its buffer, and bytes past the
  // length its header declares, are refused too.
  const test::TempDir tmp;
  GltfSpec s;
  s.position_accessor = ", \"sparse\": {\"count\": 1, \"indices\": {\"bufferView\": 1, \"componentType\": 5125},"
                        " \"values\": {\"bufferView\": 0}}";
  std::string json = gltf_json(s);
  const std::string viewed = "\"bufferView\": 0, \"componentType\": 5126, \"count\": 4,";
  json.replace(json.find(viewed), viewed.size(), "\"componentType\": 5126, \"count\": 4000000000,");
  write_text(tmp / "sparse.gltf", json);
  const test::Thrown sparse = test::thrown<InputError>([&] { read_scene((tmp / "sparse.gltf").string()); });
  EXPECT_TRUE(sparse.says({(tmp / "sparse.gltf").string() + ": accessors[0]", "4000000000"}));

  const GltfSpec plain;
  write_text(tmp / "tail.glb", glb_bytes(gltf_json(plain, true), gltf_bin(plain), "junk"));
  const test::Thrown tail = test::thrown<InputError>([&] { read_scene((tmp / "tail.glb").string()); });
  EXPECT_TRUE(tail.says({(tmp / "tail.glb").string() + ": ", "4 bytes"}));
  std::string short_bin = gltf_bin(plain);
  short_bin.resize(60);
  write_text(tmp / "short.glb", glb_bytes(gltf_json(plain, true), short_bin));
  const test::Thrown shrt = test::thrown<InputError>([&] { read_scene((tmp / "short.glb").string()); });
  EXPECT_TRUE(shrt.says({(tmp / "short.glb").string() + ": buffers[0]", "72", "60"}));
  // As written, both read.
  write_text(tmp / "right.glb", glb_bytes(gltf_json(plain, true), gltf_bin(plain)));
  EXPECT_EQ(read_scene((tmp / "right.glb").string()).patches.size(), 2u);
}

TEST(HostileFiles, ABinaryPlyListCountBeyondTheFileIsRefusedBeforeAnythingIsAllocated) {
  // One face claiming 2^26 vertices made a 280-byte file take 564 MB.
  const test::TempDir tmp;
  std::string b = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                  "property float z\nelement face 1\nproperty list int int vertex_indices\nend_header\n";
  for (const float f : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) append(b, f);
  append(b, static_cast<int32_t>(1 << 26));
  for (const int32_t i : {0, 1, 2}) append(b, i);
  write_text(tmp / "big.ply", b);
  const test::Thrown t = test::thrown<InputError>([&] { read_scene((tmp / "big.ply").string()); });
  EXPECT_TRUE(t.says({(tmp / "big.ply").string() + ": ", "face 0", "67108864", "12 bytes"}));
  // A negative count in a signed count type.
  b.replace(b.size() - 16, 4, std::string("\xff\xff\xff\xff", 4));
  write_text(tmp / "negative.ply", b);
  const test::Thrown n = test::thrown<InputError>([&] { read_scene((tmp / "negative.ply").string()); });
  EXPECT_TRUE(n.says({(tmp / "negative.ply").string() + ": ", "face 0", "-1"}));
}

TEST(HostileFiles, DataPastWhatAnOffPlyOrStlDeclaresIsRefusedNotDropped) {
  // assimp read the faces an OFF header declares and dropped the rest, and
  // took the values a line declares and dropped what followed on it.
  struct Case {
    const char* name;
    const char* file;
    const char* text;
    std::vector<std::string> says;
  };
  const std::vector<Case> cases = {
      {"off_extra_face", "mesh.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n3 1 3 2\n",
       {"line 8", "1 face"}},
      {"off_extra_vertex_value", "mesh.off", "OFF\n3 1 0\n0 0 0\n1 0 0 5\n0 1 0\n3 0 1 2\n", {"line 4", "'5'"}},
      {"off_extra_face_value", "mesh.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 x\n", {"line 6", "'x'"}},
      {"ply_extra_vertex_value", "mesh.ply", PLY_HEAD(3, 1) "0 0 0\n1 0 0 5\n0 1 0\n3 0 1 2\n", {"line 11", "'5'"}},
      {"ply_extra_face_value", "mesh.ply", PLY_HEAD(3, 1) "0 0 0\n1 0 0\n0 1 0\n3 0 1 2 2\n", {"line 13", "'2'"}},
      {"ply_missing_value", "mesh.ply", PLY_HEAD(3, 1) "0 0 0\n1 0\n0 1 0\n3 0 1 2\n", {"line 11"}},
      {"stl_extra_value", "mesh.stl",
       "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0 7\nvertex 0 1 0\nendloop\nendfacet\n"
       "endsolid s\n",
       {"line 5", "'7'"}},
      {"stl_unknown_word", "mesh.stl",
       "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertexx 0 1 0\nvertex 0 1 0\nendloop\n"
       "endfacet\nendsolid s\n",
       {"line 6", "'vertexx'"}},
      {"stl_two_vertices", "mesh.stl",
       "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid s\n",
       {"line 6", "2 vertices"}}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const test::TempDir tmp(c.name);
    write_text(tmp / c.file, c.text);
    write_text(tmp / "s.json", grey_scene(c.file));
    const test::Thrown t = test::thrown<InputError>([&] { read_scene((tmp / "s.json").string()); });
    EXPECT_TRUE(t.says({(tmp / c.file).string() + ": "}));
    for (const std::string& part : c.says) EXPECT_TRUE(t.says({part}));
  }
}

namespace {

// Number tokens outside the one syntax every text reader takes: refused at
// their line by each. Before, tinyobjloader read 0x1p0 as 0 and the long
// one as 0 (the check, strtod, as 1), and assimp read 1,5 as 1.5.
const std::vector<std::string>& refused_numbers() {
  static const std::vector<std::string> tokens = {
      "0x1p0", "+1", "1,5", "nan", "-inf", "infinity", "1e400", "1e", ".", "-", "1.5.0", "1e5x",
      "0." + std::string(330, '0') + "1e331", std::string(101, '1'), "1e99999999999999999999"};
  return tokens;
}

// Tokens in the syntax that assimp's parser reads otherwise (a run of 24
// digits as 0, digits past the 15th decimal as nothing): read in OBJ, whose
// parser gets them right, and refused at their line in PLY, OFF and STL.
const std::vector<std::string>& numbers_assimp_misreads() {
  static const std::vector<std::string> tokens = {"123456789012345678901234e-23", "0.0000000000000000015e18"};
  return tokens;
}

// Tokens every reader reads as 1.5.
const std::vector<std::string>& numbers_meaning_one_and_a_half() {
  static const std::vector<std::string> tokens = {"1.5", "1.50", "15e-1", "0.15E1", "150e-2", "1.5e+0", "001.5"};
  return tokens;
}

// The text of a file holding a unit right triangle whose vertex (1, 0, 0)
// has its x written as `x`, and the line that x is on.
std::pair<std::string, int> triangle_with_x(const std::string& format, const std::string& x) {
  if (format == "obj") return {"mtllib m.mtl\nusemtl grey\nv 0 0 0\nv " + x + " 0 0\nv 0 1 0\nf 1 2 3\n", 4};
  if (format == "ply")
    return {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n" + x + " 0 0\n0 1 0\n3 0 1 2\n",
            11};
  if (format == "ply_double")
    return {"ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n" + x + " 0 0\n0 1 0\n3 0 1 2\n",
            11};
  if (format == "off") return {"OFF\n3 1 0\n0 0 0\n" + x + " 0 0\n0 1 0\n3 0 1 2\n", 4};
  return {"solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex " + x +
              " 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid s\n",
          5};
}

}  // namespace

TEST(HostileNumbers, EveryTextReaderReadsANumberAsItsTextMeansOrRefusesItsLine) {
  // The value checked is the value used: a token either reads as what it
  // means (to the precision the format keeps: double in OBJ, float in the
  // others) or is refused at its line, naming it.
  for (const std::string format : {"obj", "ply", "ply_double", "off", "stl"}) {
    const std::string ext = format == "ply_double" ? "ply" : format;
    auto read = [&](const std::string& x, const test::TempDir& tmp) {
      write_text(tmp / ("t." + ext), triangle_with_x(format, x).first);
      write_text(tmp / "m.mtl", "newmtl grey\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
      write_text(tmp / "s.json", grey_scene("t." + ext));
      return read_scene(ext == "obj" ? (tmp / "t.obj").string() : (tmp / "s.json").string());
    };
    auto expect_refused = [&](const std::string& x) {
      SCOPED_TRACE(format + " '" + x.substr(0, 30) + "'");
      const test::TempDir tmp(format);
      const test::Thrown t = test::thrown<InputError>([&] { read(x, tmp); });
      const std::string at = (tmp / ("t." + ext)).string() + (ext == "obj" ? ":" : ": line ") +
                             std::to_string(triangle_with_x(format, x).second);
      EXPECT_TRUE(t.says({at, "'" + x.substr(0, 20)}));
    };
    auto expect_read = [&](const std::string& x, double want) {
      SCOPED_TRACE(format + " '" + x + "'");
      const test::TempDir tmp(format);
      const Scene s = read(x, tmp);
      ASSERT_EQ(s.patches.size(), 1u);
      EXPECT_NEAR(point(s, 0, 1).x, want, ext == "obj" ? 1e-15 : 1e-7);
    };
    for (const std::string& x : refused_numbers()) expect_refused(x);
    for (const std::string& x : numbers_assimp_misreads()) {
      if (ext == "obj")
        expect_read(x, std::strtod(x.c_str(), nullptr));
      else
        expect_refused(x);
    }
    for (const std::string& x : numbers_meaning_one_and_a_half()) expect_read(x, 1.5);
  }
}

TEST(HostileNumbers, MtlValuesProbesAndIntegersFollowTheSameSyntax) {
  const test::TempDir tmp;
  const std::string obj = "mtllib m.mtl\nusemtl grey\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  for (const std::string kd : {"0x1p-1", "+0.5", "0.5,0"}) {
    SCOPED_TRACE(kd);
    write_text(tmp / "m.mtl", "newmtl grey\nKd " + kd + " 0.5 0.5\nKe 1 1 1\n");
    write_text(tmp / "t.obj", obj);
    const test::Thrown t = test::thrown<InputError>([&] { read_scene((tmp / "t.obj").string()); });
    EXPECT_TRUE(t.says({(tmp / "m.mtl").string() + ":2", "'" + kd + "'"}));
  }
  // A face index the OBJ parser reads otherwise (atoi: 4294967297 is 1).
  write_text(tmp / "m.mtl", "newmtl grey\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
  write_text(tmp / "i.obj", "mtllib m.mtl\nusemtl grey\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 +3\n");
  EXPECT_TRUE(test::thrown<InputError>([&] { read_scene((tmp / "i.obj").string()); }).says({"i.obj:6", "'+3'"}));
  // Probe files: strtod read 0x1p0 as 1.
  write_text(tmp / "p.txt", "# probes\na 0 0 0 0 1 0\nb 0x1p0 0 0 0 1 0\n");
  EXPECT_TRUE(test::thrown<InputError>([&] { read_probes((tmp / "p.txt").string()); }).says({"p.txt:3", "'0x1p0'"}));
  // PLY integers: assimp read a count of +3 as 0 and an index of 4294967296 as 0.
  const std::string verts = "0 0 0\n1 0 0\n0 1 0\n";
  for (const std::string face : {"+3 0 1 2", "3 0 1 4294967296", "3 0 1 -2", "3 0 1 2.0", "300 0 1 2"}) {
    SCOPED_TRACE(face);
    write_text(tmp / "f.ply", PLY_HEAD(3, 1) + verts + face + "\n");
    write_text(tmp / "f.json", grey_scene("f.ply"));
    const test::Thrown t = test::thrown<InputError>([&] { read_scene((tmp / "f.json").string()); });
    EXPECT_TRUE(t.says({(tmp / "f.ply").string() + ": line 13"}));
  }
  // OFF indices: assimp read -1 as 0.
  write_text(tmp / "f.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n");
  write_text(tmp / "o.json", grey_scene("f.off"));
  EXPECT_TRUE(
      test::thrown<InputError>([&] { read_scene((tmp / "o.json").string()); }).says({"f.off: line 6", "'-1'"}));
}

TEST(HostileMessages, AByteOrderMarkBeforeAnObjOrMtlIsReadAsTheFileWithoutIt) {
  // It was "unknown OBJ statement", and an MTL's first newmtl went unseen.
  const test::TempDir tmp;
  const std::string bom = "\xEF\xBB\xBF";
  write_text(tmp / "m.mtl", bom + "newmtl grey\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
  write_text(tmp / "t.obj", bom + "v 0 0 0\nv 1 0 0\nv 0 1 0\nmtllib m.mtl\nusemtl grey\nf 1 2 3\n");
  const Scene s = read_scene((tmp / "t.obj").string());
  ASSERT_EQ(s.patches.size(), 1u);
  EXPECT_EQ(s.materials[0].reflectance, Rgb(0.5));
  EXPECT_EQ(s.patches[0].line, 6);
  expect_point(point(s, 0, 1), {1, 0, 0}, 0.0);
}

TEST(HostileMessages, ANulInAJsonSceneFileNameIsShownEscapedAndRefused) {
  // The message stopped at the NUL, and the name was looked up as the part
  // before it.
  const test::TempDir tmp;
  test::write_ply(tmp / "a.ply", octahedron(), false);
  write_text(tmp / "s.json", std::string("{\"materials\": {\"m\": {\"reflectance\": [0.5, 0.5, 0.5]}}, \"objects\": "
                                         "[{\"file\": \"a.ply\\u0000.obj\", \"material\": \"m\"}]}"));
  const test::Thrown t = test::thrown<InputError>([&] { read_scene((tmp / "s.json").string()); });
  EXPECT_TRUE(t.says({(tmp / "s.json").string() + ": objects[0].file", "a.ply\\u0000.obj"}));
}

TEST(HostileMessages, OneMaterialLibraryNamedTwiceIsReadOnce) {
  // It said "material 'grey' is defined again (first at the same file:line)".
  const test::TempDir tmp;
  write_text(tmp / "m.mtl", "newmtl grey\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
  write_text(tmp / "t.obj", "mtllib m.mtl\nmtllib ./m.mtl m.mtl\nusemtl grey\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const Scene s = read_scene((tmp / "t.obj").string());
  ASSERT_EQ(s.materials.size(), 1u);
  EXPECT_EQ(s.materials[0].line, 1);
  // Every library of one mtllib line is read (tinyobjloader read the first
  // it could open, and the face was said to have no material).
  write_text(tmp / "red.mtl", "newmtl red\nKd 0.5 0.1 0.1\n");
  write_text(tmp / "u.obj", "mtllib red.mtl m.mtl\nusemtl grey\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const Scene u = read_scene((tmp / "u.obj").string());
  ASSERT_EQ(u.patches.size(), 1u);
  EXPECT_EQ(u.material_of(u.patches[0]).name, "grey");
}

TEST(HostileMessages, AnMtlMaterialNameWithASpaceNamesItsLine) {
  // It was "material 'grey paint' was read but not found by the MTL scan", with no line.
  const test::TempDir tmp;
  write_text(tmp / "m.mtl", "# paints\nnewmtl grey paint\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
  write_text(tmp / "t.obj", "mtllib m.mtl\nusemtl grey\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const test::Thrown t = test::thrown<InputError>([&] { read_scene((tmp / "t.obj").string()); });
  EXPECT_TRUE(t.says({(tmp / "m.mtl").string() + ":2", "'grey paint'"}));
}

TEST(HostileMessages, APlyWithoutVerticesSaysSo) {
  // assimp said "Vertices should be declared before faces".
  const test::TempDir tmp;
  write_text(tmp / "empty.ply", PLY_HEAD(0, 0));
  write_text(tmp / "s.json", grey_scene("empty.ply"));
  const test::Thrown t = test::thrown<InputError>([&] { read_scene((tmp / "s.json").string()); });
  EXPECT_TRUE(t.says({(tmp / "empty.ply").string() + ": ", "no vertices"}));
  EXPECT_FALSE(t.says({"declared before"}));
}
