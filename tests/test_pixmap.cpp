// Pixmap radiosity: the hemicube's form factors against closed forms, the
// texel layout's exact areas, progressive refinement against the linear
// system it solves, determinism, and saving and resuming.

#include "radmesh/obj_reader.h"
#include "io/writers/pixmap_io.h"
#include "radmesh/errors.h"
#include "radmesh/form_factor.h"
#include "radiosity/pixmap/hemicube.h"
#include "radmesh/pixmap.h"

#include <gtest/gtest.h>

#include "test_util.h"

#include <array>
#include <cmath>
#include <filesystem>
#include <filesystem>
#include <fstream>
#include <numeric>

using namespace radmesh;
namespace fs = std::filesystem;

namespace {

using radmesh::test::kData;

// Two triangles of the quad a b c d (counter-clockwise around `normal`).
void add_quad(std::vector<HemicubeTriangle>& out, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
              const Vec3& normal, int id) {
  out.push_back({a, b, c, normal, id});
  out.push_back({a, c, d, normal, id});
}

// The area-to-area form factor from the unit square [0,1]^2 of z = 0
// (normal +z) to `target` (id 1): hemicubes at 4 x 4 Gauss-Legendre points
// of the source, weighted.
double square_form_factor(const std::vector<HemicubeTriangle>& target, int resolution) {
  const double node[4] = {0.5 - 0.5 * 0.8611363115940526, 0.5 - 0.5 * 0.3399810435848563,
                          0.5 + 0.5 * 0.3399810435848563, 0.5 + 0.5 * 0.8611363115940526};
  const double weight[4] = {0.5 * 0.3478548451374538, 0.5 * 0.6521451548625461, 0.5 * 0.6521451548625461,
                            0.5 * 0.3478548451374538};
  Hemicube cube(resolution);
  double f = 0.0;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      cube.render(Vec3(node[i], node[j], 0.0), Vec3(1, 0, 0), Vec3(0, 1, 0), target);
      f += weight[i] * weight[j] * cube.form_factor(1);
    }
  return f;
}

TEST(Hemicube, ParallelUnitSquaresMatchHowellC11) {
  // Unit squares one apart, facing each other: F = 0.199825 (Howell C-11).
  std::vector<HemicubeTriangle> target;
  add_quad(target, {0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1}, {0, 0, -1}, 1);
  const double exact = 0.1998248;
  const double coarse = square_form_factor(target, 256), fine = square_form_factor(target, 2048);
  std::printf("C-11: resolution 256 %.6f (%.3g), 2048 %.6f (%.3g)\n", coarse, coarse / exact - 1, fine,
              fine / exact - 1);
  EXPECT_NEAR(coarse / exact, 1.0, 5e-3);
  EXPECT_NEAR(fine / exact, 1.0, 5e-4);
}

TEST(Hemicube, PerpendicularUnitSquaresMatchHowellC14) {
  // Unit squares at a right angle sharing an edge: F = 0.200044 (Howell C-14).
  std::vector<HemicubeTriangle> target;
  add_quad(target, {0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 0}, {1, 0, 0}, 1);
  const double f = square_form_factor(target, 256);
  std::printf("C-14: resolution 256 %.6f (%.3g)\n", f, f / 0.200044 - 1);
  EXPECT_NEAR(f / 0.200044, 1.0, 1e-2);
}

TEST(Hemicube, EveryPixelSeesAClosedCubeAndTheFactorsSumToOne) {
  // From a point on the floor of a closed cube, every pixel sees one of the
  // other five faces' fronts: no gap between triangles, no pixel empty, and
  // the delta form factors sum to 1.
  std::vector<HemicubeTriangle> cube_faces;
  add_quad(cube_faces, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}, {0, 0, -1}, 0);  // ceiling: its front is below
  add_quad(cube_faces, {0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}, {1, 0, 0}, 1);
  add_quad(cube_faces, {1, 0, 0}, {1, 0, 1}, {1, 1, 1}, {1, 1, 0}, {-1, 0, 0}, 2);
  add_quad(cube_faces, {0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}, {0, 1, 0}, 3);
  add_quad(cube_faces, {0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1}, {0, -1, 0}, 4);
  add_quad(cube_faces, {0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, 5);  // the floor, in the hemicube's plane
  for (int resolution : {2, 64, 300}) {
    Hemicube cube(resolution);
    cube.render(Vec3(0.3, 0.55, 0.0), Vec3(1, 0, 0), Vec3(0, 1, 0), cube_faces);
    double sum = 0.0;
    for (int id = 0; id < 6; ++id) sum += cube.form_factor(id);
    EXPECT_NEAR(sum, 1.0, 1e-12) << resolution;
    EXPECT_EQ(cube.form_factor(5), 0.0);  // coplanar with the centre
    for (const auto& face : cube.faces())
      for (int id : face.id) ASSERT_GE(id, 0) << resolution;
  }
  EXPECT_THROW(Hemicube(255), InputError);
}

TEST(Hemicube, BackFacesHideButDoNotReceive) {
  std::vector<HemicubeTriangle> tris;
  add_quad(tris, {-1, -1, 1}, {-1, 1, 1}, {1, 1, 1}, {1, -1, 1}, {0, 0, 1}, 7);  // faces away from the centre
  add_quad(tris, {-1, -1, 2}, {-1, 1, 2}, {1, 1, 2}, {1, -1, 2}, {0, 0, -1}, 8);  // behind it
  Hemicube cube(64);
  cube.render(Vec3(0.0), Vec3(1, 0, 0), Vec3(0, 1, 0), tris);
  EXPECT_EQ(cube.form_factor(7), 0.0);
  EXPECT_EQ(cube.form_factor(8), 0.0);
  EXPECT_GT(cube.form_factor(Hemicube::kBack), 0.5);
}

TEST(Hemicube, TheLitSideOfATwoSidedPanelIsSeenWhicheverComesFirst) {
  // A panel one above the source, its two sides one quad written twice
  // (the back first, then the front, and the other way): the front gets
  // Howell's C-11 factor both times, the back nothing. The back drawn
  // first used to win the tie of equal depths and hide the front.
  for (bool back_first : {true, false}) {
    std::vector<HemicubeTriangle> target, back;
    add_quad(target, {0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1}, {0, 0, -1}, 1);
    add_quad(back, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}, {0, 0, 1}, 2);
    if (back_first)
      target.insert(target.begin(), back.begin(), back.end());
    else
      target.insert(target.end(), back.begin(), back.end());
    const double f = square_form_factor(target, 256);
    EXPECT_NEAR(f / 0.1998248, 1.0, 5e-3) << back_first;
  }
}

TEST(Hemicube, NothingShowsThroughAWall) {
  // From the middle of a 2 x 2 wall lamp, a wall 2 away stands across the
  // room, a floor under both. The floor's edge along the back (z = 0) runs
  // on the screen's diagonal, as do the pixel centres that look at that
  // edge 3.66 away past the wall; its corner under the lamp is clipped at
  // the near plane. The floor's depth was interpolated over the clipped
  // polygon's fan, whose sliver gave such a centre most of the clipped
  // corner's depth: the floor won over the wall at 5 pixels, and a sealed
  // room behind the wall got light. Every pixel whose ray crosses the wall
  // must see the wall.
  const double a = 1.9995;
  std::vector<HemicubeTriangle> tris;
  tris.push_back({{4, 0, 0}, {0, 0, 0}, {0, 0, 2}, {0, 1, 0}, 0});
  tris.push_back({{4, 0, 0}, {0, 0, 2}, {4, 0, 2}, {0, 1, 0}, 0});
  add_quad(tris, {a, 0, 0}, {a, 0, 2}, {a, 2, 2}, {a, 2, 0}, {-1, 0, 0}, 1);
  const Vec3 centre(0, 1, 1);
  for (int resolution : {64, 128, 256}) {
    Hemicube cube(resolution);
    cube.render(centre, Vec3(0, 1, 0), Vec3(0, 0, 1), tris);
    int crossing = 0, through = 0;
    for (int f = 0; f < 5; ++f) {
      const Hemicube::Face& F = cube.faces()[f];
      for (int y = 0; y < F.height; ++y)
        for (int x = 0; x < F.width; ++x) {
          const Vec3 d = F.forward + cube.pixel_x(x) * F.right + cube.pixel_y(f, y) * F.up;
          if (!(d.x > 0.0)) continue;
          const Vec3 p = centre + ((a - centre.x) / d.x) * d;
          if (p.y < 1e-3 || p.y > 2.0 - 1e-3 || p.z < 1e-3 || p.z > 2.0 - 1e-3) continue;
          ++crossing;
          if (F.id[static_cast<size_t>(y) * F.width + x] != 1) ++through;
        }
    }
    EXPECT_GT(crossing, resolution * resolution / 5) << resolution;  // the wall fills a quarter of the front face
    EXPECT_EQ(through, 0) << resolution;
  }
}

// ---- layout ------------------------------------------------------------------

TEST(PixmapLayout, TexelAreasAddUpToThePatchesAndCoplanarNeighboursShareAGrid) {
  const Scene scene = read_obj_scene(kData + "/cornell_box/cornell_box.obj");
  PixmapOptions o;
  o.texel_size = 37.0;
  const PixmapLayout L = make_pixmap_layout(scene, o, 1e9);
  // The four ceiling pieces around the light are one grid.
  int ceiling = -1;
  for (size_t p = 0; p < scene.patches.size(); ++p)
    if (scene.patches[p].name == "ceiling") {
      if (ceiling < 0) ceiling = L.pixmap_of_patch[p];
      EXPECT_EQ(L.pixmap_of_patch[p], ceiling);
    }
  // Every patch's area is in a texel, but the floor under the two blocks
  // (inside closed objects), cut exactly along the blocks' outlines.
  double total = 0.0, covered = 0.0, footprints = 0.0;
  for (size_t p = 0; p < scene.patches.size(); ++p) total += scene.patch_area(static_cast<int>(p));
  for (const char* block : {"short_block", "tall_block"}) footprints += scene.patch_area(test::patch_named(scene, block));
  for (size_t k = 0; k < L.pixmaps.size(); ++k) {
    const Pixmap& pm = L.pixmaps[k];
    const double coverage = std::accumulate(pm.coverage.begin(), pm.coverage.end(), 0.0);
    const double owned = std::accumulate(pm.area.begin(), pm.area.end(), 0.0);
    covered += coverage;
    EXPECT_NEAR(owned / coverage, 1.0, 1e-12) << k;
    EXPECT_LE(std::abs(pm.texel_u - 37.0), 37.0 / pm.width + 1e-9);  // stretched to fit its extent
    for (long long i = 0; i < pm.texels(); ++i) {
      EXPECT_LE(pm.coverage[i], pm.texel_u * pm.texel_v * (1 + 1e-12));
      if (pm.owner[i] >= 0) {
        EXPECT_EQ(pm.owner[pm.owner[i]], pm.owner[i]);  // an owner owns itself
      }
    }
  }
  EXPECT_NEAR((covered + L.enclosed_area) / total, 1.0, 1e-12);
  std::printf("enclosed %.1f, the blocks' footprints %.1f\n", L.enclosed_area, footprints);
  EXPECT_NEAR(L.enclosed_area / footprints, 1.0, 1e-9);
  o.max_texels = 100;
  for (const Pixmap& pm : make_pixmap_layout(scene, o, 1e9).pixmaps) EXPECT_LE(pm.texels(), 100);
  EXPECT_THROW(make_pixmap_layout(scene, o, 1e3), NumericalError);
}

// ---- progressive refinement -------------------------------------------------

// The area mean of the first channel of per-texel values (a state's or a
// display's), over the texels holding a value.
// Over the pixmaps of material `material` (-1: all).
double area_mean(const PixmapLayout& L, const std::vector<std::vector<float>>& values, int material = -1) {
  double sum = 0.0, area = 0.0;
  for (size_t k = 0; k < L.pixmaps.size(); ++k)
    for (long long i = 0; i < L.pixmaps[k].texels(); ++i)
      if ((material < 0 || L.pixmaps[k].material == material) && L.pixmaps[k].owner[i] == i) {
        sum += values[k][i * 3] * L.pixmaps[k].area[i];
        area += L.pixmaps[k].area[i];
      }
  return sum / area;
}

// The area mean of the first channel of the radiosity of the pixmap of
// patch `name`, over its texels holding a value.
double patch_mean(const Scene& scene, const PixmapLayout& L, const PixmapState& state, const std::string& name) {
  const int k = L.pixmap_of_patch[test::patch_named(scene, name)];
  double sum = 0.0, area = 0.0;
  for (long long i = 0; i < L.pixmaps[k].texels(); ++i)
    if (L.pixmaps[k].owner[i] == i) {
      sum += state.radiosity[k][i * 3] * L.pixmaps[k].area[i];
      area += L.pixmaps[k].area[i];
    }
  return sum / area;
}

SolveOptions threads(int n) {
  SolveOptions so;
  so.threads = n;
  return so;
}

using NamedQuad = std::pair<std::string, std::array<std::array<double, 3>, 4>>;

// An OBJ scene of quads (counter-clockwise seen from the side they face)
// written to a folder of the test's own and read: the quad named "light"
// emits 1 (reflectance 0), those named "black..." are black, the others
// white (0.7).
Scene quad_scene(const std::string& name, const std::vector<NamedQuad>& quads) {
  const test::TempDir tmp(name);
  const std::string dir = tmp.string();
  std::ofstream mtl(dir + "/room.mtl");
  mtl << "newmtl white\nKd 0.7 0.7 0.7\nnewmtl light\nKd 0 0 0\nKe 1 1 1\nnewmtl black\nKd 0 0 0\n";
  mtl.close();
  std::ofstream obj(dir + "/room.obj");
  obj << "mtllib room.mtl\n";
  int v = 0;
  for (const auto& [quad_name, q] : quads) {
    for (const auto& p : q) obj << "v " << p[0] << " " << p[1] << " " << p[2] << "\n";
    const char* material = quad_name == "light" ? "light" : quad_name.rfind("black", 0) == 0 ? "black" : "white";
    obj << "o " << quad_name << "\nusemtl " << material << "\nf " << v + 1 << " "
        << v + 2 << " " << v + 3 << " " << v + 4 << "\n";
    v += 4;
  }
  obj.close();
  return read_obj_scene(dir + "/room.obj");
}

// The six walls of the closed box [0, x] x [0, y] x [0, z], facing in, named
// in this order: floor (y = 0), ceiling, back (z = 0), front, the end at
// x = 0 and the end at x = x; then `more` quads.
std::vector<NamedQuad> box_room(double x, double y, double z, const std::array<std::string, 6>& names,
                                const std::vector<NamedQuad>& more = {}) {
  std::vector<NamedQuad> quads = {
      {names[0], {{{0, 0, 0}, {0, 0, z}, {x, 0, z}, {x, 0, 0}}}}, {names[1], {{{0, y, 0}, {x, y, 0}, {x, y, z}, {0, y, z}}}},
      {names[2], {{{0, 0, 0}, {x, 0, 0}, {x, y, 0}, {0, y, 0}}}}, {names[3], {{{0, 0, z}, {0, y, z}, {x, y, z}, {x, 0, z}}}},
      {names[4], {{{0, 0, 0}, {0, y, 0}, {0, y, z}, {0, 0, z}}}}, {names[5], {{{x, 0, 0}, {x, 0, z}, {x, y, z}, {x, y, 0}}}},
  };
  quads.insert(quads.end(), more.begin(), more.end());
  return quads;
}

// A 4 x 2 x 2 room cut in two by a floor-to-ceiling wall `thickness`
// thick at x = 2, lit by its end wall at x = 0 (E = 1): the half beyond the
// wall is sealed, and its true radiosity is 0.
Scene divided_room(double thickness) {
  const double a = 2.0 - 0.5 * thickness, b = 2.0 + 0.5 * thickness;
  return quad_scene("divided_room", box_room(4, 2, 2, {"floor", "ceiling", "back", "front", "light", "end"},
                                             {{"wall_lit", {{{a, 0, 0}, {a, 0, 2}, {a, 2, 2}, {a, 2, 0}}}},
                                              {"wall_sealed", {{{b, 0, 0}, {b, 2, 0}, {b, 2, 2}, {b, 0, 2}}}}}));
}

TEST(PixmapLayout, ATableTopOverTheFloorLeavesNoFloorOut) {
  // A one-sided table top 3 x 3, 20 cm over a 4 x 4 floor, covers the
  // centroids of both of the floor's coarse triangles, where every ray of
  // the test for the inside of a closed object meets its back. The whole
  // floor was left out (black, and 18% of the emitted power lost). A
  // triangle must be shut near its corners too, and nothing here is.
  const Scene scene = test::room_with_panel(0.2, 1.5);
  PixmapOptions o;
  o.texel_size = 0.2;
  const PixmapLayout L = make_pixmap_layout(scene, o, 1e9);
  EXPECT_EQ(L.enclosed_area, 0.0);
  // Under a rug 1 mm up, cut along its outline, the floor is shut: its 4
  // m^2 are left out, exactly.
  const PixmapLayout rug = make_pixmap_layout(test::room_with_panel(0.001, 1.0), o, 1e9);
  EXPECT_NEAR(rug.enclosed_area, 4.0, 1e-9);
}

TEST(PixmapSolver, NoShooterSitsAcrossAWallStandingOnItsPatch) {
  // The wall (0.04) is thinner than a texel (0.08), and a block of 4 x 4
  // texels on the floor, ceiling and side walls straddles it: shooting that
  // block's power from its centroid lit the sealed half at 5% of the lit
  // half. Blocks are split along the contact lines, so only the texels that
  // straddle the wall themselves (one value for both sides) leak.
  const Scene scene = divided_room(0.04);
  for (const Patch& p : scene.patches) ASSERT_GT(scene.patch_area(static_cast<int>(&p - scene.patches.data())), 0.0);
  PixmapOptions o;
  o.texel_size = 0.08;
  o.block = 4;
  o.hemicube_res = 64;
  const PixmapSolver solver(scene, o, threads(0));
  const PixmapRun run = solver.run(solver.initial_state());
  const PixmapLayout& L = solver.layout();
  auto mean_of = [&](const std::string& name) { return patch_mean(scene, L, run.state, name); };
  const double lit = mean_of("wall_lit"), sealed = std::max(mean_of("end"), mean_of("wall_sealed"));
  std::printf("divided room: lit side of the wall %.4f, sealed half at most %.3g\n", lit, sealed);
  EXPECT_GT(lit, 0.1);
  EXPECT_LT(sealed, 3e-3 * lit);
}

TEST(PixmapSolver, ATexelAWallStandsAcrossIsSplitAndNeitherLeaksNorLosesLight) {
  // The wall, 1 mm thick, stands in the middle of a row of texels (45 of
  // 4/45 along the room): each such texel is cut in two by the wall's
  // footprint. With one value and one centroid (inside the wall) its shots
  // went into the wall's back faces, and whatever it shot it shot from the
  // wall. Now the part beyond the wall is held by the texel next to it on
  // that side: the sealed half stays dark and no power is lost.
  const Scene scene = divided_room(0.001);
  PixmapOptions o;
  o.texel_size = 4.0 / 45.0;
  o.hemicube_res = 64;
  const PixmapSolver solver(scene, o, threads(0));
  const PixmapRun run = solver.run(solver.initial_state());
  const PixmapLayout& L = solver.layout();
  const Pixmap& floor = L.pixmaps[L.pixmap_of_patch[test::patch_named(scene, "floor")]];
  EXPECT_EQ(floor.cuts.size(), static_cast<size_t>(floor.height));  // the row of texels under the wall
  auto mean_of = [&](const std::string& name) { return patch_mean(scene, L, run.state, name); };
  const double lit = mean_of("wall_lit"), sealed = std::max(mean_of("end"), mean_of("wall_sealed"));
  const double escaped = run.state.power_escaped.x / run.power_emitted.x;
  std::printf("wall across a texel row: lit side %.4f, sealed half at most %.3g, escaped %.3g of the emitted\n", lit,
              sealed, escaped);
  EXPECT_GT(lit, 0.1);
  EXPECT_LT(sealed, 3e-3 * lit);
  EXPECT_LT(escaped, 1e-3);
}

TEST(PixmapSolver, TheCornellBoxAMillionUnitsFromTheOriginLosesNoLight) {
  // Moved by 10^6, a shooter's centre on the tall block's top lies 3e-10
  // below it (its texels' centres rounded): the top, seen from behind a
  // hair under it, covered a quarter of its hemicube, and 3% of the power
  // escaped the closed box, every patch mean 3-8% off. A plane through the
  // centre up to rounding is seen edge on.
  const Scene at = read_obj_scene(kData + "/cornell_box/cornell_box.obj");
  const Scene moved = test::transformed(at, [](const Vec3& v) { return v + Vec3(1e6); });
  PixmapOptions o;
  o.texel_size = 20.0;
  o.hemicube_res = 64;
  const PixmapSolver a(at, o, threads(0)), b(moved, o, threads(0));
  const PixmapRun ra = a.run(a.initial_state()), rb = b.run(b.initial_state());
  const double escaped = rb.state.power_escaped.x / rb.power_emitted.x;
  std::printf("Cornell box moved by 1e6: escaped %.3g of the emitted (%.3g as it is)\n", escaped,
              ra.state.power_escaped.x / ra.power_emitted.x);
  EXPECT_LT(escaped, 1e-4);
  for (const char* name : {"floor", "ceiling", "tall_block", "short_block", "back_wall"}) {
    const double pa = patch_mean(at, a.layout(), ra.state, name), pb = patch_mean(moved, b.layout(), rb.state, name);
    EXPECT_NEAR(pb / pa, 1.0, 1e-3) << name;
  }
}

TEST(PixmapSolver, AWallOnTheTexelLinesLetsNoLightThrough) {
  // The same room with the wall's two faces a millimetre either side of a
  // texel line (x = 2 at 0.1 and 0.08 texels). A pixel seen just before
  // the wall's foot had its share spread over the texels under its
  // footprint, on both sides of the wall: the sealed half got 0.46-0.64%
  // of the lit side's radiosity. Such a footprint now gives all of it to
  // the texel under the pixel's centre.
  const Scene scene = divided_room(0.001);
  for (double texel : {0.1, 0.08}) {
    PixmapOptions o;
    o.texel_size = texel;
    o.hemicube_res = 64;
    const PixmapSolver solver(scene, o, threads(0));
    const PixmapRun run = solver.run(solver.initial_state());
    const PixmapLayout& L = solver.layout();
    const Pixmap& floor = L.pixmaps[L.pixmap_of_patch[test::patch_named(scene, "floor")]];
    // The two columns the wall's faces stand in are marked, whole, and
    // nothing else (the room's walls stand on the floor's outline).
    const int lit_column = static_cast<int>(std::floor(1.9995 / floor.texel_u));
    ASSERT_EQ(static_cast<int>(std::floor(2.0005 / floor.texel_u)), lit_column + 1);
    for (int j = 0; j < floor.height; ++j) {
      const size_t row = static_cast<size_t>(j) * floor.width;
      EXPECT_TRUE(floor.wall_foot[row + lit_column] && floor.wall_foot[row + lit_column + 1]) << texel << " " << j;
    }
    EXPECT_EQ(std::count(floor.wall_foot.begin(), floor.wall_foot.end(), 1), 2 * floor.height) << texel;
    auto mean_of = [&](const std::string& name) { return patch_mean(scene, L, run.state, name); };
    const double lit = mean_of("wall_lit"), sealed = std::max(mean_of("end"), mean_of("wall_sealed"));
    std::printf("wall on the texel lines (%g): lit side %.4f, sealed half at most %.3g\n", texel, lit, sealed);
    EXPECT_GT(lit, 0.1) << texel;
    EXPECT_LT(sealed, 1e-6 * lit) << texel;
  }
}

TEST(PixmapSolver, BlocksUnderALampHungJustBelowTheCeilingLoseNoMoreThanTheirTexels) {
  // A closed 4 m room, a 0.9 x 0.9 lamp facing down 1 cm under the ceiling.
  // Its back receives nothing, so light that enters the gap is lost there:
  // at most the radiosity around the gap times the opening's area (the
  // lamp's perimeter times 0.01). Blocks of 2 x 2 texels are a speed-up
  // over shooting texel by texel and must lose what the texels lose. The
  // ceiling's blocks straddling the lamp's outline shot their open texels'
  // power from a centroid over the lamp, into its back: 18 times what the
  // texels shot one by one lost, 9 times the bound. Now the outline splits a
  // block, and a group whose centroid falls on the other side of it (an L of
  // three open texels around a covered one) shoots texel by texel.
  const double gap = 0.01, top = 4.0 - gap, lo = 1.35, hi = 2.25;
  const Scene scene =
      quad_scene("lamp_room", box_room(4, 4, 4, {"floor", "ceiling", "back", "front", "left", "right"},
                                       {{"light", {{{lo, top, lo}, {hi, top, lo}, {hi, top, hi}, {lo, top, hi}}}}}));
  const int floor = test::patch_named(scene, "floor"), light = test::patch_named(scene, "light");
  struct Result {
    double escaped, floor_mean, bound;
  };
  auto solve = [&](int block) {
    PixmapOptions o;
    o.texel_size = 0.2;
    o.block = block;
    o.hemicube_res = 32;
    const PixmapSolver solver(scene, o, threads(0));
    const PixmapRun run = solver.run(solver.initial_state());
    const PixmapLayout& L = solver.layout();
    double brightest = 0.0, sum = 0.0, area = 0.0;
    for (size_t k = 0; k < L.pixmaps.size(); ++k) {
      const Pixmap& pm = L.pixmaps[k];
      if (static_cast<int>(k) == L.pixmap_of_patch[light]) continue;
      for (long long i = 0; i < pm.texels(); ++i) {
        if (pm.owner[i] != i) continue;
        const double b = run.state.radiosity[k][i * 3];
        brightest = std::max(brightest, b);
        if (static_cast<int>(k) == L.pixmap_of_patch[floor]) {
          sum += b * pm.area[i];
          area += pm.area[i];
        }
      }
    }
    const Result r{run.state.power_escaped.x, sum / area, brightest * 4.0 * (hi - lo) * gap};
    std::printf("lamp under the ceiling, blocks of %d: escaped %.4g of %.4g emitted (bound %.4g), floor %.6f\n", block,
                r.escaped, run.power_emitted.x, r.bound, r.floor_mean);
    return r;
  };
  const Result texels = solve(1), blocks = solve(2);
  for (const Result& r : {texels, blocks}) {
    EXPECT_GT(r.escaped, 0.0);
    EXPECT_LT(r.escaped, r.bound);
  }
  EXPECT_NEAR(blocks.escaped / texels.escaped, 1.0, 0.25);
  EXPECT_NEAR(blocks.floor_mean / texels.floor_mean, 1.0, 2e-3);
}

TEST(PixmapSolver, FurnaceConvergesToEOverOneMinusRho) {
  // A closed cube, every wall E = 1, rho = 0.5: B = 2. Every shot's delta
  // form factors sum to 1, so the area mean is exact to the unshot power;
  // single texels differ by the hemicube's aliasing and by shooting from
  // the centre of each texel (next to an edge, a texel's exchange with its
  // neighbour across the edge is not that of its centre).
  const Scene scene = read_obj_scene(kData + "/furnace_cube/furnace_cube.obj");
  PixmapOptions o;
  o.texel_size = 0.1;
  o.block = 1;
  o.hemicube_res = 128;
  o.unshot = 1e-7;
  const PixmapSolver solver(scene, o, threads(0));
  const PixmapRun run = solver.run(solver.initial_state());
  EXPECT_LE(run.unshot_fraction, 1e-7);
  const PixmapLayout& L = solver.layout();
  double worst = 0.0;
  for (size_t k = 0; k < L.pixmaps.size(); ++k)
    for (long long i = 0; i < L.pixmaps[k].texels(); ++i)
      if (L.pixmaps[k].owner[i] == i) worst = std::max(worst, std::abs(run.state.radiosity[k][i * 3] / 2.0 - 1.0));
  const double mean = area_mean(L, run.state.radiosity);
  std::printf("furnace: mean %.9f, worst texel %.3g\n", mean, worst);
  // The state is in float: each of some 10^5 additions rounds by up to 6e-8.
  EXPECT_NEAR(mean, 2.0, 2.0 * 3e-5);
  EXPECT_LT(worst, 0.05);
  const Rgb absorbed = run.state.power_absorbed;
  EXPECT_NEAR(absorbed.x / run.power_emitted.x, 1.0, 1e-6);  // closed: nothing escapes
  EXPECT_NEAR(run.state.power_escaped.x, 0.0, 1e-7 * run.power_emitted.x);  // F rounded to float
}

TEST(PixmapSolver, AnyEmissionTheSceneAcceptsIsCarriedThroughItsFloatTexels) {
  // The texels are float: an emission of 1e39 overflowed them (the run never
  // ended, or with a shot limit wrote NaN), and 1e-300 underflowed to a
  // black scene. Radiosity is linear in the emission, so each run must give
  // the furnace's B = 2 E everywhere, up to float's rounding.
  Scene scene = read_obj_scene(kData + "/furnace_cube/furnace_cube.obj");
  PixmapOptions o;
  o.texel_size = 0.25;
  o.hemicube_res = 16;
  o.shots = 40;
  for (const double e : {1.0, 1e39, 1e-300, 1e50}) {
    for (Material& m : scene.materials) m.emission = Rgb(e);
    const PixmapSolver solver(scene, o, threads(0));
    Mesh mesh;
    Solution sol;
    std::vector<int> texel;
    const PixmapRun run = solver.run(solver.initial_state());
    solver.display_mesh(solver.display(run.state, solver.ambient(run.state)), mesh, sol, texel);
    double sum = 0.0, area = 0.0;
    for (int t = 0; t < mesh.triangle_count(); ++t) {
      ASSERT_TRUE(std::isfinite(sol.element[static_cast<size_t>(t)].x)) << e;
      sum += sol.element[static_cast<size_t>(t)].x * mesh.area(t);
      area += mesh.area(t);
    }
    EXPECT_NEAR(sum / area / (2.0 * e), 1.0, 0.02) << "emission " << e;
    EXPECT_NEAR(solver.power_emitted().x / (6.0 * e), 1.0, 1e-12) << "emission " << e;
  }
}

TEST(PixmapSolver, AHemicubeTooLargeForTheMemoryLimitIsRefusedBeforeItIsMade) {
  // Its buffers grow with the square of the resolution: 16384 pixels (in
  // the option's range) are 15 GiB, which ended in std::bad_alloc under a
  // 6 GB address-space limit whatever max_memory said.
  const Scene scene = read_obj_scene(kData + "/parallel_plates/parallel_plates.obj");
  PixmapOptions o;
  o.hemicube_res = 8192;  // 3.75 GiB
  SolveOptions so = threads(0);
  so.max_memory = 0.5;
  const test::Thrown t = test::thrown<NumericalError>([&] { PixmapSolver solver(scene, o, so); });
  EXPECT_TRUE(t.names("hemicube_res") && t.names("max_memory"));
  EXPECT_TRUE(t.says({"8192", "3.75 GiB", "0.5 GiB"}));
  o.hemicube_res = 64;
  EXPECT_NO_THROW(PixmapSolver(scene, o, so));
}

TEST(PixmapSolver, ReflectanceNearOneConvergesAndTheAmbientTermFillsWhatIsUnshot) {
  // rho = 0.999: B = E / (1 - rho) = 1000. Stopped at an unshot power of
  // 1e-3 of the emitted, the state lacks the bounces of what is unshot: the
  // ambient term (Cohen et al.) puts most of it back (what remains is the
  // rounding of some 3 x 10^5 float additions per texel).
  Scene scene = read_obj_scene(kData + "/furnace_cube/furnace_cube.obj");
  for (Material& m : scene.materials) m.reflectance = Rgb(0.999);
  PixmapOptions o;
  o.texel_size = 0.25;
  o.block = 1;
  o.hemicube_res = 64;
  o.unshot = 1e-3;
  const PixmapSolver solver(scene, o, threads(0));
  const PixmapRun run = solver.run(solver.initial_state());
  EXPECT_LE(run.unshot_fraction, 1e-3);
  const auto shown = solver.display(run.state, run.ambient);
  const double raw = area_mean(solver.layout(), run.state.radiosity);
  const double with_ambient = area_mean(solver.layout(), shown);
  std::printf("rho 0.999: %lld shots, mean %.4f, with the ambient term %.4f\n", run.state.shots, raw, with_ambient);
  EXPECT_NEAR(raw, 1000.0, 1000.0 * 2e-3);
  EXPECT_NEAR(with_ambient, 1000.0, 1000.0 * 5e-4);
  EXPECT_LT(std::abs(with_ambient - 1000.0), 0.5 * std::abs(raw - 1000.0));
}

TEST(PixmapSolver, InAnOpenSceneTheAmbientTermCountsOnlyThePowerThatStays) {
  // The box on the floor is open: most of the light leaves. Stopped early,
  // the state lacks what is unshot; an ambient term that spread all of it
  // over the scene (as in a closed one) would put back several times what
  // stays. Against a converged run, the ambient term must close most of
  // the gap, without overshooting it.
  const Scene scene = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  PixmapOptions o;
  o.texel_size = 0.25;
  o.hemicube_res = 64;
  o.unshot = 1e-7;
  // Over the white surfaces (the light's emission would hide the rest).
  const int white = static_cast<int>(std::find_if(scene.materials.begin(), scene.materials.end(),
                                                  [](const Material& m) { return m.emission.x == 0.0; }) -
                                     scene.materials.begin());
  const PixmapSolver converged(scene, o, threads(0));
  const double exact =
      area_mean(converged.layout(), converged.run(converged.initial_state()).state.radiosity, white);
  o.unshot = 0.02;
  const PixmapSolver early(scene, o, threads(0));
  const PixmapRun run = early.run(early.initial_state());
  const double raw = area_mean(early.layout(), run.state.radiosity, white);
  const double with_ambient = area_mean(early.layout(), early.display(run.state, run.ambient), white);
  const double stays = run.state.power_absorbed.x / (run.state.power_absorbed.x + run.state.power_escaped.x);
  std::printf("open scene: converged %.6f, early %.6f, with the ambient term %.6f (%.0f%% of the power ended stayed)\n",
              exact, raw, with_ambient, 100.0 * stays);
  ASSERT_LT(stays, 0.8);
  EXPECT_LT(raw, exact);
  EXPECT_LT(std::abs(with_ambient - exact), 0.3 * (exact - raw));
}

TEST(PixmapSolver, AStripNarrowerThanThePixelsGetsItsLightWhateverItsWidth) {
  // A 1 x 1 lamp (E = 1) facing down 2 above a one-sided strip 1 m long
  // facing up, and nothing else: the strip's radiosity is 0.7 F(x -> lamp),
  // Lambert's closed form. At hemicube resolution 32 a pixel is 3.6 degrees
  // wide and the strip 0.03 to 1.4 of one: the item buffer saw the 1 mm
  // strip in no pixel at all. It now takes the exact factor.
  for (double w : {0.001, 0.01, 0.05}) {
    const double z0 = 1.5 - 0.5 * w, z1 = 1.5 + 0.5 * w;
    const Scene scene = quad_scene("narrow_strip", {
                                                       {"light", {{{0, 2, 0}, {1, 2, 0}, {1, 2, 1}, {0, 2, 1}}}},
                                                       {"strip", {{{0, 0, z0}, {0, 0, z1}, {1, 0, z1}, {1, 0, z0}}}},
                                                   });
    PixmapOptions o;
    o.texel_size = 0.1;
    o.hemicube_res = 32;
    const PixmapSolver solver(scene, o, threads(0));
    const PixmapRun run = solver.run(solver.initial_state());
    const PixmapLayout& L = solver.layout();
    const double mean = patch_mean(scene, L, run.state, "strip");
    const Vec3 lamp[4] = {{0, 2, 0}, {1, 2, 0}, {1, 2, 1}, {0, 2, 1}};
    double exact = 0.0;
    constexpr int kSamples = 400;
    for (int i = 0; i < kSamples; ++i)
      for (int j = 0; j < 4; ++j)
        exact += point_polygon_form_factor(Vec3((i + 0.5) / kSamples, 0.0, z0 + (j + 0.5) / 4 * w), Vec3(0, 1, 0), lamp, 4,
                                           Vec3(0, -1, 0));
    exact *= 0.7 / (4.0 * kSamples);
    std::printf("strip %g wide: radiosity %.5f, exact %.5f\n", w, mean, exact);
    EXPECT_NEAR(mean / exact, 1.0, 0.01) << "strip " << w << " wide";
  }
}

TEST(PixmapSolver, TheSidesOfABoxALampCrossesGetTheLampsExactLight) {
  // A closed black room 4 x 3 x 4, a 1 x 1 lamp (E = 1) facing down 10 cm
  // under its ceiling, crossed by a closed box 0.4 x 0.35 x 0.4 (y from 2.6
  // to 2.95): each side's radiosity is 0.7 F(side -> lamp), the part of the
  // lamp in front of it (Lambert's closed form, integrated over the side).
  // The lamp's 13 x 13 texels of 0.077 make blocks of 4, 4, 4 and 1. The
  // near field took F from points of the shooting texels to the receiving
  // squares, one point (the centroid) for the lamp's texels that the box's
  // outline cuts: two sides came out 5.9% low, and with --block 1 all four
  // 5% low. It is now taken from points of the receiving texels' pieces to
  // the shooting texels' polygons.
  const double x0 = 1.8, x1 = 2.2, y0 = 2.6, y1 = 2.95, z0 = 1.8, z1 = 2.2;
  const std::vector<NamedQuad> sides = {
      {"side_mz", {{{x0, y0, z0}, {x0, y1, z0}, {x1, y1, z0}, {x1, y0, z0}}}},
      {"side_pz", {{{x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}}}},
      {"side_mx", {{{x0, y0, z0}, {x0, y0, z1}, {x0, y1, z1}, {x0, y1, z0}}}},
      {"side_px", {{{x1, y0, z0}, {x1, y1, z0}, {x1, y1, z1}, {x1, y0, z1}}}}};
  std::vector<NamedQuad> more = sides;
  more.push_back({"light", {{{1.5, 2.9, 1.5}, {2.5, 2.9, 1.5}, {2.5, 2.9, 2.5}, {1.5, 2.9, 2.5}}}});
  more.push_back({"top", {{{x0, y1, z0}, {x0, y1, z1}, {x1, y1, z1}, {x1, y1, z0}}}});
  more.push_back({"bottom", {{{x0, y0, z0}, {x1, y0, z0}, {x1, y0, z1}, {x0, y0, z1}}}});
  const Scene scene = quad_scene(
      "lamp_through_box",
      box_room(4, 3, 4, {"black_floor", "black_ceiling", "black_back", "black_front", "black_end0", "black_end1"}, more));
  const Vec3 lamp[4] = {{1.5, 2.9, 1.5}, {2.5, 2.9, 1.5}, {2.5, 2.9, 2.5}, {1.5, 2.9, 2.5}};
  for (int block : {4, 1}) {
    PixmapOptions o;
    o.texel_size = 0.08;
    o.block = block;
    const PixmapSolver solver(scene, o, threads(0));
    const PixmapRun run = solver.run(solver.initial_state());
    for (const auto& [name, q] : sides) {
      const Vec3 a(q[0][0], q[0][1], q[0][2]), b(q[1][0], q[1][1], q[1][2]), d(q[3][0], q[3][1], q[3][2]);
      const Vec3 normal = glm::normalize(glm::cross(b - a, d - a));
      double exact = 0.0;
      constexpr int kSamples = 200;
      for (int i = 0; i < kSamples; ++i)
        for (int j = 0; j < kSamples; ++j)
          exact += point_polygon_form_factor(a + ((i + 0.5) / kSamples) * (b - a) + ((j + 0.5) / kSamples) * (d - a), normal,
                                             lamp, 4, Vec3(0, -1, 0));
      exact *= 0.7 / (kSamples * kSamples);
      const double mean = patch_mean(scene, solver.layout(), run.state, name);
      std::printf("block %d, %s: radiosity %.5f, exact %.5f\n", block, name.c_str(), mean, exact);
      EXPECT_NEAR(mean / exact, 1.0, 0.015) << name << ", block " << block;
    }
  }
}

TEST(PixmapSolver, APicturesMillimetreEdgesSeeHalfTheirViewInTheWallTheyHangOn) {
  // A picture 1 mm thick on a 4 x 4 wall of a closed room 1 deep: each
  // edge face, perpendicular to the wall and 1 mm high off it, has F = 1/2
  // to the wall (the wall right beside it fills half its view). By
  // reciprocity the wall's shooters must send
  // sum_q A_q F(q -> edge) = A_edge / 2. From a block's centre, or
  // from points on its texels, the wall sees an edge edge on: the hemicube
  // and the near field gave 0 to 0.5% of it. The texels (4/47) leave slivers
  // along the outline, held by the texels beyond them; the blocks around
  // the picture's corners have their centres beyond the edges' planes.
  const double t = 0.001;
  const Scene scene =
      quad_scene("picture", box_room(1, 4, 4, {"floor", "ceiling", "back", "front_wall", "wall", "end"},
                                     {
                                         {"front", {{{t, 1.5, 1.5}, {t, 2.2, 1.5}, {t, 2.2, 2.5}, {t, 1.5, 2.5}}}},
                                         {"top", {{{0, 2.2, 1.5}, {0, 2.2, 2.5}, {t, 2.2, 2.5}, {t, 2.2, 1.5}}}},
                                         {"bottom", {{{0, 1.5, 1.5}, {t, 1.5, 1.5}, {t, 1.5, 2.5}, {0, 1.5, 2.5}}}},
                                         {"left", {{{0, 1.5, 1.5}, {0, 2.2, 1.5}, {t, 2.2, 1.5}, {t, 1.5, 1.5}}}},
                                         {"right", {{{0, 1.5, 2.5}, {t, 1.5, 2.5}, {t, 2.2, 2.5}, {0, 2.2, 2.5}}}},
                                     }));
  PixmapOptions o;
  o.texel_size = 4.0 / 47.0;
  o.hemicube_res = 32;
  const PixmapSolver solver(scene, o, threads(0));
  const PixmapLayout& L = solver.layout();
  const int wall = L.pixmap_of_patch[test::patch_named(scene, "wall")];
  const Pixmap& pw = L.pixmaps[wall];
  for (const char* edge : {"top", "bottom", "left", "right"}) {
    const Pixmap& pe = L.pixmaps[L.pixmap_of_patch[test::patch_named(scene, edge)]];
    double sent = 0.0;
    for (size_t s = 0; s < L.shooters.size(); ++s) {
      if (L.shooters[s].pixmap != wall) continue;
      const auto rows = solver.form_factors(static_cast<int>(s));
      for (size_t q = 0; q < rows.size(); ++q)
        for (const auto& [texel, f] : rows[q])
          if (texel >= pe.first && texel < pe.first + pe.texels()) sent += pw.area[L.shooters[s].texels[q]] * f;
    }
    const double edge_area = scene.patch_area(test::patch_named(scene, edge));
    std::printf("picture edge %s: F to the wall by reciprocity %.5f\n", edge, sent / edge_area);
    EXPECT_NEAR(sent / edge_area, 0.5, 0.005) << edge;
  }
}

TEST(PixmapSolver, ConvergesToTheLinearSystemOfItsOwnFormFactors) {
  // Progressive refinement solves B_t = E_t + rho_t sum_i F(i -> t) A_i / A_t
  // B_i over the texels, with F from each source texel as the shots use it
  // (blocks of 2 x 2 texels shoot, their near field per texel): Jacobi on the
  // same rows must agree to the stopping tolerance.
  const Scene scene = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  PixmapOptions o;
  o.texel_size = 0.25;
  o.block = 2;
  o.hemicube_res = 64;
  o.unshot = 1e-9;
  const PixmapSolver solver(scene, o, threads(0));
  const PixmapLayout& L = solver.layout();
  const size_t nt = static_cast<size_t>(L.texels);
  std::vector<double> area(nt, 0.0), rho(nt, 0.0), emission(nt, 0.0);
  std::vector<std::vector<std::pair<long long, double>>> rows(nt);
  size_t blocks = 0;
  for (size_t s = 0; s < L.shooters.size(); ++s) {
    const Shooter& sh = L.shooters[s];
    const Pixmap& pm = L.pixmaps[sh.pixmap];
    auto from = solver.form_factors(static_cast<int>(s));
    ASSERT_EQ(from.size(), sh.texels.size());
    if (sh.texels.size() > 1) ++blocks;
    for (size_t q = 0; q < sh.texels.size(); ++q) {
      const size_t g = static_cast<size_t>(pm.first + sh.texels[q]);
      area[g] = pm.area[sh.texels[q]];
      rho[g] = scene.materials[pm.material].reflectance.x;
      emission[g] = scene.materials[pm.material].emission.x;
      rows[g] = std::move(from[q]);
    }
  }
  ASSERT_GT(blocks, 20u);
  std::vector<double> b(emission), next(nt);
  for (int it = 0; it < 500; ++it) {
    next = emission;
    for (size_t g = 0; g < nt; ++g)
      for (const auto& [t, f] : rows[g]) {
        ASSERT_GT(area[t], 0.0);
        next[t] += rho[t] * f * area[g] / area[t] * b[g];
      }
    b.swap(next);
  }
  const PixmapRun run = solver.run(solver.initial_state());
  double bmax = 0.0, worst = 0.0;
  for (size_t g = 0; g < nt; ++g) bmax = std::max(bmax, b[g]);
  for (size_t k = 0; k < L.pixmaps.size(); ++k) {
    const Pixmap& pm = L.pixmaps[k];
    for (long long i = 0; i < pm.texels(); ++i)
      if (pm.owner[i] == i)
        worst = std::max(worst, std::abs(run.state.radiosity[k][i * 3] - b[pm.first + i]) / bmax);
  }
  EXPECT_LT(worst, 1e-5);
}

void expect_same_state(const PixmapState& a, const PixmapState& b) {
  ASSERT_EQ(a.shots, b.shots);
  ASSERT_EQ(a.radiosity.size(), b.radiosity.size());
  for (size_t k = 0; k < a.radiosity.size(); ++k) {
    EXPECT_EQ(a.radiosity[k], b.radiosity[k]) << "pixmap " << k;
    EXPECT_EQ(a.unshot[k], b.unshot[k]) << "pixmap " << k;
  }
  EXPECT_EQ(a.power_absorbed, b.power_absorbed);
  EXPECT_EQ(a.power_escaped, b.power_escaped);
}

// What write_pixmap_state takes for `state` of `solver` (which outlives it).
PixmapOutput output_of(const PixmapSolver& solver, const PixmapState& state) {
  PixmapOutput out;
  out.solver = std::shared_ptr<const PixmapSolver>(&solver, [](const PixmapSolver*) {});
  out.state = state;
  out.display = solver.display(state, solver.ambient(state));
  return out;
}

TEST(PixmapSolver, OneAndTwoThreadsAndAResumeGiveIdenticalStates) {
  const Scene scene = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  PixmapOptions o;
  o.hemicube_res = 64;
  o.shots = 60;
  o.unshot = 0.0;
  const PixmapSolver one(scene, o, threads(1)), two(scene, o, threads(2));
  const PixmapRun a = one.run(one.initial_state()), b = two.run(two.initial_state());
  EXPECT_EQ(a.state.shots, 60);
  expect_same_state(a.state, b.state);
  // 25 shots, saved to files and read back, then resumed to 60.
  PixmapOptions first = o;
  first.shots = 25;
  const PixmapSolver part(scene, first, threads(0));
  const PixmapRun p = part.run(part.initial_state());
  const test::TempDir tmp;
  const std::string dir = (tmp / "state").string();
  write_pixmap_state(dir, output_of(part, p.state));
  PixmapState saved = read_pixmap_state(dir);
  expect_same_state(saved, p.state);
  check_resumable(saved, scene, one.layout(), o, saved.source);
  const PixmapRun resumed = one.run(saved);
  EXPECT_EQ(resumed.shots_this_run, 35);
  expect_same_state(resumed.state, a.state);
}

TEST(PixmapSolver, AStateFromOtherOptionsOrAnotherSceneIsRefused) {
  const Scene scene = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  PixmapOptions o;
  o.hemicube_res = 64;
  const PixmapSolver solver(scene, o, threads(0));
  const PixmapState st = solver.initial_state();
  PixmapOptions other = o;
  other.hemicube_res = 128;
  const test::Thrown options = test::thrown<InputError>([&] { check_resumable(st, scene, solver.layout(), other, "S"); });
  EXPECT_TRUE(options.names("hemicube_res"));
  EXPECT_TRUE(options.says({"S: ", "hemicube_res 64", "hemicube_res 128"}));
  Scene edited = scene;
  edited.materials[0].reflectance.x *= 0.5;
  EXPECT_TRUE(test::thrown<InputError>([&] { check_resumable(st, edited, solver.layout(), o, "S"); })
                  .says({"S: ", "another scene"}));
  PixmapState broken = st;
  broken.radiosity[0][0] = std::nanf("");
  EXPECT_TRUE(test::thrown<InputError>([&] { check_resumable(broken, scene, solver.layout(), o, "S"); })
                  .says({"S: ", "non-finite"}));
}

TEST(PixmapSolver, AStateDamagedEditedOrWithSwappedPixmapsIsRefusedByItsChecksum) {
  // The box's faces have pixmaps of one size: swapped, every size check
  // passes, as it does for a figure of state.json changed by hand.
  const Scene scene = read_obj_scene(kData + "/box_on_floor/box_on_floor.obj");
  PixmapOptions o;
  o.hemicube_res = 32;
  o.shots = 10;
  const PixmapSolver solver(scene, o, threads(0));
  const PixmapRun run = solver.run(solver.initial_state());
  const test::TempDir tmp;
  const PixmapOutput out = output_of(solver, run.state);
  auto fresh = [&](const std::string& name) {
    const std::string dir = (tmp / name).string();
    write_pixmap_state(dir, out);
    return dir;
  };
  const std::string intact = fresh("intact");
  expect_same_state(read_pixmap_state(intact), run.state);
  const fs::path json = fs::path("pixmaps") / "state.json";
  const std::string text = test::folder(intact).at(json.string());
  auto with_json = [&](const std::string& name, const std::string& from, const std::string& to) {
    const std::string dir = fresh(name);
    std::string edited = text;
    const size_t at = edited.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    edited.replace(at, from.size(), to);
    std::ofstream(fs::path(dir) / json) << edited;
    return dir;
  };
  const std::string shots = with_json("shots", "\"shots\": 10", "\"shots\": 11");
  EXPECT_TRUE(test::thrown<InputError>([&] { read_pixmap_state(shots); }).says({"state.json", "checksum", "edited"}));
  const std::string swapped = fresh("swapped");
  const fs::path p1 = fs::path(swapped) / "pixmaps" / "pixmap_1.vti", p2 = fs::path(swapped) / "pixmaps" / "pixmap_2.vti";
  ASSERT_EQ(run.state.sizes[1], run.state.sizes[2]);
  ASSERT_NE(run.state.radiosity[1], run.state.radiosity[2]);
  fs::rename(p1, fs::path(swapped) / "pixmaps" / "t");
  fs::rename(p2, p1);
  fs::rename(fs::path(swapped) / "pixmaps" / "t", p2);
  EXPECT_TRUE(test::thrown<InputError>([&] { read_pixmap_state(swapped); }).says({"checksum", "swapped"}));
  // A state written before states had a checksum is read as it is.
  const size_t line = text.find("  \"checksum\"");
  ASSERT_NE(line, std::string::npos);
  const std::string older = with_json("older", text.substr(line, text.find('\n', line) + 1 - line), "");
  expect_same_state(read_pixmap_state(older), run.state);
}

TEST(PixmapSolver, DisplayMeshCoversEveryPatchAndEachTriangleLiesInItsTexel) {
  const Scene scene = read_obj_scene(kData + "/cornell_box/cornell_box.obj");
  PixmapOptions o;
  o.texel_size = 40.0;
  o.shots = 3;
  const PixmapSolver solver(scene, o, threads(0));
  const PixmapRun run = solver.run(solver.initial_state());
  Mesh mesh;
  Solution sol;
  std::vector<int> texel;
  const auto shown = solver.display(run.state, Rgb(0.0));
  solver.display_mesh(shown, mesh, sol, texel);
  const auto areas = test::patch_areas(scene, mesh);
  for (size_t p = 0; p < scene.patches.size(); ++p) EXPECT_NEAR(areas[p] / scene.patch_area(static_cast<int>(p)), 1.0, 1e-9);
  const PixmapLayout& L = solver.layout();
  double dark = 0.0, footprints = 0.0;
  for (const char* block : {"short_block", "tall_block"}) footprints += scene.patch_area(test::patch_named(scene, block));
  for (int t = 0; t < mesh.triangle_count(); ++t) {
    if (texel[t] < 0) dark += mesh.area(t);
    const Pixmap& pm = L.pixmaps[L.pixmap_of_patch[mesh.patch[t]]];
    const Vec3 c = mesh.centroid(t);
    const int i = static_cast<int>(std::floor(pm.s_of(c))), j = static_cast<int>(std::floor(pm.t_of(c)));
    // Its texel's owner (in a texel a contact line cuts, its part's), or -1
    // for the parts inside the blocks.
    if (texel[t] >= 0) {
      const int cell = j * pm.width + i;
      std::vector<int> owners = {pm.owner[static_cast<size_t>(cell)]};
      for (const Pixmap::Cut& cut : pm.cuts)
        if (cut.texel == cell) owners.insert(owners.end(), cut.owners.begin(), cut.owners.end());
      EXPECT_NE(std::find(owners.begin(), owners.end(), texel[t]), owners.end());
    }
    // Counter-clockwise around the patch normal.
    const auto& v = mesh.triangles[t];
    const Vec3 n = glm::cross(mesh.positions[v[1]] - mesh.positions[v[0]], mesh.positions[v[2]] - mesh.positions[v[0]]);
    EXPECT_GE(glm::dot(n, scene.patches[mesh.patch[t]].normal), 0.0);
  }
  // What is shown dark is exactly the floor under the blocks: no dark teeth
  // outside their outlines, no lit floor under them.
  EXPECT_NEAR(dark / footprints, 1.0, 1e-9);
  for (const Rgb& b : sol.nodal.radiosity) EXPECT_TRUE(std::isfinite(b.x) && b.x >= 0.0);
}

}  // namespace
