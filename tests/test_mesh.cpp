// The initial CGAL mesh: exact areas, conformity between patches, quality.

#include "radmesh/obj_reader.h"
#include "radmesh/errors.h"
#include "radmesh/mesh.h"

#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

using namespace radmesh;

namespace {
using radmesh::test::kData;

// Undirected edge -> number of triangles using it, over the triangles kept by `use`.
template <class Use>
std::map<std::pair<int, int>, int> edge_use(const Mesh& m, Use use) {
  std::map<std::pair<int, int>, int> e;
  for (int t = 0; t < m.triangle_count(); ++t) {
    if (!use(t)) continue;
    const auto& tri = m.triangles[static_cast<size_t>(t)];
    for (int k = 0; k < 3; ++k) {
      const int a = tri[static_cast<size_t>(k)], b = tri[static_cast<size_t>((k + 1) % 3)];
      ++e[{std::min(a, b), std::max(a, b)}];
    }
  }
  return e;
}

double longest_edge(const Mesh& m) {
  double l = 0.0;
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k)
      l = std::max(l, glm::length(m.positions[static_cast<size_t>(t[static_cast<size_t>(k)])] -
                                  m.positions[static_cast<size_t>(t[static_cast<size_t>((k + 1) % 3)])]));
  return l;
}

Scene plate_with_hole() {
  RawFace f;
  f.name = "plate";
  f.material = 0;
  f.points = {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}};
  f.holes = {{{1, 1, 0}, {1, 3, 0}, {3, 3, 0}, {3, 1, 0}}};
  RawFace l;  // concave L-shape in the plane z = 1, facing down
  l.name = "ell";
  l.material = 0;
  l.points = {{0, 0, 1}, {0, 2, 1}, {1, 2, 1}, {1, 1, 1}, {2, 1, 1}, {2, 0, 1}};
  Material m;
  m.name = "m";
  m.reflectance = Rgb(0.5);
  return build_scene({f, l}, {m}, "test");
}
}  // namespace

TEST(Mesh, ClosedCubeIsClosedAndConsistentlyOriented) {
  const Scene s = read_obj_scene(kData + "/furnace_cube/furnace_cube.obj");
  MeshingOptions o;
  o.max_edge = 0.3;
  const Mesh m = mesh_scene(s, o);
  const auto edges = edge_use(m, [](int) { return true; });
  for (const auto& [e, n] : edges) EXPECT_EQ(n, 2) << e.first << "-" << e.second;
  // Orientation: each directed edge appears once.
  std::map<std::pair<int, int>, int> directed;
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k) ++directed[{t[static_cast<size_t>(k)], t[static_cast<size_t>((k + 1) % 3)]}];
  for (const auto& [e, n] : directed) EXPECT_EQ(n, 1);
  double area = 0.0;
  for (int t = 0; t < m.triangle_count(); ++t) area += m.area(t);
  EXPECT_NEAR(area, 6.0, 1e-12);
  EXPECT_LE(longest_edge(m), 0.3 * (1 + 1e-12));
  // Every triangle is counter-clockwise around its patch normal.
  for (int t = 0; t < m.triangle_count(); ++t) {
    const auto& tri = m.triangles[static_cast<size_t>(t)];
    const Vec3 n = glm::cross(m.positions[static_cast<size_t>(tri[1])] - m.positions[static_cast<size_t>(tri[0])],
                              m.positions[static_cast<size_t>(tri[2])] - m.positions[static_cast<size_t>(tri[0])]);
    EXPECT_GT(glm::dot(n, s.patches[static_cast<size_t>(m.patch[static_cast<size_t>(t)])].normal), 0.0);
  }
}

TEST(Mesh, CornellBoxPatchesShareEdgeVerticesAndKeepTheirArea) {
  const Scene s = read_obj_scene(kData + "/cornell_box/cornell_box.obj");
  for (DiscontinuityMode mode : {DiscontinuityMode::contacts, DiscontinuityMode::full}) {
    SCOPED_TRACE(to_string(mode));
    MeshingOptions o;
    o.max_edge = 60.0;
    o.discontinuity = mode;
    MeshReport rep;
    const Mesh m = mesh_scene(s, o, &rep);
    const std::vector<double> area = radmesh::test::patch_areas(s, m);
    for (size_t p = 0; p < s.patches.size(); ++p)
      EXPECT_NEAR(area[p] / s.patch_area(static_cast<int>(p)), 1.0, 1e-12) << s.patches[p].name;
    // The room (everything but the blocks) is a closed surface: every edge has
    // exactly two triangles, T-junctions at the ceiling hole included.
    auto room = [&](int t) {
      return s.patches[static_cast<size_t>(m.patch[static_cast<size_t>(t)])].name.find("block") == std::string::npos;
    };
    for (const auto& [e, n] : edge_use(m, room)) EXPECT_EQ(n, 2) << e.first << "-" << e.second;
    EXPECT_LE(longest_edge(m), 60.0 * (1 + 1e-12));
    const TriangleQuality q = compute_quality(m);
    // The angle bound holds where the input allows it: with contact lines
    // only. Shadow lines cross at angles of their own, which no mesh removes.
    if (mode == DiscontinuityMode::contacts)
      EXPECT_GE(*std::min_element(q.min_angle.begin(), q.min_angle.end()), 20.0 - 1e-6);
    else
      EXPECT_GT(*std::min_element(q.min_angle.begin(), q.min_angle.end()), 1.0);
  }
}

TEST(Mesh, HolesAndConcaveOutlines) {
  const Scene s = plate_with_hole();
  MeshingOptions o;
  o.max_edge = 0.5;
  const Mesh m = mesh_scene(s, o);
  double plate = 0.0, ell = 0.0;
  for (int t = 0; t < m.triangle_count(); ++t) {
    const Vec3 c = m.centroid(t);
    if (m.patch[static_cast<size_t>(t)] == 0) {
      plate += m.area(t);
      EXPECT_FALSE(c.x > 1 && c.x < 3 && c.y > 1 && c.y < 3) << "triangle inside the hole";
    } else {
      ell += m.area(t);
      EXPECT_FALSE(c.x > 1 && c.y > 1) << "triangle in the L's notch";
    }
  }
  EXPECT_NEAR(plate, 12.0, 1e-12);
  EXPECT_NEAR(ell, 3.0, 1e-12);
}

TEST(Mesh, ASliverIsLeftAsItsOutlineAndMeshesAtOnce) {
  // A unit floor and a needle 0.8 long and 1e-7 wide standing over it. The
  // mesher split the needle's two long edges wherever a point of the other
  // lay in an edge's diametral circle, down to about the width: it ran for
  // minutes towards 16 M points. The needle is now the triangulation of
  // its outline (cut at --max-edge where outlines are shared: about 1.6 /
  // 0.1 points, as many triangles less two), counted, and the floor is
  // meshed as before.
  std::vector<RawFace> faces(2);
  faces[0].name = "floor";
  faces[0].points = {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}};
  faces[1].name = "needle";
  faces[0].material = faces[1].material = 0;
  faces[1].points = {{0.1, 0.3, 0.5}, {0.9, 0.3, 0.5}, {0.5, 0.3, 0.5 + 1e-7}};
  const Scene s = build_scene(faces, {test::material("white", Rgb(0.5), Rgb(1.0))}, "needle");
  MeshingOptions o;
  o.max_edge = 0.1;
  MeshReport report;
  const Mesh m = mesh_scene(s, o, &report);
  int needle = 0, floor = 0;
  for (int t = 0; t < m.triangle_count(); ++t) ++(m.patch[static_cast<size_t>(t)] == 1 ? needle : floor);
  EXPECT_EQ(report.thin_faces_unrefined, 1);
  EXPECT_GE(needle, 1);
  EXPECT_LE(needle, 16);
  EXPECT_GT(floor, 100);  // 1 / 0.1^2 squares' worth: refined as ever
}

TEST(Mesh, ANearlyTouchingLineLeavesItsFaceUnrefinedInsteadOfCuttingItThatFine) {
  // A 4 x 4 floor and a panel standing on it, d from the floor's edge and
  // parallel to it: its foot is a contact line on the floor. At d = 1e-5
  // the mesher cut the floor's edge and the line about d apart (10^5
  // points) and the next round took minutes to insert them; the floor is
  // now left as the triangulation of its outline and lines, and counted.
  // At d = 1e-3 (10^3 points along the panel) it is refined as before.
  auto scene = [](double d) {
    std::vector<RawFace> faces(2);
    faces[0].name = "floor";
    faces[0].points = {{0, 0, 0}, {0, 0, 4}, {4, 0, 4}, {4, 0, 0}};
    faces[1].name = "panel";
    faces[1].points = {{d, 0, 1.5}, {d, 1, 1.5}, {d, 1, 2.5}, {d, 0, 2.5}};
    faces[0].material = faces[1].material = 0;
    return build_scene(faces, {test::material("white", Rgb(0.5), Rgb(1.0))}, "panel");
  };
  for (const double d : {1e-5, 1e-3}) {
    const Scene s = scene(d);
    MeshReport report;
    const Mesh m = mesh_scene(s, {}, &report);
    EXPECT_EQ(report.thin_faces_unrefined, d < 1e-4 ? 1 : 0) << d;
    // Said, naming the face and the vertex (the panel's foot at z 1.5 or 2.5).
    ASSERT_EQ(report.warnings.size(), d < 1e-4 ? 1u : 0u) << d;
    if (d < 1e-4) {
      EXPECT_TRUE(test::mentions(report.warnings[0], {"face 'floor'", "vertex at (1e-05, 0, ", "lies 1e-05"}));
    }
    EXPECT_GT(report.contact_segments, 0) << d;
    int floor = 0;
    for (int t = 0; t < m.triangle_count(); ++t) floor += m.patch[static_cast<size_t>(t)] == 0;
    if (d < 1e-4) {
      EXPECT_LT(floor, 100) << d;
    } else {
      EXPECT_GT(floor, 1000) << d;  // cut about d apart along the panel: 10^3 points
    }
    const std::vector<double> area = test::patch_areas(s, m);
    EXPECT_NEAR(area[0], 16.0, 1e-9) << d;
    EXPECT_NEAR(area[1], 1.0, 1e-9) << d;
  }
}

// A carpet [-s, s]^2 (grey) 1 mm above the floor of test::room_with.
static RawFace carpet(double s) {
  RawFace c;
  c.name = "carpet";
  c.material = 1;
  c.points = {{-s, 1e-3, -s}, {-s, 1e-3, s}, {s, 1e-3, s}, {s, 1e-3, -s}};
  return c;
}

TEST(Mesh, AWallBesideACarpetAMillimetreUpIsLeftUncutUnlessItsElementsAreTheUnknowns) {
  // A carpet 1 mm above the floor of a 4 m room, touching the four walls:
  // its edge is a contact line 1 mm up each wall, joined to the wall's
  // sides, and the mesher cut it and the wall's foot about 1 mm apart
  // (about 4,000 points each, 38,501 elements; the hierarchical solve then
  // stopped at its memory limit). Refining it past 15 x the points its
  // size and edges ask for, each wall is now left as the triangulation of
  // its outline and lines, and said; the matrix method's option cuts it as
  // before.
  const Scene s = test::room_with({carpet(2.0)});
  for (const bool refine : {false, true}) {
    MeshingOptions o;
    o.discontinuity = DiscontinuityMode::contacts;
    o.refine_narrow_strips = refine;
    MeshReport report;
    const Mesh m = mesh_scene(s, o, &report);
    EXPECT_EQ(report.thin_faces_unrefined, refine ? 0 : 4);
    ASSERT_EQ(report.warnings.size(), refine ? 0u : 4u);
    for (const std::string& w : report.warnings)
      EXPECT_TRUE(test::mentions(w, {"face 'room'", "--max-edge", "made more than", "15 x", "+ 100"}));
    std::vector<int> count(s.patches.size(), 0);
    for (int t = 0; t < m.triangle_count(); ++t) ++count[static_cast<size_t>(m.patch[static_cast<size_t>(t)])];
    for (int wall = 0; wall < 4; ++wall) {
      // Cut about 1 mm apart along its 4 m foot, or its outline's points
      // (those the floor and ceiling share with it, about --max-edge apart).
      if (refine)
        EXPECT_GT(count[static_cast<size_t>(wall)], 4000) << wall;
      else
        EXPECT_LT(count[static_cast<size_t>(wall)], 100) << wall;
    }
    const std::vector<double> area = test::patch_areas(s, m);
    for (size_t p = 0; p < area.size(); ++p) EXPECT_NEAR(area[p], s.patch_area(static_cast<int>(p)), 1e-9) << p;
  }
}

TEST(Mesh, AFloorUnderACarpetAMillimetreShortOfTheWallsIsLeftUncut) {
  // The same carpet 1 mm short of the walls: its outline, 1 mm above the
  // floor, is drawn on the floor as overhang lines 1 mm inside the floor's
  // edge, and the floor was cut about 1 mm apart along them (39,647
  // elements; the hierarchical run was still going after 300 s at 11.5 GB).
  const Scene s = test::room_with({carpet(2.0 - 1e-3)});
  const int floor = test::patch_named(s, "floor");
  ASSERT_GE(floor, 0);
  MeshingOptions o;
  o.discontinuity = DiscontinuityMode::contacts;
  MeshReport report;
  const Mesh m = mesh_scene(s, o, &report);
  EXPECT_EQ(report.thin_faces_unrefined, 1);
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_TRUE(test::mentions(report.warnings[0], {"face 'floor'", "--max-edge", "made more than"}));
  int triangles = 0;
  for (int t = 0; t < m.triangle_count(); ++t) triangles += m.patch[static_cast<size_t>(t)] == floor;
  EXPECT_LT(triangles, 200);
  const std::vector<double> area = test::patch_areas(s, m);
  EXPECT_NEAR(area[static_cast<size_t>(floor)], 16.0, 1e-9);
}

TEST(Mesh, AVertexNextToAThinHolesEdgeDoesNotCrashTheMesher) {
  // A 2 x 2 floor with a triangle 1 long and 1e-8 high lying in it (cut
  // out as a hole) and a panel standing on a vertex 1e-10 from that
  // hole's long edge: CGAL's mesher dereferenced a null face refining
  // the floor (a segmentation fault). The floor is left unrefined.
  std::vector<RawFace> faces(3);
  faces[0].name = "floor";
  faces[0].points = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}};
  faces[1].name = "strip";
  faces[1].points = {{0.5, 0.5, 0}, {1.5, 0.5, 0}, {1, 0.5 + 1e-8, 0}};
  faces[2].name = "panel";
  faces[2].points = {{1, 0.5 + 1e-10, 0}, {1.2, 0.5 + 1e-10, 1}, {1, 0.5 + 1e-10, 1}};
  for (RawFace& f : faces) f.material = 0;
  const Scene s = build_scene(faces, {test::material("white", Rgb(0.5), Rgb(1.0))}, "strip");
  ASSERT_EQ(s.report.faces_cut_out, 1);
  MeshReport report;
  const Mesh m = mesh_scene(s, {}, &report);
  EXPECT_EQ(report.thin_faces_unrefined, 2);  // the strip (a sliver) and the floor
  ASSERT_EQ(report.warnings.size(), 1u);       // the floor's hole; a sliver face is only counted
  EXPECT_TRUE(test::contains(report.warnings[0], "face 'floor': a hole ")) << report.warnings[0];
  const std::vector<double> area = test::patch_areas(s, m);
  EXPECT_NEAR(area[0] + area[1], 4.0, 1e-12);
  EXPECT_NEAR(area[2], 0.1, 1e-12);
}

TEST(Mesh, ALineChainedThroughABoundaryPointKeepsTheSliverBetweenThem) {
  // A 1 x 1 panel standing on a lit floor, one foot 1e-10 from the
  // floor's edge and the rest 1e-5 off it: a quad out of plane by 1e-5,
  // split along its diagonal. One half's shadow line on the other runs
  // from the foot to 7e-6 below the far corner, and passes 5.5e-7 (1e-7 of
  // the scene's diagonal) from a point on the diagonal, so it is chained
  // through that point. The sliver between the chained line and the
  // diagonal counted as outside (the line's piece off the diagonal was
  // taken for a boundary): the half came out 3e-6 short of its 0.5 (found
  // by fuzzing).
  std::vector<RawFace> faces(2);
  faces[0].name = "floor";
  faces[0].points = {{0, 0, 0}, {0, 0, 4}, {4, 0, 4}, {4, 0, 0}};
  faces[1].name = "panel";
  faces[1].points = {{1e-10, 0, 1.5}, {1e-5, 1, 1.5}, {1e-5, 1, 2.5}, {1e-5, 0, 2.5}};
  for (RawFace& f : faces) f.material = 0;
  const Scene s = build_scene(faces, {test::material("lamp", Rgb(0.5), Rgb(1.0))}, "panel");
  ASSERT_EQ(s.patches.size(), 3u);  // the floor and the panel's two halves
  MeshReport report;
  const Mesh m = mesh_scene(s, {}, &report);
  ASSERT_GT(report.shadow_segments, 0);
  const std::vector<double> area = test::patch_areas(s, m);
  for (size_t p = 0; p < s.patches.size(); ++p)
    EXPECT_NEAR(area[p] / s.patch_area(static_cast<int>(p)), 1.0, 1e-9) << p;  // the foot joins the floor's edge
}

TEST(Mesh, ALineEndingNextToAVertexDoesNotCrashTheMesher) {
  // The Cornell box with the light's corner (213, 548.8, 332) raised by
  // 0.1: the ceiling beside it tilts, and the flat ceiling behind it,
  // within the overhang gap of that tilted face, is clipped to a 2e-4
  // long line across its corner, ending 1e-4 (1e-7 of the diagonal) from
  // the corner. CGAL's mesher dereferenced a null face refining it (a
  // segmentation fault, found by fuzzing); the end is now the corner.
  const test::TempDir dir;
  const std::string obj = test::write_edited_obj(
      kData + "/cornell_box/cornell_box", dir.path(),
      [](const std::string& line, int) { return line == "v 213 548.8 332" ? std::string("v 213 548.9 332") : line; });
  const Scene s = read_obj_scene(obj);
  MeshingOptions o;
  o.max_elements = 2e4;
  MeshReport report;
  const Mesh m = mesh_scene(s, resolve_meshing_options(s, o), &report);
  const std::vector<double> area = test::patch_areas(s, m);
  for (size_t p = 0; p < s.patches.size(); ++p)
    EXPECT_NEAR(area[p] / s.patch_area(static_cast<int>(p)), 1.0, 1e-9) << s.patches[p].name;
}

TEST(Mesh, ATinyLinePieceLeavesItsFaceUnrefinedInsteadOfCrashingTheMesher) {
  // A floor quad bent 1 mm up at one corner (split in two triangles), a
  // rug 1 mm up sharing that corner, and a panel 2 mm up tilted by 1e-4
  // over both: the panel's overhang on one floor triangle is clipped by
  // that triangle's diagonal into two pieces 2e-6 long (4e-7 of the
  // scene's size). CGAL's mesher dereferenced a null face refining around
  // them (a segmentation fault, found by fuzzing); the face is now left as
  // the triangulation of its outline and lines, with a warning.
  std::vector<RawFace> faces(4);
  faces[0].name = "floor";
  faces[0].points = {{0, 0, 0}, {1, 0.001, 3}, {4, 0, 4}, {4, 0, 0}};
  faces[1].name = "rug";
  faces[1].points = {{1, 0.001, 1}, {1, 0.001, 3}, {3, 0.001, 3}, {3, 0.001, 1}};
  faces[2].name = "tilted";
  faces[2].points = {{1.5, 0.002, 1.5}, {1.5, 0.002, 2.5}, {2.5, 0.0021, 2.5}, {2.5, 0.0021, 1.5}};
  faces[3].name = "slab_side";
  faces[3].points = {{0.2, 0, 0.2}, {0.8, 0, 0.2}, {0.8, 0.001, 0.2}, {0.2, 0.001, 0.2}};
  for (RawFace& f : faces) f.material = 0;
  const Scene s = build_scene(faces, {test::material("lamp", Rgb(0.5), Rgb(1.0))}, "tiny_piece");
  ASSERT_EQ(s.patches.size(), 5u);  // the floor in two triangles
  MeshingOptions o;
  o.max_elements = 2e4;
  MeshReport report;
  const Mesh m = mesh_scene(s, resolve_meshing_options(s, o), &report);
  EXPECT_TRUE(std::any_of(report.warnings.begin(), report.warnings.end(), [](const std::string& w) {
    return test::contains(w, "discontinuity line") && test::contains(w, "under 1e-06");
  }));
  const std::vector<double> area = test::patch_areas(s, m);
  for (size_t p = 0; p < s.patches.size(); ++p)
    EXPECT_NEAR(area[p] / s.patch_area(static_cast<int>(p)), 1.0, 1e-9) << s.patches[p].name;
}

TEST(Mesh, SameInputSameMesh) {
  const Scene s = read_obj_scene(kData + "/cornell_box/cornell_box.obj");
  const Mesh a = mesh_scene(s, {});
  const Mesh b = mesh_scene(s, {});
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.positions, b.positions);
}

TEST(Mesh, AScaledOrMovedSceneHasTheSameMesh) {
  // CGAL sees each patch in units of its own size, snapped (mesher_cgal's
  // Frame): the Cornell box, its shadow lines and the cocircular corners of
  // its rectangles included, meshes into the same triangles scaled by 1e-4
  // or 1e4 or moved by 1e6, at the same points up to their rounding.
  const Scene s = read_obj_scene(kData + "/cornell_box/cornell_box.obj");
  const Mesh a = mesh_scene(s, {});
  const double diagonal = s.diagonal();
  const std::vector<std::pair<double, double>> maps = {{1e-4, 0.0}, {1e4, 0.0}, {3.0, 0.0}, {1.0, 1e6}};
  for (const auto& map : maps) {
    const double scale = map.first, shift = map.second;  // named: clang 14 cannot capture structured bindings
    const Scene moved = test::transformed(s, [&](const Vec3& v) { return scale * v + Vec3(shift); });
    const Mesh b = mesh_scene(moved, {});
    ASSERT_EQ(a.triangles, b.triangles) << "scaled by " << scale << ", moved by " << shift;
    ASSERT_EQ(a.positions.size(), b.positions.size());
    double worst = 0.0;
    for (size_t i = 0; i < a.positions.size(); ++i)
      worst = std::max(worst, glm::length((b.positions[i] - Vec3(shift)) / scale - a.positions[i]));
    EXPECT_LT(worst, 1e-11 * diagonal) << "scaled by " << scale << ", moved by " << shift;
  }
}

TEST(Mesh, AZeroAreaTriangleFarFromTheOriginIsZeroArea) {
  // A T-vertex closed by a zero-area triangle: the long edge's midpoint,
  // rounded. A million units from the origin the rounding (1e-10) is more
  // than 1e-12 of a 5-unit edge, and such a triangle was taken for a real
  // one (a source of the gather with an area of rounding). A triangle as
  // thin as 1e-6 of its edge keeps its area.
  int checked = 0;
  for (const double shift : {0.0, 1e3, 1e6})
    for (int k = 0; k < 50; ++k) {
      Mesh m;
      const Vec3 a = Vec3(shift) + Vec3(0.1 * k, 0.37 * k, 0.77), b = a + Vec3(3.3, 1.9 + 0.01 * k, 0.7);
      const Vec3 c = 0.5 * (a + b);
      const Vec3 off = 1e-6 * glm::length(b - a) * glm::normalize(glm::cross(b - a, Vec3(0, 0, 1)));
      m.positions = {a, c, b, c + off};
      m.triangles = {{0, 1, 2}, {0, 3, 2}};
      m.patch = {0, 0};
      EXPECT_TRUE(m.zero_area(0)) << "moved by " << shift << ", " << k;
      EXPECT_FALSE(m.zero_area(1)) << "moved by " << shift << ", " << k;
      ++checked;
    }
  EXPECT_EQ(checked, 150);
}

TEST(Quality, EquilateralTriangle) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0.5, std::sqrt(3.0) / 2, 0}};
  m.triangles = {{0, 1, 2}};
  m.patch = {0};
  const TriangleQuality q = compute_quality(m);
  EXPECT_NEAR(q.min_angle[0], 60.0, 1e-12);
  EXPECT_NEAR(q.aspect_ratio[0], 1.0, 1e-12);
}

TEST(Mesh, AFaceFarFromTheOriginForItsSizeIsToldToMoveNearer) {
  // The Cornell box moved 1e12 mm along x: its faces, 1e9 times their
  // size from the origin, keep too few digits to triangulate, and the
  // error says so rather than only suspecting the face's outline.
  std::string text;
  {
    std::ifstream in(kData + "/cornell_box/cornell_box.obj");
    std::string line;
    while (std::getline(in, line)) {
      if (line.rfind("v ", 0) == 0) {
        std::istringstream v(line.substr(2));
        double x = 0, y = 0, z = 0;
        v >> x >> y >> z;
        std::ostringstream out;
        out.precision(17);
        out << "v " << x + 1e12 << ' ' << y << ' ' << z;
        line = out.str();
      }
      text += line + "\n";
    }
  }
  const test::TempDir dir;
  std::filesystem::copy_file(kData + "/cornell_box/cornell_box.mtl", dir / "cornell_box.mtl");
  std::ofstream(dir / "far.obj") << text;
  const Scene s = read_obj_scene((dir / "far.obj").string());
  const test::Thrown t = test::thrown<GeometryError>([&] { mesh_scene(s, {}); });
  EXPECT_TRUE(t.says({"far.obj:", "times its size", "nearer the origin"}));
}

namespace {
// A rectangle [x0, x1] x [z0, z1] in the plane y, facing up (+y) or down,
// defined at line `line` of "rug.obj".
RawFace flat_rect(const std::string& name, double x0, double z0, double x1, double z1, double y, bool up,
                  int line) {
  RawFace f;
  f.name = name;
  f.material = 0;
  f.points = {{x0, y, z0}, {x0, y, z1}, {x1, y, z1}, {x1, y, z0}};
  if (!up) std::reverse(f.points.begin(), f.points.end());
  f.file = "rug.obj";
  f.line = line;
  return f;
}

// The error a scene of these faces gets, from build_scene (convex faces) or
// from meshing (the others).
test::Thrown overlap_error(const std::vector<RawFace>& faces) {
  MeshingOptions o;
  o.discontinuity = DiscontinuityMode::contacts;
  return test::thrown<InputError>(
      [&] { mesh_scene(build_scene(faces, {test::material("white", Rgb(0.5))}, "rug.obj"), o); });
}
}  // namespace

TEST(Mesh, FacesOverlappingInOnePlaneFacingTheSameWayAreRefused) {
  // A rug over the floor's edge: which of the two is lit is not defined
  // and the light counts the area twice. Refused, naming both faces and a
  // point of the overlap: with convex outlines (tested whole), an L-shaped
  // floor (tested through its triangles), and a rug over the edge of a
  // floor's hole. (A rug wholly inside the floor is cut out of it instead:
  // Scene.AFaceLyingInAnotherOfItsPlaneIsCutOutOfIt.)
  test::Thrown t = overlap_error({flat_rect("floor", 0, 0, 4, 4, 0, true, 10), flat_rect("rug", 3, 1, 5, 2, 0, true, 20)});
  EXPECT_TRUE(t.says({"rug.obj:20: face 'rug'", "face 'floor' (rug.obj:10)", "one plane", "overlap"}));
  EXPECT_TRUE(t.says({"(around (3.5, 0, 1.5))"}));

  RawFace ell = flat_rect("floor", 0, 0, 4, 4, 0, true, 10);
  ell.points = {{0, 0, 0}, {0, 0, 4}, {2, 0, 4}, {2, 0, 2}, {4, 0, 2}, {4, 0, 0}};
  t = overlap_error({ell, flat_rect("rug", 1.5, 1.5, 3, 3, 0, true, 20)});
  EXPECT_TRUE(t.says({"face 'rug'", "face 'floor'", "one plane", "same way", "overlap"}));

  RawFace holed = flat_rect("floor", 0, 0, 4, 4, 0, true, 10);
  holed.holes = {{{1, 0, 1}, {1, 0, 2}, {2, 0, 2}, {2, 0, 1}}};
  t = overlap_error({holed, flat_rect("rug", 0.5, 1.25, 1.5, 1.75, 0, true, 20)});
  EXPECT_TRUE(t.says({"face 'rug'", "face 'floor'", "overlap"}));

  // A ring of eight tiles around a bare square: cut as one, the floor would
  // have an island in its hole, which a face cannot hold (a rug of tiles
  // without one is cut: Scene.FacesJoinedAlongEdgesInAnotherOfTheirPlaneAreCutOutAsOneHole).
  // The first tile is cut, and the next one, along its edge, is refused
  // saying why.
  std::vector<RawFace> ring = {flat_rect("floor", 0, 0, 4, 4, 0, true, 10)};
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k)
      if (i != 1 || k != 1)
        ring.push_back(flat_rect("tile", 0.5 + i, 0.5 + k, 1.5 + i, 1.5 + k, 0, true, 20 + 3 * i + k));
  t = overlap_error(ring);
  EXPECT_TRUE(t.says({"face 'floor' (rug.obj:10)", "touches", "face 'tile' (rug.obj:2", "ring of tiles"}));

  // Two tiles meeting only at a corner: not joined, and the second is
  // refused naming the first.
  t = overlap_error({flat_rect("floor", 0, 0, 4, 4, 0, true, 10), flat_rect("a", 1, 1, 2, 2, 0, true, 20),
                     flat_rect("b", 2, 2, 3, 3, 0, true, 21)});
  EXPECT_TRUE(t.says({"rug.obj:21: face 'b'", "face 'floor' (rug.obj:10)", "touches", "face 'a' (rug.obj:20)",
                      "whole edges"}));
}

TEST(Mesh, FacesThatOnlyMeetInOnePlaneOrFaceOppositeWaysAreKept) {
  // Two floor halves along an edge, a tile at the corner, a rug filling a
  // hole exactly, a block's bottom on the floor (facing down), and a rug
  // lifted 1e-3 (more than 1e-5 of the scene size): no overlap to refuse.
  RawFace holed = flat_rect("floor_a", 0, 0, 2, 4, 0, true, 10);
  holed.holes = {{{0.5, 0, 1}, {0.5, 0, 2}, {1.5, 0, 2}, {1.5, 0, 1}}};
  const std::vector<RawFace> faces = {holed,
                                      flat_rect("floor_b", 2, 0, 4, 4, 0, true, 11),
                                      flat_rect("tile", 4, 4, 5, 5, 0, true, 12),
                                      flat_rect("plug", 0.5, 1, 1.5, 2, 0, true, 13),
                                      flat_rect("block_bottom", 2.5, 2.5, 3.5, 3.5, 0, false, 14),
                                      flat_rect("lifted_rug", 2.5, 0.5, 3.5, 1.5, 1e-3, true, 15)};
  const Scene s = build_scene(faces, {test::material("white", Rgb(0.5))}, "rug.obj");
  MeshingOptions o;
  o.discontinuity = DiscontinuityMode::contacts;
  const Mesh m = mesh_scene(s, o);
  const std::vector<double> area = test::patch_areas(s, m);
  EXPECT_NEAR(area[0], 7.0, 1e-12);
  EXPECT_NEAR(area[3], 1.0, 1e-12);
}
