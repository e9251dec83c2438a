// The layout: which patches share a texel grid, each grid's frame and size,
// what of each texel the patches cover, where walls stand on the grid, the
// texels a contact line cuts into parts, and which texel holds each texel's
// value (see Pixmap). It works on the coarse mesh cut along the contact
// lines, whose triangles lie wholly inside or outside every closed object
// standing on a patch, so that coverage and cuts follow the outlines of the
// objects exactly; the shooters are made from the owners in shooters.cpp.

#include "radiosity/pixmap/layout.h"

#include "radmesh/errors.h"
#include "radiosity/pixmap/hemicube.h"
#include "radiosity/pixmap/texel_geometry.h"
#include "radiosity/transport/transport.h"
#include "radiosity/transport/visibility.h"

#include <cstdint>
#include <sstream>
#include <tuple>
#include <unordered_map>

namespace radmesh {

namespace internal {

namespace {

// Coplanar patches of one material sharing a vertex share a pixmap.
void group_patches(const Scene& scene, PixmapLayout& L) {
  const int np = static_cast<int>(scene.patches.size());
  const double tol = 1e-9 * scene.diagonal();
  UnionFind uf(np);
  std::vector<std::vector<int>> at_vertex(scene.vertices.size());
  for (int p = 0; p < np; ++p) {
    const Patch& P = scene.patches[p];
    for (int v : P.outer) at_vertex[v].push_back(p);
    for (const auto& h : P.holes)
      for (int v : h) at_vertex[v].push_back(p);
  }
  auto coplanar = [&](int a, int b) {
    const Patch& A = scene.patches[a];
    const Patch& B = scene.patches[b];
    if (A.material != B.material || glm::length(A.normal - B.normal) > 1e-9) return false;
    const Vec3& o = scene.vertices[A.outer[0]];
    for (int v : B.outer)
      if (std::abs(glm::dot(scene.vertices[v] - o, A.normal)) > tol) return false;
    return true;
  };
  for (auto& list : at_vertex) {
    std::vector<int> heads;
    for (int p : list) {
      bool joined = false;
      for (int h : heads)
        if (coplanar(h, p)) {
          uf.unite(h, p);
          joined = true;
          break;
        }
      if (!joined) heads.push_back(p);
    }
  }
  L.pixmap_of_patch.assign(static_cast<size_t>(np), -1);
  for (int p = 0; p < np; ++p) {
    const int r = uf.find(p);
    if (L.pixmap_of_patch[r] < 0) {
      L.pixmap_of_patch[r] = static_cast<int>(L.pixmaps.size());
      L.pixmaps.emplace_back();
    }
    L.pixmap_of_patch[p] = L.pixmap_of_patch[r];
    L.pixmaps[L.pixmap_of_patch[p]].patches.push_back(p);
  }
}

// Triangles inside closed objects (inside_closed_object tests points near
// the corners as well as the centroid: a one-sided table top over a floor,
// covering a coarse triangle's centroid, must not leave the floor out).
void mark_enclosed(const Scene& scene, const Mesh& coarse, const Visibility* vis, PixmapLayout& L) {
  L.enclosed.assign(static_cast<size_t>(coarse.triangle_count()), 0);
  if (vis)
    for (int t = 0; t < coarse.triangle_count(); ++t) {
      const auto& c = coarse.triangles[static_cast<size_t>(t)];
      L.enclosed[t] =
          inside_closed_object(scene, *vis, {coarse.positions[c[0]], coarse.positions[c[1]], coarse.positions[c[2]]},
                               coarse.patch[t])
              ? 1
              : 0;
    }
}

// The contact lines inside each pixmap's patches (feature edges of the
// coarse mesh, found by the triangles that have them), in world points
// until the pixmap's frame is known.
std::vector<std::vector<std::pair<Vec3, Vec3>>> contact_lines(const Mesh& coarse, const PixmapLayout& L) {
  std::vector<std::vector<std::pair<Vec3, Vec3>>> contact_world(L.pixmaps.size());
  if (!coarse.feature_edges.empty()) {
    std::unordered_map<uint64_t, int> pixmap_of_edge;
    for (int t = 0; t < coarse.triangle_count(); ++t)
      for (int c = 0; c < 3; ++c)
        pixmap_of_edge.emplace(undirected_edge_key(coarse.triangles[t][c], coarse.triangles[t][(c + 1) % 3]),
                               L.pixmap_of_patch[coarse.patch[t]]);
    for (const auto& e : coarse.feature_edges)
      if (const auto it = pixmap_of_edge.find(undirected_edge_key(e[0], e[1])); it != pixmap_of_edge.end())
        contact_world[static_cast<size_t>(it->second)].push_back({coarse.positions[e[0]], coarse.positions[e[1]]});
  }
  return contact_world;
}

// Per edge of the coarse mesh, the pixmap of its triangles, or -1 where
// triangles of two pixmaps share it: a wall stands on it.
std::unordered_map<uint64_t, int> pixmaps_of_edges(const Mesh& coarse, const PixmapLayout& L) {
  std::unordered_map<uint64_t, int> pixmap_of_edge;  // -1: a wall stands on it
  for (int t = 0; t < coarse.triangle_count(); ++t)
    for (int c = 0; c < 3; ++c) {
      const int k = L.pixmap_of_patch[coarse.patch[t]];
      auto [it, fresh] = pixmap_of_edge.try_emplace(
          undirected_edge_key(coarse.triangles[t][c], coarse.triangles[t][(c + 1) % 3]), k);
      if (!fresh && it->second != k) it->second = -1;
    }
  return pixmap_of_edge;
}

// Pixmap pm's frame (its normal, the tangent axes and the origin at the
// corner of its patches' bounding box) and its grid: `texel_size`,
// stretched to fit the extent exactly and coarsened to stay within
// `max_texels`.
void set_frame(Pixmap& pm, const Scene& scene, double texel_size, long long max_texels) {
  const Patch& first = scene.patches[pm.patches[0]];
  pm.material = first.material;
  pm.normal = first.normal;
  pm.u = tangent_of(pm.normal);
  pm.v = glm::cross(pm.normal, pm.u);
  double u0 = INFINITY, u1 = -INFINITY, v0 = INFINITY, v1 = -INFINITY;
  for (int p : pm.patches)
    for (int vi : scene.patches[p].outer) {
      const Vec3& x = scene.vertices[vi];
      u0 = std::min(u0, glm::dot(x, pm.u));
      u1 = std::max(u1, glm::dot(x, pm.u));
      v0 = std::min(v0, glm::dot(x, pm.v));
      v1 = std::max(v1, glm::dot(x, pm.v));
    }
  const double offset = glm::dot(scene.vertices[first.outer[0]], pm.normal);
  pm.origin = u0 * pm.u + v0 * pm.v + offset * pm.normal;
  const double eu = u1 - u0, ev = v1 - v0;
  double size = texel_size;
  auto cells = [&](double extent) { return std::max(1.0, std::ceil(extent / size - 1e-9)); };
  if (cells(eu) * cells(ev) > static_cast<double>(max_texels))
    size *= std::sqrt(cells(eu) * cells(ev) / static_cast<double>(max_texels)) * (1.0 + 1e-12);
  while (cells(eu) * cells(ev) > static_cast<double>(max_texels)) size *= 1.01;
  pm.width = static_cast<int>(cells(eu));
  pm.height = static_cast<int>(cells(ev));
  pm.texel_u = eu > 0.0 ? eu / pm.width : size;
  pm.texel_v = ev > 0.0 ? ev / pm.height : size;
}

[[noreturn]] void refuse_memory(const Scene& scene, double memory_bytes) {
  std::ostringstream m;
  m.precision(3);
  m << scene.source << ": the texels (their grids, display mesh and files) need more than the "
    << memory_bytes / (1024.0 * 1024.0 * 1024.0)
    << " GiB allowed; use a larger texel_size (the texel count falls with its square) or raise max_memory";
  throw NumericalError(m.str(), {"texel_size", "max_memory"});
}

// The piece of a coarse triangle inside one texel.
struct Piece {
  int texel, triangle;
  double area;
  Vec3 moment;  // area x centroid
  bool operator<(const Piece& o) const { return std::tie(texel, triangle) < std::tie(o.texel, o.triangle); }
};

// A part of a cut texel given to a neighbour.
struct Move {
  int from, to;
  double area;
  Vec3 moment;
};

// The grid of one pixmap, phase by phase: its coverage, its wall feet, the
// texels cut into parts and where the parts go, and the owners.
struct GridBuilder {
  const Mesh& coarse;
  const std::vector<int>& triangles;  // the pixmap's coarse triangles
  const std::unordered_map<uint64_t, int>& pixmap_of_edge;
  Pixmap& pm;
  std::vector<Piece> pieces;
  std::vector<Move> moves;
  std::vector<char> is_cut;

  void cover(const std::vector<char>& enclosed, double& enclosed_area);
  void find_wall_feet();
  bool joined(int a, int b) const;
  void find_cuts();
  std::pair<std::vector<Piece>::const_iterator, std::vector<Piece>::const_iterator> pieces_of(int texel) const;
  double part_area(int texel, const std::vector<int>& tris, Vec3* moment) const;
  int neighbour_for(int texel, const std::vector<int>& part, double cell_area) const;
  void move_parts();
  void set_owners(long long& covered);
};

// Coverage from the pieces of the triangles in each texel, less the
// triangles inside a closed object standing on the patch (a block on a
// floor): light never reaches there, and a shooter placed there would
// shoot into the object's back faces. The coarse mesh is cut along the
// contact lines, so each triangle is wholly inside or outside.
void GridBuilder::cover(const std::vector<char>& enclosed, double& enclosed_area) {
  pm.coverage.assign(static_cast<size_t>(pm.texels()), 0.0);
  pm.centroid.assign(static_cast<size_t>(pm.texels()), Vec3(0.0));
  for (int t : triangles) {
    if (enclosed[t]) {
      enclosed_area += coarse.area(t);
      continue;
    }
    St tri[3];
    for (int c = 0; c < 3; ++c) tri[c] = st_of(pm, coarse.positions[coarse.triangles[t][c]]);
    for_each_piece(pm, tri, [&](int i, int j, const St* poly, int n) {
      double a;
      St c;
      area_centroid(poly, n, a, c);
      a = std::abs(a) * pm.texel_u * pm.texel_v;
      const int idx = j * pm.width + i;
      pm.coverage[idx] += a;
      pm.centroid[idx] += a * point_of(pm, c.s, c.t);
      if (a > 0.0) pieces.push_back({idx, t, a, a * point_of(pm, c.s, c.t)});
    });
  }
}

// The wall feet and the texels they touch: edges another pixmap's
// triangles share, with this one's on both sides (the edges all round,
// where the walls around meet it, have nothing beyond them to keep
// light from).
void GridBuilder::find_wall_feet() {
  std::unordered_map<uint64_t, int> sides;
  for (int t : triangles)
    for (int c = 0; c < 3; ++c) {
      const uint64_t key = undirected_edge_key(coarse.triangles[t][c], coarse.triangles[t][(c + 1) % 3]);
      if (pixmap_of_edge.at(key) < 0) ++sides[key];
    }
  for (int t : triangles)
    for (int c = 0; c < 3; ++c) {
      const int u = coarse.triangles[t][c], v = coarse.triangles[t][(c + 1) % 3];
      const auto it = sides.find(undirected_edge_key(u, v));
      if (it == sides.end() || it->second < 2) continue;
      it->second = 0;  // once
      if (pm.wall_foot.empty()) pm.wall_foot.assign(static_cast<size_t>(pm.texels()), 0);
      const St a = st_of(pm, coarse.positions[u]), b = st_of(pm, coarse.positions[v]);
      const int foot = static_cast<int>(pm.feet.size());
      pm.feet.push_back({a.s, a.t, b.s, b.t});
      for_each_texel_on(pm, a, b, [&](int texel) {
        pm.wall_foot[static_cast<size_t>(texel)] = 1;
        pm.foot_at.emplace_back(texel, foot);
      });
    }
  std::sort(pm.foot_at.begin(), pm.foot_at.end());
}

// Triangles of one pixmap joined across an edge no other surface stands
// on (a wall's foot is an edge of the wall's triangles too; an overhang's
// or a shadow's line is not): within one texel, pieces of triangles so
// joined are one part of it.
bool GridBuilder::joined(int a, int b) const {
  for (int c = 0; c < 3; ++c) {
    const int u = coarse.triangles[a][c], v = coarse.triangles[a][(c + 1) % 3];
    const auto& tb = coarse.triangles[b];
    const bool shared = (u == tb[0] || u == tb[1] || u == tb[2]) && (v == tb[0] || v == tb[1] || v == tb[2]);
    if (shared && pixmap_of_edge.at(undirected_edge_key(u, v)) >= 0) return true;
  }
  return false;
}

// Texels cut into parts: pieces of triangles not joined (a thin wall
// stands across the texel: its footprint is a gap between them, or it
// stands on the line between them). One value and one centroid for both
// sides put the shooter inside the wall, or on one side shooting the
// other side's light: move_parts gives all parts but the largest away.
void GridBuilder::find_cuts() {
  std::sort(pieces.begin(), pieces.end());
  is_cut.assign(pieces.empty() ? 0 : static_cast<size_t>(pm.texels()), 0);
  for (size_t a = 0; a < pieces.size();) {
    size_t b = a;
    while (b < pieces.size() && pieces[b].texel == pieces[a].texel) ++b;
    if (b - a > 1) {
      UnionFind uf(static_cast<int>(b - a));
      for (size_t x = a; x < b; ++x)
        for (size_t y = x + 1; y < b; ++y)
          if (joined(pieces[x].triangle, pieces[y].triangle)) uf.unite(static_cast<int>(x - a), static_cast<int>(y - a));
      std::vector<std::vector<int>> parts;
      std::vector<int> part_of(b - a, -1);
      for (size_t x = a; x < b; ++x) {
        const int r = uf.find(static_cast<int>(x - a));
        if (part_of[r] < 0) {
          part_of[r] = static_cast<int>(parts.size());
          parts.emplace_back();
        }
        parts[part_of[r]].push_back(static_cast<int>(x));
      }
      if (parts.size() > 1) {
        Pixmap::Cut cut;
        cut.texel = pieces[a].texel;
        for (const auto& part : parts) {
          cut.triangles.emplace_back();
          for (int x : part) cut.triangles.back().push_back(pieces[x].triangle);
        }
        cut.owners.assign(parts.size(), -1);  // -1: the texel's owner (set_owners)
        is_cut[cut.texel] = 1;
        pm.cuts.push_back(std::move(cut));
      }
    }
    a = b;
  }
}

std::pair<std::vector<Piece>::const_iterator, std::vector<Piece>::const_iterator> GridBuilder::pieces_of(
    int texel) const {
  return std::equal_range(pieces.begin(), pieces.end(), Piece{texel, -1, 0.0, Vec3(0.0)},
                          [](const Piece& x, const Piece& y) { return x.texel < y.texel; });
}

// The area in `texel` of the pieces of triangles `tris`, adding their
// moment to *moment when not null.
double GridBuilder::part_area(int texel, const std::vector<int>& tris, Vec3* moment) const {
  double area = 0.0;
  const auto [lo, hi] = pieces_of(texel);
  for (auto it = lo; it != hi; ++it)
    if (std::find(tris.begin(), tris.end(), it->triangle) != tris.end()) {
      area += it->area;
      if (moment) *moment += it->moment;
    }
  return area;
}

// The most covered neighbour of cut `texel` holding a piece of one of the
// part's triangles (on the part's side), at least a quarter covered and not
// cut itself; -1 when none.
int GridBuilder::neighbour_for(int texel, const std::vector<int>& part, double cell_area) const {
  const int i = texel % pm.width, j = texel / pm.width;
  int best = -1;
  for (int dj = -1; dj <= 1; ++dj)
    for (int di = -1; di <= 1; ++di) {
      const int x = i + di, y = j + dj;
      if ((di == 0 && dj == 0) || x < 0 || y < 0 || x >= pm.width || y >= pm.height) continue;
      const int n = y * pm.width + x;
      if (is_cut[n] || pm.coverage[n] < 0.25 * cell_area || (best >= 0 && pm.coverage[n] <= pm.coverage[best])) continue;
      const auto [lo, hi] = pieces_of(n);
      for (auto it = lo; it != hi; ++it)
        if (std::find(part.begin(), part.end(), it->triangle) != part.end()) {
          best = n;
          break;
        }
    }
  return best;
}

// Each part of a cut texel but the largest goes to its neighbour_for, when
// there is one.
void GridBuilder::move_parts() {
  const double cell_area = pm.texel_u * pm.texel_v;
  for (Pixmap::Cut& cut : pm.cuts) {
    const auto& parts = cut.triangles;
    size_t largest = 0;
    for (size_t q = 1; q < parts.size(); ++q)
      if (part_area(cut.texel, parts[q], nullptr) > part_area(cut.texel, parts[largest], nullptr)) largest = q;
    for (size_t q = 0; q < parts.size(); ++q) {
      if (q == largest) continue;
      const int best = neighbour_for(cut.texel, parts[q], cell_area);
      if (best < 0) continue;
      Vec3 moment(0.0);
      const double area = part_area(cut.texel, parts[q], &moment);
      moves.push_back({cut.texel, best, area, moment});
      cut.owners[q] = best;
    }
  }
}

// What stays with each texel: its coverage less the parts moved away
// (coverage stays the area inside the texel); the centroid is the kept
// part's. Owners: a texel less than a quarter covered gives its area to
// its most covered neighbour that is at least a quarter covered.
void GridBuilder::set_owners(long long& covered) {
  const double cell_area = pm.texel_u * pm.texel_v;
  std::vector<double> kept(pm.coverage);
  for (const Move& m : moves) {
    kept[m.from] -= m.area;
    pm.centroid[m.from] -= m.moment;
  }
  pm.owner.assign(static_cast<size_t>(pm.texels()), -1);
  pm.area.assign(static_cast<size_t>(pm.texels()), 0.0);
  for (long long idx = 0; idx < pm.texels(); ++idx)
    if (kept[idx] > 0.0) pm.centroid[idx] /= kept[idx];
  for (int j = 0; j < pm.height; ++j)
    for (int i = 0; i < pm.width; ++i) {
      const size_t idx = static_cast<size_t>(j) * pm.width + i;
      if (pm.coverage[idx] <= 0.0) continue;
      int best = static_cast<int>(idx);
      if (kept[idx] < 0.25 * cell_area) {
        const int n = most_covered_around(pm, i, j, 0.25 * cell_area);
        if (n >= 0) best = n;
      }
      pm.owner[idx] = best;
      pm.area[best] += kept[idx];
    }
  for (const Move& m : moves) pm.area[m.to] += m.area;  // an uncut texel at least a quarter covered owns itself
  for (Pixmap::Cut& cut : pm.cuts)
    for (int& o : cut.owners)
      if (o < 0) o = pm.owner[cut.texel];
  pm.whole.assign(static_cast<size_t>(pm.texels()), 0);
  for (long long idx = 0; idx < pm.texels(); ++idx) {
    if (pm.owner[idx] == idx) ++covered;
    pm.whole[idx] = pm.owner[idx] == idx && pm.area[idx] >= (1.0 - 1e-9) * cell_area &&
                    pm.coverage[idx] >= (1.0 - 1e-9) * cell_area;
  }
}

}  // namespace

void check_options(const PixmapOptions& o) {
  pixmap_option_table().check(o);
  Hemicube::check_resolution(o.hemicube_res);
}

PixmapLayout layout_of(const Scene& scene, const Mesh& coarse, const PixmapOptions& options, double memory_bytes,
                       const Visibility* vis) {
  check_options(options);
  PixmapLayout L;
  L.texel_size = options.texel_size > 0.0 ? options.texel_size : scene.diagonal() / 80.0;
  group_patches(scene, L);
  mark_enclosed(scene, coarse, vis, L);
  std::vector<std::vector<int>> triangles_of(L.pixmaps.size());
  const std::vector<std::vector<std::pair<Vec3, Vec3>>> contact_world = contact_lines(coarse, L);
  for (int t = 0; t < coarse.triangle_count(); ++t) triangles_of[L.pixmap_of_patch[coarse.patch[t]]].push_back(t);
  const std::unordered_map<uint64_t, int> pixmap_of_edge = pixmaps_of_edges(coarse, L);
  double bytes = Hemicube::bytes(options.hemicube_res);  // the solver's hemicube comes out of the same limit
  for (size_t k = 0; k < L.pixmaps.size(); ++k) {
    Pixmap& pm = L.pixmaps[k];
    set_frame(pm, scene, L.texel_size, options.max_texels);
    pm.first = L.texels;
    L.texels += pm.texels();
    bytes += kBytesPerTexel * static_cast<double>(pm.texels());
    if (bytes > memory_bytes) refuse_memory(scene, memory_bytes);
    GridBuilder grid{coarse, triangles_of[k], pixmap_of_edge, pm, {}, {}, {}};
    grid.cover(L.enclosed, L.enclosed_area);
    grid.find_wall_feet();
    grid.find_cuts();
    grid.move_parts();
    grid.set_owners(L.covered);
    add_shooters(pm, static_cast<int>(k), contact_world[k], options.block, vis, L.shooters);
  }
  return L;
}

Mesh outline_triangulation(const Scene& scene) { return mesh_scene(scene, pixmap_meshing_options(scene)); }

}  // namespace internal

PixmapLayout make_pixmap_layout(const Scene& scene, const PixmapOptions& options, double memory_bytes) {
  internal::check_options(options);
  const Visibility vis(scene);
  return internal::layout_of(scene, internal::outline_triangulation(scene), options, memory_bytes, &vis);
}

MeshingOptions pixmap_meshing_options(const Scene& scene) {
  MeshingOptions mo;
  mo.max_edge = scene.diagonal();
  mo.discontinuity = DiscontinuityMode::contacts;
  return mo;
}

}  // namespace radmesh
