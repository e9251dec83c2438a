// The MGF reader: every entity it reads, the colour conversions against
// Radiance's primaries and the CIE tables, holes by seams against the same
// face in OBJ, includes with transforms and arrays, the curved primitives'
// chord bound, every error's file:line and value, the warnings counted once,
// and the bundled Cornell box in MGF solving as its OBJ does.

#include "io/readers/mgf.h"
#include "io/readers/scene_sources.h"
#include "radmesh/radmesh.h"

#include <gtest/gtest.h>

#include "tests/test_util.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

using namespace radmesh;
namespace fs = std::filesystem;
using radmesh::test::kData;
using radmesh::test::mentions;
using radmesh::test::message_of;

namespace {

std::string write(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
  return p.string();
}

// A scene of `body` after a lamp (so that the scene emits) and four named
// corners of the unit square in z = 0: a b c d, counter-clockwise seen from +z.
std::string with_square(const std::string& body) {
  return "v a =\n p 0 0 0\nv b =\n p 1 0 0\nv c =\n p 1 1 0\nv d =\n p 0 1 0\n" + body;
}

Scene read_text(const test::TempDir& tmp, const std::string& text, const SceneOptions& options = {}) {
  return read_scene(write(tmp / "scene.mgf", text), options);
}

// The faces and materials of an MGF file before build_scene (whose checks
// would refuse the overlapping faces of the small tests of materials).
internal::SceneSource read_source(const test::TempDir& tmp, const std::string& text) {
  return internal::read_mgf_source(write(tmp / "scene.mgf", text), {});
}

const Material& material_of(const internal::SceneSource& s, size_t face) {
  return s.materials[static_cast<size_t>(s.faces[face].material)];
}

bool has_warning(const std::vector<std::string>& warnings, std::initializer_list<std::string> parts) {
  for (const std::string& w : warnings)
    if (mentions(w, parts)) return true;
  return false;
}
bool has_warning(const Scene& s, std::initializer_list<std::string> parts) {
  return has_warning(s.report.warnings, parts);
}

std::string shown(const std::vector<std::string>& warnings) {
  std::string out;
  for (const std::string& w : warnings) out += w + "\n";
  return out;
}
std::string warnings(const Scene& s) { return shown(s.report.warnings); }

// The outward test of a closed shape around `center`: every patch's normal
// points away from it (towards it with inward).
void expect_facing(const Scene& s, const Vec3& center, bool outward) {
  for (size_t p = 0; p < s.patches.size(); ++p) {
    Vec3 c(0.0);
    const std::vector<Vec3> pts = s.loop_points(s.patches[p].outer);
    for (const Vec3& q : pts) c += q / static_cast<double>(pts.size());
    EXPECT_EQ(glm::dot(s.patches[p].normal, c - center) > 0.0, outward) << "patch " << p;
  }
}

double total_area(const Scene& s) {
  double a = 0.0;
  for (size_t p = 0; p < s.patches.size(); ++p) a += s.patch_area(static_cast<int>(p));
  return a;
}

}  // namespace

TEST(Mgf, VerticesObjectsAndMaterialsAsTheFormatDefinesThem) {
  const test::TempDir tmp;
  const internal::SceneSource s = read_source(tmp, with_square(
      "# a comment \\\n"
      "  that goes on\n"
      "v e = a\n"           // an alias of a
      "v a =\n p 5 5 5\n"   // a again, fresh: e keeps the old position
      "v a\n p 0 0 1\n"     // a made current and moved
      "n 0 0 1\n"           // read, not needed
      "m paint =\n c\n  cxy .3333333333333333 .3333333333333333\n rd .5\n sides 1\n"
      "m lamp = paint\n ed 358\n"
      "o room\n o wall\n  m paint\n  f e b c d\n o\n m lamp\n f e \\\n b c\no\n"
      "f e b c\n"));
  ASSERT_EQ(s.faces.size(), 3u);
  EXPECT_EQ(s.faces[0].name, "room.wall");
  EXPECT_EQ(s.faces[1].name, "room");
  EXPECT_EQ(s.faces[2].name, "scene");  // no o: the file's stem
  EXPECT_EQ(s.faces[1].line, 30);       // where the continued face starts
  EXPECT_EQ(s.faces[1].points, (std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}));
  const Material& paint = material_of(s, 0);
  EXPECT_EQ(paint.name, "paint");
  EXPECT_EQ(paint.reflectance, Rgb(0.5));  // grey stays grey to the last bit
  EXPECT_EQ(paint.reflectance_line, 20);
  const Material& lamp = material_of(s, 1);
  EXPECT_EQ(lamp.name, "lamp");
  EXPECT_EQ(lamp.reflectance, Rgb(0.5));
  EXPECT_EQ(lamp.emission, Rgb(2.0));  // ed / 179
  EXPECT_EQ(lamp.emission_line, 23);
  // The third face uses the lamp too (the context stays): the same material.
  EXPECT_EQ(s.faces[2].material, s.faces[1].material);
  EXPECT_TRUE(has_warning(s.warnings, {"179 lm/W", "Radiance"})) << shown(s.warnings);
  EXPECT_FALSE(has_warning(s.warnings, {"two-sided"})) << shown(s.warnings);
}

TEST(Mgf, AMaterialChangedAfterUseIsANewMaterialAndTheDefaultIsATwoSidedBlackAbsorber) {
  const test::TempDir tmp;
  const internal::SceneSource s =
      read_source(tmp, with_square("f a b c d\nm red =\n c\n  cxy .5 .3\n rd .2\n sides 1\n"
                                   "f a b c\nrd .3\nf a c d\nm\nf b c d\nm\nc\nrd .1\nf a b d\n"
                                   "m lamp =\n sides 1\n ed 179\nf a b c\n"));
  ASSERT_EQ(s.faces.size(), 6u);
  EXPECT_EQ(material_of(s, 0).name, "(default)");
  EXPECT_EQ(material_of(s, 0).reflectance, Rgb(0.0));
  EXPECT_EQ(material_of(s, 1).name, "red");
  EXPECT_EQ(material_of(s, 2).name, "red (2)");
  EXPECT_NEAR(material_of(s, 2).reflectance.x / material_of(s, 1).reflectance.x, 1.5, 1e-12);
  EXPECT_EQ(s.faces[3].material, s.faces[0].material);  // m again: the default again
  EXPECT_EQ(material_of(s, 4).name, "(unnamed)");
  EXPECT_EQ(material_of(s, 4).reflectance, Rgb(0.1));
  EXPECT_TRUE(has_warning(s.warnings, {"without a material", "two-sided black absorber", "(2, first at",
                                       "scene.mgf:9)"}))
      << shown(s.warnings);
  EXPECT_TRUE(has_warning(s.warnings, {"two-sided", "front only", "(3, first at", "scene.mgf:9)"}))
      << shown(s.warnings);
}

TEST(Mgf, ColoursAreRadiancesPrimariesFromTheCieTables) {
  using namespace radmesh::internal::mgf;
  bool clipped = true;
  // The primaries themselves: one channel each, of the luminance over the
  // primary's share of white.
  const Rgb red = to_rgb({0.640, 0.330}, 0.2, &clipped);
  EXPECT_NEAR(red.y, 0.0, 1e-15);
  EXPECT_NEAR(red.z, 0.0, 1e-15);
  EXPECT_FALSE(clipped);
  const Rgb green = to_rgb({0.290, 0.600}, 0.2, &clipped);
  const Rgb blue = to_rgb({0.150, 0.060}, 0.2, &clipped);
  // Their luminance shares add up to 1 (white = (1, 1, 1)).
  EXPECT_NEAR(0.2 / red.x + 0.2 / green.y + 0.2 / blue.z, 1.0, 1e-12);
  EXPECT_NEAR(0.2 / red.x, 0.2651, 1e-4);  // the shares of cmix's example in the MGF specification
  EXPECT_NEAR(0.2 / green.y, 0.6701, 1e-4);
  // Outside the gamut: clipped, and said.
  const Rgb spectral = to_rgb({0.08, 0.8}, 0.5, &clipped);
  EXPECT_TRUE(clipped);
  EXPECT_GE(std::min({spectral.x, spectral.y, spectral.z}), 0.0);
  // The specification's mix of the three primaries for white.
  const Chromaticity white = mix({{0.640, 0.330}, {0.290, 0.600}, {0.150, 0.060}}, {0.265, 0.670, 0.065});
  EXPECT_NEAR(white.x, 1.0 / 3.0, 1e-3);
  EXPECT_NEAR(white.y, 1.0 / 3.0, 1e-3);
  // A flat spectrum is the equal-energy white: grey to the last bit.
  Chromaticity flat;
  ASSERT_EQ(spectrum_chromaticity(380, 780, {1.0, 1.0, 1.0}, &flat), "");
  EXPECT_EQ(to_rgb(flat, 0.7, &clipped), Rgb(0.7));
  // A narrow band at 580 nm: on the spectrum locus (CIE 1931: 0.5125, 0.4866).
  Chromaticity band;
  ASSERT_EQ(spectrum_chromaticity(579, 581, {1.0, 1.0}, &band), "");
  EXPECT_NEAR(band.x, 0.5125, 2e-3);
  EXPECT_NEAR(band.y, 0.4866, 2e-3);
  EXPECT_NE(spectrum_chromaticity(200, 300, {1.0, 1.0}, &band), "");  // no visible light
  // Black bodies on the Planckian locus (CIE 1931: 1000 K 0.6528 0.3444, 6500 K 0.3135 0.3236).
  Chromaticity bb;
  ASSERT_EQ(black_body_chromaticity(1000, &bb), "");
  EXPECT_NEAR(bb.x, 0.6528, 2e-3);
  EXPECT_NEAR(bb.y, 0.3444, 2e-3);
  ASSERT_EQ(black_body_chromaticity(6500, &bb), "");
  EXPECT_NEAR(bb.x, 0.3135, 2e-3);
  EXPECT_NEAR(bb.y, 0.3236, 2e-3);
  ASSERT_EQ(black_body_chromaticity(1.0, &bb), "");  // no overflow at the extremes
  ASSERT_EQ(black_body_chromaticity(1e12, &bb), "");
}

TEST(Mgf, ColourEntitiesReachTheMaterials) {
  const test::TempDir tmp;
  const internal::SceneSource s = read_source(tmp, with_square(
      "c R =\n cxy .640 .330\nc G =\n cxy .290 .600\nc B =\n cxy .150 .060\n"
      "c white =\n cmix .26506 R .67011 G .06483 B\n"
      "c warm = white\n cct 3000\n"
      "m a =\n c R\n rd .1\n sides 1\nf a b c d\n"
      "m b =\n c white\n rd .5\n sides 1\nf a b c d\n"
      "m c =\n c warm\n rd .5\n sides 1\nf a b c\n"
      "m d =\n c\n cspec 400 700 1 1 1 1\n rd .4\n sides 1\nf a c d\n"));
  ASSERT_EQ(s.materials.size(), 4u);
  EXPECT_NEAR(s.materials[0].reflectance.x, 0.1 / 0.26506, 1e-4);
  EXPECT_NEAR(s.materials[1].reflectance.x, 0.5, 1e-3);  // weights of 5 digits
  EXPECT_NEAR(s.materials[1].reflectance.z, 0.5, 1e-3);
  EXPECT_GT(s.materials[2].reflectance.x, s.materials[2].reflectance.z * 2.0);  // 3000 K is warm
  // 400-700 nm flat: a little off the equal-energy white, still near grey.
  EXPECT_NEAR(s.materials[3].reflectance.y, 0.4, 0.02);
}

TEST(Mgf, AFaceWithAHoleBySeamsOrFhIsTheObjFaceItsWindowIsCutOutOf) {
  const test::TempDir tmp;
  const std::string corners = with_square(
      "v e =\n p .25 .25 0\nv f =\n p .75 .25 0\nv g =\n p .75 .75 0\nv h =\n p .25 .75 0\n"
      "m wall =\n c\n rd .5\n sides 1\nm glass =\n c\n rd .2\n ed 179\n sides 1\n");
  // The hole runs the other way round, entered from d along d -> h.
  const Scene seam = read_scene(write(tmp / "seam.mgf", corners + "o wall\nm wall\nf a b c d h g f e h d\no\n"
                                                                  "o window\nm glass\nf e f g h\no\n"));
  const Scene fh = read_scene(write(tmp / "fh.mgf", corners + "o wall\nm wall\nfh a b c d - e h g f\no\n"
                                                              "o window\nm glass\nf e f g h\no\n"));
  // The OBJ has the wall without a hole; the window lying in it is cut out of it.
  write(tmp / "wall.mtl", "newmtl wall\nKd 0.5 0.5 0.5\nnewmtl glass\nKd 0.2 0.2 0.2\nKe 1 1 1\n");
  const Scene obj = read_scene(write(tmp / "wall.obj",
                                     "mtllib wall.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                     "v .25 .25 0\nv .75 .25 0\nv .75 .75 0\nv .25 .75 0\n"
                                     "o wall\nusemtl wall\nf 1 2 3 4\no window\nusemtl glass\nf 5 6 7 8\n"));
  for (const Scene* s : {&seam, &fh}) {
    ASSERT_EQ(s->patches.size(), obj.patches.size());
    for (size_t p = 0; p < obj.patches.size(); ++p) {
      EXPECT_EQ(s->patches[p].name, obj.patches[p].name);
      EXPECT_EQ(s->patches[p].holes.size(), obj.patches[p].holes.size());
      EXPECT_NEAR(s->patch_area(static_cast<int>(p)), obj.patch_area(static_cast<int>(p)), 1e-15);
      EXPECT_EQ(s->patches[p].normal, obj.patches[p].normal);
      EXPECT_EQ(s->material_of(static_cast<int>(p)).reflectance, obj.material_of(static_cast<int>(p)).reflectance);
      EXPECT_EQ(s->material_of(static_cast<int>(p)).emission, obj.material_of(static_cast<int>(p)).emission);
    }
  }
  EXPECT_EQ(seam.patches[0].holes.size(), 1u);
  EXPECT_DOUBLE_EQ(seam.patch_area(0), 0.75);
}

TEST(Mgf, IncludesTransformsAndArraysPlaceTheirInstances) {
  const test::TempDir tmp;
  // A unit square tile in parts/tile.mgf; its vertices come from a file it
  // includes from its own folder.
  write(tmp / "parts" / "corners.inc", "v t0 =\n p 0 0 0\nv t1 =\n p 1 0 0\nv t2 =\n p 1 1 0\nv t3 =\n p 0 1 0\n");
  write(tmp / "parts" / "tile.mgf", "i corners.inc\no tile\nf t0 t1 t2 t3\no\n");
  const Scene s = read_scene(write(tmp / "floor.mgf",
                                   "m lamp =\n ed 179\n sides 1\n"
                                   "i parts/tile.mgf -t 0 0 0 -a 3 -t 2 0 0\n"
                                   "xf -t 0 5 0 -a 2 -t 0 2 0 -a 2 -t 10 0 0\n"
                                   "i parts/tile.mgf -s 0.5\n"
                                   "xf\n"
                                   "xf -rz 90 -t 100 0 0\ni parts/tile.mgf\nxf\n"
                                   "xf -mx\ni parts/tile.mgf\nxf\n"));
  ASSERT_EQ(s.patches.size(), 3u + 4u + 1u + 1u);
  auto min_corner = [&](size_t p) {
    Vec3 lo(INFINITY);
    for (const Vec3& q : s.loop_points(s.patches[p].outer)) lo = glm::min(lo, q);
    return lo;
  };
  // Instance k of -a applies the steps after it k times (0 first).
  for (int k = 0; k < 3; ++k) EXPECT_EQ(min_corner(static_cast<size_t>(k)), Vec3(2.0 * k, 0, 0));
  // Two arrays: the last one varies fastest; the xf's own steps after the
  // include's -s (a context's arguments come before its enclosing one's).
  EXPECT_EQ(min_corner(3), Vec3(0, 5, 0));
  EXPECT_EQ(min_corner(4), Vec3(10, 5, 0));
  EXPECT_EQ(min_corner(5), Vec3(0, 7, 0));
  EXPECT_EQ(min_corner(6), Vec3(10, 7, 0));
  EXPECT_DOUBLE_EQ(s.patch_area(3), 0.25);
  // -rz 90 turns x into y exactly, then the translation.
  EXPECT_EQ(min_corner(7), Vec3(99, 0, 0));
  // Every face faces +z, the mirrored one too (its order reversed).
  for (const Patch& p : s.patches) EXPECT_EQ(p.normal, Vec3(0, 0, 1));
  EXPECT_EQ(min_corner(8), Vec3(-1, 0, 0));
  EXPECT_TRUE(mentions(s.patches[8].file, {"parts/tile.mgf"}));
}

TEST(Mgf, ASphereConvergesTo4PiR2WithinTheChordBound) {
  const test::TempDir tmp;
  const double r = 2.0;
  const Vec3 c(1, 2, 3);
  double last = 0.0;
  for (const double t : {0.1, 0.01, 0.001}) {
    SceneOptions o;
    o.curve_tolerance = t;
    const Scene s = read_text(tmp, "v c =\n p 1 2 3\nm lamp =\n ed 179\n sides 1\nsph c 2\n", o);
    const double area = total_area(s), exact = 4.0 * std::numbers::pi * r * r;
    EXPECT_LT(area, exact);
    EXPECT_GT(area, (1.0 - t) * (1.0 - t) * exact) << t;
    EXPECT_GT(area, last);  // closer as the tolerance shrinks
    last = area;
    // Every face within t r of the sphere: its plane no nearer the centre than (1 - t) r.
    for (const Patch& p : s.patches) {
      const double d = glm::dot(s.vertices[static_cast<size_t>(p.outer[0])] - c, p.normal);
      EXPECT_GE(d, (1.0 - t) * r * (1.0 - 1e-12));
    }
    expect_facing(s, c, true);
    EXPECT_TRUE(has_warning(s, {"1 cut into", std::to_string(s.patches.size()) + " planar faces"})) << warnings(s);
  }
  // A negative radius faces inward.
  const Scene in = read_text(tmp, "v c =\n p 1 2 3\nm lamp =\n ed 179\n sides 1\nsph c -2\n");
  expect_facing(in, c, false);
}

TEST(Mgf, CylindersConesRingsToriAndPrismsFaceOutwardWithTheirAreas) {
  const test::TempDir tmp;
  const double t = 0.001, pi = std::numbers::pi;
  SceneOptions o;
  o.curve_tolerance = t;
  const std::string lamp = "m lamp =\n ed 179\n sides 1\n";
  const std::string ends = "v a =\n p 0 0 0\n n 0 0 1\nv b =\n p 0 0 2\n";
  struct Case {
    std::string body;
    double area;
    bool outward;
    Vec3 center;
  };
  const std::vector<Case> cases = {
      {"cyl a 1 b\n", 2 * pi * 1 * 2, true, {0, 0, 1}},
      {"cyl a -1 b\n", 2 * pi * 1 * 2, false, {0, 0, 1}},
      {"cone a 1 b 0\n", pi * 1 * std::sqrt(1 + 4.0), true, {0, 0, 0.5}},
      {"cone a 0 b 1\n", pi * 1 * std::sqrt(1 + 4.0), true, {0, 0, 1.5}},
      {"cone a 2 b 1\n", pi * (2 + 1) * std::sqrt(1 + 4.0), true, {0, 0, 1}},
      {"ring a .5 1\n", pi * (1 - 0.25), true, {0, 0, -1}},
      {"ring a 0 1\n", pi, true, {0, 0, -1}},
      {"torus a 1 3\n", 4 * pi * pi * 2 * 1, true, {0, 0, 0}},
      {"torus a -1 -3\n", 4 * pi * pi * 2 * 1, false, {0, 0, 0}},
      {"prism a b c 1.5\n", 0.0, true, {0, 0, 0}}};
  for (const Case& k : cases) {
    SCOPED_TRACE(k.body);
    const std::string prism = "v c =\n p 1 0 0\n";
    const Scene s = read_text(tmp, ends + prism + lamp + k.body, o);
    const bool torus = k.body.rfind("torus", 0) == 0;
    if (k.area > 0.0) {
      EXPECT_NEAR(total_area(s), k.area, 2 * t * k.area);
    }
    if (k.area > 0.0 && !torus) {
      EXPECT_LE(total_area(s), k.area);  // inscribed
    }
    if (torus) {
      // Outward from the tube's core circle, not from one point.
      for (size_t p = 0; p < s.patches.size(); ++p) {
        Vec3 m(0.0);
        const std::vector<Vec3> pts = s.loop_points(s.patches[p].outer);
        for (const Vec3& q : pts) m += q / static_cast<double>(pts.size());
        const Vec3 core = 2.0 * glm::normalize(Vec3(m.x, m.y, 0.0));
        EXPECT_EQ(glm::dot(s.patches[p].normal, m - core) > 0.0, k.outward) << p;
      }
    } else if (k.body.rfind("prism", 0) == 0) {
      ASSERT_EQ(s.patches.size(), 5u);  // the triangle, its copy and three sides
      Vec3 mid(0.0);
      for (const Vec3& q : s.vertices) mid += q / static_cast<double>(s.vertices.size());
      expect_facing(s, mid, true);
      EXPECT_NEAR(total_area(s), 2 * 1.0 + 1.5 * (2.0 + 1.0 + std::sqrt(5.0)), 1e-12);
    } else {
      expect_facing(s, k.center, k.outward);
    }
  }
}

TEST(Mgf, WarningsAreCountedOnceWithTheFirstPlace) {
  const test::TempDir tmp;
  const Scene s = read_text(tmp, with_square("m lamp =\n ed 179\n rs .1 .2\n rs .1 .2\n td .1\n ir 1.5 0\n"
                                             "ies lamp.ies\nfrob 1 2\nsd 1\nrs 0 0\nf a b c d\n"));
  EXPECT_TRUE(has_warning(s, {"rs (specular reflectance)", "diffuse", "(3, first at", "scene.mgf:11)"})) << warnings(s);
  EXPECT_TRUE(has_warning(s, {"td (diffuse transmittance)", "(1, first at", "scene.mgf:13)"})) << warnings(s);
  EXPECT_TRUE(has_warning(s, {"ir (index of refraction)", "(1, first at"})) << warnings(s);
  EXPECT_TRUE(has_warning(s, {"ies", "not loaded", "scene.mgf:15"})) << warnings(s);
  EXPECT_TRUE(has_warning(s, {"unknown MGF entities", "(2, first at", "scene.mgf:16 'frob'"})) << warnings(s);
}

// ---------------------------------------------------------------- errors

struct MgfError {
  std::string name, text;
  std::vector<std::string> says;
};

class MgfErrors : public ::testing::TestWithParam<MgfError> {};

TEST_P(MgfErrors, MessageNamesTheFileTheLineAndTheValue) {
  const test::TempDir tmp;
  const MgfError& e = GetParam();
  write(tmp / "self.mgf", "i self.mgf\n");
  write(tmp / "a.mgf", "i b.mgf\n");
  write(tmp / "b.mgf", "v x =\n p 0 0 0\ni a.mgf\n");
  const std::string path = write(tmp / "scene.mgf", with_square(e.text));
  const test::Thrown t = test::thrown<InputError>([&] { read_scene(path); });
  for (const std::string& part : e.says) EXPECT_TRUE(t.says({part})) << t.message;
}

INSTANTIATE_TEST_SUITE_P(
    Mgf, MgfErrors,
    ::testing::Values(
        MgfError{"UnknownVertex", "f a b v9\n", {"scene.mgf:9: f: unknown vertex 'v9'"}},
        MgfError{"TwoVertices", "f a b\n", {":9: f: a face needs at least 3 vertices", "f a b"}},
        MgfError{"NotANumber", "v e =\n p 1 nan 0\n", {":10: p: 'nan' is not finite"}},
        MgfError{"Hexadecimal", "v e =\n p 0x1p0 0 0\n", {":10: p: '0x1p0' is hexadecimal"}},
        MgfError{"TooFewCoordinates", "v e =\n p 1 2\n", {":10: p: expected 'p X Y Z', got 'p 1 2'"}},
        MgfError{"ScaleZero", "xf -s 0\n", {":9: xf: -s 0 would flatten"}},
        MgfError{"UnknownTransform", "xf -q 1\n", {":9: xf: unknown transform argument '-q'"}},
        MgfError{"TransformShort", "xf -t 1 2\n", {":9: xf: '-t' needs 3 value(s)"}},
        MgfError{"ArrayOfNone", "xf -a 0\n", {"-a 0"}},
        MgfError{"Overflow", "xf -i 3 -s 1e300\nf a b c\nxf\n", {"scene.mgf:9: the transform overflows"}},
        MgfError{"EndWithoutBegin", "xf\n", {":9: xf: no transform begun"}},
        MgfError{"ObjectEndWithoutBegin", "o\n", {":9: o: no object begun"}},
        MgfError{"Chromaticity", "c\ncxy .8 .5\n", {":10: cxy: 0.8 0.5 is not a chromaticity"}},
        MgfError{"ReflectanceAboveOne", "m x =\nrd 1.5\n", {":10: rd: 1.5 is outside [0, 1]"}},
        MgfError{"SaturatedReflectance", "m x =\n c\n cxy .64 .33\n rd .9\nf a b c\n",
                 {":12: rd 0.9 with the colour x 0.64 y 0.33", "a channel of 1 or more"}},
        MgfError{"GreyOfOne", "m x =\n rd 1\nf a b c\n", {":10: rd 1 ", "a channel of 1 or more"}},
        MgfError{"Sides", "m x =\nsides 3\n", {":10: sides: '3'"}},
        MgfError{"NegativeEmission", "m x =\ned -1\n", {":10: ed: -1 is negative"}},
        MgfError{"UnknownMaterial", "m glass\n", {":9: m: unknown material 'glass'"}},
        MgfError{"UnknownTemplate", "c warm = hot\n", {":9: c: unknown colour 'hot' as a template"}},
        MgfError{"UnknownMixColour", "c x =\n cmix 1 red\n", {":10: cmix: unknown colour 'red'"}},
        MgfError{"NoLight", "c x =\n cspec 100 200 1 1\n", {":10: cspec: the spectrum has no luminance"}},
        MgfError{"ZeroRadius", "sph a 0\n", {":9: sph: a radius of 0"}},
        MgfError{"ConeSigns", "cone a 1 b -1\n", {":9: cone: the radii 1 and -1 differ in sign"}},
        MgfError{"CylinderOfOnePoint", "cyl a 1 a\n", {":9: cyl: its two ends are at one point"}},
        MgfError{"RingWithoutNormal", "ring a 0 1\n", {":9: ring: vertex 'a' has no normal"}},
        MgfError{"TorusRadii", "n 0 0 1\nv a\n n 0 0 1\ntorus a 2 1\n", {":12: torus: needs radii of one sign"}},
        MgfError{"PrismFlat", "prism a b c 0\n", {":9: prism: a length of 0"}},
        MgfError{"FhShortHole", "fh a b c - d a\n", {":9: fh: hole 1 has 2 vertices"}},
        MgfError{"ControlCharacter", "f a b\x01 c\n", {":9: control character 0x01"}},
        MgfError{"MissingInclude", "i nowhere.mgf\n", {":9: i: 'nowhere.mgf' not found (looked for"}},
        MgfError{"IncludesItself", "i self.mgf\n", {"self.mgf:1: i: 'self.mgf' includes itself"}},
        MgfError{"IncludeCycle", "i a.mgf\n", {"b.mgf:3: i: 'a.mgf' includes itself", "a.mgf -> b.mgf -> a.mgf"}}),
    [](const ::testing::TestParamInfo<MgfError>& info) { return info.param.name; });

TEST(Mgf, WorkPastTheBoundsIsRefusedNamingTheBound) {
  const test::TempDir tmp;
  internal::MgfLimits limits;
  limits.faces = 1000;
  limits.statements = 10000;
  limits.include_depth = 3;
  const std::string faces = write(tmp / "faces.mgf", with_square("xf -a 600 -a 600\nf a b c\nxf\n"));
  EXPECT_TRUE(mentions(message_of<InputError>([&] { internal::read_mgf_source(faces, {}, limits); }),
                       {"faces.mgf:10: f: more than 1000 faces"}));
  const std::string empty = write(tmp / "empty.mgf", "xf -a 1000000000\nxf\n");
  EXPECT_TRUE(mentions(message_of<InputError>([&] { internal::read_mgf_source(empty, {}, limits); }),
                       {"empty.mgf:2: more than 10000 statements executed"}));
  const std::string open = write(tmp / "open.mgf", "xf -a 1000000000\n");  // ended by the file's end
  EXPECT_TRUE(mentions(message_of<InputError>([&] { internal::read_mgf_source(open, {}, limits); }),
                       {"more than 10000 statements"}));
  for (int k = 0; k < 5; ++k) write(tmp / ("d" + std::to_string(k) + ".mgf"), "i d" + std::to_string(k + 1) + ".mgf\n");
  write(tmp / "d5.mgf", "\n");
  EXPECT_TRUE(mentions(message_of<InputError>([&] { internal::read_mgf_source((tmp / "d0.mgf").string(), {}, limits); }),
                       {"d3.mgf:1: i: 'd4.mgf': includes nested more than 3 deep"}));
  // A face of too many vertices (splitting at seams grows as their square),
  // too many vertices in all, objects nested too deep.
  limits.face_vertices = 5;
  const std::string wide = write(tmp / "wide.mgf", with_square("f a b c d a b\n"));
  EXPECT_TRUE(mentions(message_of<InputError>([&] { internal::read_mgf_source(wide, {}, limits); }),
                       {"wide.mgf:9: f: a face of 6 vertices; radmesh reads faces of at most 5"}));
  limits.face_vertices = 10000;
  limits.points = 30;
  const std::string many = write(tmp / "many.mgf", with_square("xf -a 10\nf a b c d\nxf\n"));
  EXPECT_TRUE(mentions(message_of<InputError>([&] { internal::read_mgf_source(many, {}, limits); }),
                       {"many.mgf:10: f: more than 30 face vertices"}));
  limits.object_depth = 2;
  const std::string deep = write(tmp / "deep.mgf", "o a\no b\no c\n");
  EXPECT_TRUE(mentions(message_of<InputError>([&] { internal::read_mgf_source(deep, {}, limits); }),
                       {"deep.mgf:3: o: objects nested more than 2 deep"}));
  // A sphere at the finest tolerance is within the default bound.
  SceneOptions fine;
  fine.curve_tolerance = 1e-5;
  EXPECT_GT(internal::read_mgf_source(write(tmp / "sph.mgf", "v c =\n p 0 0 0\nsph c 1\n"), fine).faces.size(), 100000u);
  fine.curve_tolerance = 1e-6;
  EXPECT_TRUE(test::thrown<InputError>([&] { internal::read_mgf_source((tmp / "sph.mgf").string(), fine); })
                  .names("curve_tolerance"));
}

TEST(Mgf, AJsonSceneNamesAnMgfFile) {
  const test::TempDir tmp;
  write(tmp / "box.mgf", with_square("m grey =\n rd .5\n sides 1\nprism a b c d -1\n"));
  const Scene s = read_scene(write(tmp / "scene.json",
                                   "{\"materials\": {\"lamp\": {\"reflectance\": [0, 0, 0], \"emission\": [1, 1, 1]}},\n"
                                   " \"objects\": [{\"file\": \"box.mgf\", \"transform\": {\"translate\": [5, 0, 0]}},\n"
                                   "             {\"file\": \"box.mgf\", \"material\": \"lamp\"}]}\n"));
  ASSERT_EQ(s.patches.size(), 12u);
  EXPECT_EQ(s.material_of(0).name, "grey");
  EXPECT_EQ(s.material_of(0).reflectance, Rgb(0.5));
  EXPECT_EQ(s.material_of(6).name, "lamp");
  // An object given a material of its own keeps what its file says of its
  // faces (curves cut, entities ignored), not of its materials.
  write(tmp / "ball.mgf", "m white =\n rd .5\nv c =\n p 0 0 0\nsph c 1\nbogus 1 2\n");
  const Scene lit = read_scene(write(tmp / "lit.json",
                                     "{\"materials\": {\"grey\": {\"reflectance\": [0.5, 0.5, 0.5]}},\n"
                                     " \"objects\": [{\"file\": \"ball.mgf\", \"material\": \"grey\"}]}\n"));
  const std::vector<std::string>& w = lit.report.warnings;
  auto has = [&](const std::string& text) {
    return std::any_of(w.begin(), w.end(), [&](const std::string& x) { return x.find(text) != std::string::npos; });
  };
  EXPECT_TRUE(has("MGF curved primitives: 1 cut into"));
  EXPECT_TRUE(has("unknown MGF entities, ignored as the format asks (1, first at"));
  EXPECT_FALSE(has("two-sided"));
}

TEST(Mgf, TheCornellBoxInMgfSolvesAsItsObjDoes) {
  const Scene obj = read_scene(kData + "/cornell_box/cornell_box.obj");
  const Scene mgf = read_scene(kData + "/cornell_box/cornell_box.mgf");
  ASSERT_EQ(mgf.patches.size(), obj.patches.size());
  ASSERT_EQ(mgf.vertices, obj.vertices);
  for (size_t p = 0; p < obj.patches.size(); ++p) {
    const int q = static_cast<int>(p);
    EXPECT_EQ(mgf.patches[p].name, obj.patches[p].name);
    EXPECT_EQ(mgf.patches[p].outer, obj.patches[p].outer);
    EXPECT_EQ(mgf.patch_area(q), obj.patch_area(q));
    EXPECT_EQ(mgf.material_of(q).name, obj.material_of(q).name);
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(mgf.material_of(q).reflectance[c], obj.material_of(q).reflectance[c], 1e-12) << p;
      EXPECT_NEAR(mgf.material_of(q).emission[c], obj.material_of(q).emission[c], 1e-12) << p;
    }
  }
  EXPECT_TRUE(has_warning(mgf, {"179 lm/W"})) << warnings(mgf);
  // The matrix method on a coarse mesh (the scene's size / 5, contact lines
  // only): the same mesh for both, so equal figures.
  SolveOptions common;
  common.field = FieldMode::mean;
  const Method& matrix = find_method("matrix");
  auto solved = [&](const Scene& scene) {
    MeshingOptions mo = matrix.meshing(scene);
    mo.max_edge = scene.diagonal() / 5.0;
    mo.discontinuity = DiscontinuityMode::contacts;
    const Mesh mesh = mesh_scene(scene, mo);
    const MethodResult r = run_method(matrix, scene, mesh, common, OptionValues{});
    return std::make_pair(mesh.triangles.size(), element_patch_means(scene, r.mesh, r.solution));
  };
  const auto [na, ma] = solved(obj);
  const auto [nb, mb] = solved(mgf);
  ASSERT_EQ(na, nb);
  for (size_t p = 0; p < ma.size(); ++p)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(mb[p][c], ma[p][c], 1e-6 * std::abs(ma[p][c])) << p;
}
