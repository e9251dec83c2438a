// Pixmap radiosity: layout of the texel grids, hemicube rows, progressive
// refinement and the display mesh (see pixmap.h).

#include "radmesh/pixmap.h"

#include "radmesh/errors.h"
#include "radmesh/form_factor.h"
#include "radiosity/pixmap/hemicube.h"
#include "radiosity/transport/transport.h"
#include "radiosity/transport/visibility.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <numeric>
#include <span>
#include <sstream>
#include <tuple>
#include <unordered_map>

namespace radmesh {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// ---- polygons in texel coordinates -----------------------------------------

struct St {
  double s, t;
};

// Sutherland-Hodgman of a convex polygon against s >= c (dir = +1) or
// s <= c (dir = -1) (axis 0), or the same for t (axis 1). The crossing of
// an edge is computed from its end points in a fixed order, so that the two
// triangles sharing an edge cut it at the same point.
int clip_line(const St* in, int n, St* out, int axis, double c, double dir) {
  auto coord = [axis](const St& p) { return axis == 0 ? p.s : p.t; };
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const St& p = in[i];
    const St& q = in[(i + 1) % n];
    const double dp = dir * (coord(p) - c), dq = dir * (coord(q) - c);
    if (dp >= 0.0) out[m++] = p;
    if ((dp >= 0.0) != (dq >= 0.0) && dp != 0.0 && dq != 0.0) {
      const bool swap = std::tie(q.s, q.t) < std::tie(p.s, p.t);
      const St& a = swap ? q : p;
      const St& b = swap ? p : q;
      const double ca = coord(a), cb = coord(b);
      const double t = (c - ca) / (cb - ca);
      St x{a.s + t * (b.s - a.s), a.t + t * (b.t - a.t)};
      if (axis == 0) x.s = c; else x.t = c;
      out[m++] = x;
    }
  }
  return m;
}

// Area and centroid of a polygon in (s, t).
void area_centroid(const St* p, int n, double& area, St& centroid) {
  double a = 0.0, cs = 0.0, ct = 0.0;
  for (int i = 0; i < n; ++i) {
    const St& u = p[i];
    const St& w = p[(i + 1) % n];
    const double cross = u.s * w.t - w.s * u.t;
    a += cross;
    cs += (u.s + w.s) * cross;
    ct += (u.t + w.t) * cross;
  }
  area = 0.5 * a;
  centroid = area != 0.0 ? St{cs / (6.0 * area), ct / (6.0 * area)} : p[0];
}

// Calls f(i, j, polygon, n) for each texel cell (i, j) the triangle
// overlaps with non-zero area, with the triangle clipped to the cell.
template <class F>
void for_each_piece(const Pixmap& pm, const St tri[3], F&& f) {
  const double smin = std::min({tri[0].s, tri[1].s, tri[2].s}), smax = std::max({tri[0].s, tri[1].s, tri[2].s});
  const double tmin = std::min({tri[0].t, tri[1].t, tri[2].t}), tmax = std::max({tri[0].t, tri[1].t, tri[2].t});
  const int i0 = std::clamp(static_cast<int>(std::floor(smin)), 0, pm.width - 1);
  const int i1 = std::clamp(static_cast<int>(std::ceil(smax)) - 1, i0, pm.width - 1);
  const int j0 = std::clamp(static_cast<int>(std::floor(tmin)), 0, pm.height - 1);
  const int j1 = std::clamp(static_cast<int>(std::ceil(tmax)) - 1, j0, pm.height - 1);
  St a[12], b[12];
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      int n = 3;
      std::copy(tri, tri + 3, a);
      // The grid's outer cells reach to infinity, so that rounding at the
      // pixmap's border loses no sliver.
      if (i > 0) n = clip_line(a, n, b, 0, i, 1.0); else std::copy(a, a + n, b);
      if (i < pm.width - 1) n = clip_line(b, n, a, 0, i + 1, -1.0); else std::copy(b, b + n, a);
      if (j > 0) n = clip_line(a, n, b, 1, j, 1.0); else std::copy(a, a + n, b);
      if (j < pm.height - 1) n = clip_line(b, n, a, 1, j + 1, -1.0); else std::copy(b, b + n, a);
      if (n < 3) continue;
      f(i, j, a, n);
    }
}

// ---- the layout ------------------------------------------------------------

// Whether texel idx is its own square and nothing else: wholly covered and
// holding no sliver of a neighbour.
bool plain_square(const Pixmap& pm, long long idx) {
  return pm.whole[idx] && pm.area[idx] <= (1.0 + 1e-9) * pm.texel_u * pm.texel_v;
}

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(int n) : parent(static_cast<size_t>(n)) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

St st_of(const Pixmap& pm, const Vec3& x) { return {pm.s_of(x), pm.t_of(x)}; }

// Point a of the 3-point rule on triangle v (exact for quadratics): a
// sixth of the way from corner a toward the midpoint of the other two.
Vec3 rule_point(const std::array<Vec3, 3>& v, int a) { return (4.0 * v[a] + v[(a + 1) % 3] + v[(a + 2) % 3]) / 6.0; }

// Whether segments pq and ab cross (touching counts).
bool segments_cross(const St& p, const St& q, const St& a, const St& b) {
  auto side = [](const St& o, const St& u, const St& v) { return (u.s - o.s) * (v.t - o.t) - (u.t - o.t) * (v.s - o.s); };
  const double d1 = side(a, b, p), d2 = side(a, b, q), d3 = side(p, q, a), d4 = side(p, q, b);
  return ((d1 <= 0.0 && d2 >= 0.0) || (d1 >= 0.0 && d2 <= 0.0)) && ((d3 <= 0.0 && d4 >= 0.0) || (d3 >= 0.0 && d4 <= 0.0));
}

Vec3 point_of(const Pixmap& pm, double s, double t) { return pm.origin + (s * pm.texel_u) * pm.u + (t * pm.texel_v) * pm.v; }

// The cut (Pixmap::cuts) of texel idx, or null when no contact line cuts it.
const Pixmap::Cut* cut_of(const Pixmap& pm, int idx) {
  if (pm.cuts.empty()) return nullptr;
  const auto it = std::lower_bound(pm.cuts.begin(), pm.cuts.end(), idx,
                                   [](const Pixmap::Cut& c, int texel) { return c.texel < texel; });
  return it != pm.cuts.end() && it->texel == idx ? &*it : nullptr;
}

// The owner of the piece of coarse triangle t in texel idx.
int owner_of_piece(const Pixmap& pm, int idx, int t) {
  if (const Pixmap::Cut* cut = cut_of(pm, idx))
    for (size_t q = 0; q < cut->triangles.size(); ++q)
      if (std::find(cut->triangles[q].begin(), cut->triangles[q].end(), t) != cut->triangles[q].end())
        return cut->owners[q];
  return pm.owner[idx];
}

// Calls touch(texel) for every texel whose closed square the segment a-b
// (in texel coordinates) meets: column by column along its longer axis, the
// rows its span there reaches, a texel's edges included.
template <class Touch>
void for_each_texel_on(const Pixmap& pm, St a, St b, Touch&& touch) {
  const bool by_s = std::abs(b.s - a.s) >= std::abs(b.t - a.t);
  const int n_major = by_s ? pm.width : pm.height, n_minor = by_s ? pm.height : pm.width;
  double m0 = by_s ? a.s : a.t, m1 = by_s ? b.s : b.t, q0 = by_s ? a.t : a.s, q1 = by_s ? b.t : b.s;
  if (m0 > m1) {
    std::swap(m0, m1);
    std::swap(q0, q1);
  }
  constexpr double kEdge = 1e-9;  // on a texel line: both texels
  auto minor_at = [&](double m) { return m1 > m0 ? q0 + (q1 - q0) * (m - m0) / (m1 - m0) : q0; };
  const int i0 = std::max(0, static_cast<int>(std::floor(m0 - kEdge)));
  const int i1 = std::min(n_major - 1, static_cast<int>(std::floor(m1 + kEdge)));
  for (int i = i0; i <= i1; ++i) {
    const double lo = std::clamp(static_cast<double>(i), m0, m1), hi = std::clamp(i + 1.0, m0, m1);
    const double qa = minor_at(lo), qb = minor_at(hi);
    const int j0 = std::max(0, static_cast<int>(std::floor(std::min(qa, qb) - kEdge)));
    const int j1 = std::min(n_minor - 1, static_cast<int>(std::floor(std::max(qa, qb) + kEdge)));
    for (int j = j0; j <= j1; ++j) touch(by_s ? j * pm.width + i : i * pm.width + j);
  }
}

// The owner of point (s, t) for texel idx: where a contact line cuts the
// texel, that of the part nearest the point (the one holding it, when it
// lies in the texel), its triangles being those of `coarse`. A pixel's
// footprint may reach across the wall, but its centre lies on the side the
// pixel sees.
int owner_of_cut_point(const Pixmap& pm, const Mesh& coarse, int idx, double s, double t) {
  const Pixmap::Cut* cut = cut_of(pm, idx);
  if (!cut) return pm.owner[idx];
  auto to_segment = [&](const St& a, const St& b) {
    const double ds = b.s - a.s, dt = b.t - a.t, len2 = ds * ds + dt * dt;
    const double h = len2 > 0.0 ? std::clamp(((s - a.s) * ds + (t - a.t) * dt) / len2, 0.0, 1.0) : 0.0;
    return std::hypot(s - a.s - h * ds, t - a.t - h * dt);
  };
  double nearest = INFINITY;
  int owner = pm.owner[idx];
  for (size_t q = 0; q < cut->triangles.size(); ++q)
    for (int tri : cut->triangles[q]) {
      St v[3];
      for (int c = 0; c < 3; ++c) v[c] = st_of(pm, coarse.positions[coarse.triangles[tri][c]]);
      if ((v[1].s - v[0].s) * (v[2].t - v[0].t) == (v[1].t - v[0].t) * (v[2].s - v[0].s)) continue;  // no area
      double e[3];
      for (int c = 0; c < 3; ++c)
        e[c] = (v[(c + 1) % 3].s - v[c].s) * (t - v[c].t) - (v[(c + 1) % 3].t - v[c].t) * (s - v[c].s);
      const bool inside = (e[0] >= 0.0 && e[1] >= 0.0 && e[2] >= 0.0) || (e[0] <= 0.0 && e[1] <= 0.0 && e[2] <= 0.0);
      const double d = inside ? 0.0 : std::min({to_segment(v[0], v[1]), to_segment(v[1], v[2]), to_segment(v[2], v[0])});
      if (d < nearest) {
        nearest = d;
        owner = cut->owners[q];
      }
    }
  return owner;
}

// The same, fast where no texel is cut or the texel is whole (a cut texel
// never is): the hemicube's hottest loop asks it for every pixel.
inline int owner_of_point(const Pixmap& pm, const Mesh& coarse, int idx, double s, double t) {
  return pm.cuts.empty() || pm.whole[idx] ? pm.owner[idx] : owner_of_cut_point(pm, coarse, idx, s, t);
}

// The square of texel idx (counter-clockwise around the pixmap's normal).
std::array<Vec3, 4> texel_square(const Pixmap& pm, int idx) {
  const int i = idx % pm.width, j = idx / pm.width;
  return {point_of(pm, i, j), point_of(pm, i + 1, j), point_of(pm, i + 1, j + 1), point_of(pm, i, j + 1)};
}

// The texel of the 3 x 3 around (i, j) with the most coverage, at least
// `min_coverage` and more than 0 (the first in row order on ties); -1 when none.
int most_covered_around(const Pixmap& pm, int i, int j, double min_coverage) {
  int best = -1;
  double most = 0.0;
  for (int dj = -1; dj <= 1; ++dj)
    for (int di = -1; di <= 1; ++di) {
      const int x = i + di, y = j + dj;
      if (x < 0 || y < 0 || x >= pm.width || y >= pm.height) continue;
      const size_t n = static_cast<size_t>(y) * pm.width + x;
      if (pm.coverage[n] >= min_coverage && pm.coverage[n] > most) {
        most = pm.coverage[n];
        best = static_cast<int>(n);
      }
    }
  return best;
}

void check_options(const PixmapOptions& o) {
  pixmap_option_table().check(o);
  Hemicube::check_resolution(o.hemicube_res);
}

// What a pixmap run holds per texel at its peak, besides the cached rows:
// the texel grids and state, the display mesh and its values, and the
// radiosity.vtu being written. Measured (peak resident memory / texels, one
// shot): 656 bytes on the Cornell box at 7.6 M texels, 660 on the 16 x 16 box
// field at 5.8 M. The grids alone were counted before (90 bytes), and the
// Cornell box's run then peaked at 6.8 GiB under --max-memory 3.
constexpr double kBytesPerTexel = 700.0;

PixmapLayout layout_of(const Scene& scene, const Mesh& coarse, const PixmapOptions& options, double memory_bytes,
                       const Visibility* vis) {
  check_options(options);
  const int np = static_cast<int>(scene.patches.size());
  PixmapLayout L;
  L.texel_size = options.texel_size > 0.0 ? options.texel_size : scene.diagonal() / 80.0;
  const double tol = 1e-9 * scene.diagonal();

  // Coplanar patches of one material sharing a vertex share a pixmap.
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

  // Triangles inside closed objects (inside_closed_object: tested at the
  // centroid alone, a one-sided table top 20 cm over a floor left the whole
  // floor out when it covered a coarse triangle's centroid).
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
  // Each pixmap's frame and grid.
  std::vector<std::vector<int>> triangles_of(L.pixmaps.size());
  // The contact lines inside each pixmap's patches (feature edges of the
  // coarse mesh, found by the triangles that have them), in world points
  // until the pixmap's frame is known.
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
  for (int t = 0; t < coarse.triangle_count(); ++t) triangles_of[L.pixmap_of_patch[coarse.patch[t]]].push_back(t);
  // Triangles of one pixmap joined across an edge no other surface stands
  // on (a wall's foot is an edge of the wall's triangles too; an overhang's
  // or a shadow's line is not): within one texel, pieces of triangles so
  // joined are one part of it.
  std::unordered_map<uint64_t, int> pixmap_of_edge;  // -1: a wall stands on it
  for (int t = 0; t < coarse.triangle_count(); ++t)
    for (int c = 0; c < 3; ++c) {
      const int k = L.pixmap_of_patch[coarse.patch[t]];
      auto [it, fresh] = pixmap_of_edge.try_emplace(
          undirected_edge_key(coarse.triangles[t][c], coarse.triangles[t][(c + 1) % 3]), k);
      if (!fresh && it->second != k) it->second = -1;
    }
  auto joined = [&](int a, int b) {
    for (int c = 0; c < 3; ++c) {
      const int u = coarse.triangles[a][c], v = coarse.triangles[a][(c + 1) % 3];
      const auto& tb = coarse.triangles[b];
      const bool shared = (u == tb[0] || u == tb[1] || u == tb[2]) && (v == tb[0] || v == tb[1] || v == tb[2]);
      if (shared && pixmap_of_edge.at(undirected_edge_key(u, v)) >= 0) return true;
    }
    return false;
  };
  double bytes = 0.0;
  for (size_t k = 0; k < L.pixmaps.size(); ++k) {
    Pixmap& pm = L.pixmaps[k];
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
    double size = L.texel_size;
    auto cells = [&](double extent) { return std::max(1.0, std::ceil(extent / size - 1e-9)); };
    if (cells(eu) * cells(ev) > static_cast<double>(options.max_texels))
      size *= std::sqrt(cells(eu) * cells(ev) / static_cast<double>(options.max_texels)) * (1.0 + 1e-12);
    while (cells(eu) * cells(ev) > static_cast<double>(options.max_texels)) size *= 1.01;
    pm.width = static_cast<int>(cells(eu));
    pm.height = static_cast<int>(cells(ev));
    pm.texel_u = eu > 0.0 ? eu / pm.width : size;
    pm.texel_v = ev > 0.0 ? ev / pm.height : size;
    pm.first = L.texels;
    L.texels += pm.texels();
    bytes += kBytesPerTexel * static_cast<double>(pm.texels());
    if (bytes > memory_bytes) {
      std::ostringstream m;
      m.precision(3);
      m << scene.source << ": the texels (their grids, display mesh and files) need more than the "
        << memory_bytes / (1024.0 * 1024.0 * 1024.0)
        << " GiB allowed; use a larger texel_size (the texel count falls with its square) or raise max_memory";
      throw NumericalError(m.str(), {"texel_size", "max_memory"});
    }
    pm.coverage.assign(static_cast<size_t>(pm.texels()), 0.0);
    pm.centroid.assign(static_cast<size_t>(pm.texels()), Vec3(0.0));
    // Coverage from the pieces of the triangles in each texel, less the
    // triangles inside a closed object standing on the patch (a block on a
    // floor): light never reaches there, and a shooter placed there would
    // shoot into the object's back faces. The coarse mesh is cut along the
    // contact lines, so each triangle is wholly inside or outside.
    struct Piece {
      int texel, triangle;
      double area;
      Vec3 moment;  // area x centroid
      bool operator<(const Piece& o) const { return std::tie(texel, triangle) < std::tie(o.texel, o.triangle); }
    };
    std::vector<Piece> pieces;
    for (int t : triangles_of[k]) {
      if (L.enclosed[t]) {
        L.enclosed_area += coarse.area(t);
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
    const double cell_area = pm.texel_u * pm.texel_v;
    // The wall feet and the texels they touch: edges another pixmap's
    // triangles share, with this one's on both sides (the edges all round,
    // where the walls around meet it, have nothing beyond them to keep
    // light from).
    std::unordered_map<uint64_t, int> sides;
    for (int t : triangles_of[k])
      for (int c = 0; c < 3; ++c) {
        const uint64_t key = undirected_edge_key(coarse.triangles[t][c], coarse.triangles[t][(c + 1) % 3]);
        if (pixmap_of_edge.at(key) < 0) ++sides[key];
      }
    for (int t : triangles_of[k])
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
    // Texels cut into parts: pieces of triangles not joined (a thin wall
    // stands across the texel: its footprint is a gap between them, or it
    // stands on the line between them). One value and one centroid for both
    // sides put the shooter inside the wall, or on one side shooting the
    // other side's light: each part but the largest goes to the most covered
    // neighbour holding a piece of one of its triangles (on its own side),
    // when one is at least a quarter covered and not cut itself.
    std::sort(pieces.begin(), pieces.end());
    struct Move {
      int from, to;
      double area;
      Vec3 moment;
    };
    std::vector<Move> moves;
    std::vector<char> is_cut(pieces.empty() ? 0 : static_cast<size_t>(pm.texels()), 0);
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
          cut.owners.assign(parts.size(), -1);  // -1: the texel's owner, set below
          is_cut[cut.texel] = 1;
          pm.cuts.push_back(std::move(cut));
        }
      }
      a = b;
    }
    auto pieces_of = [&](int texel) {
      return std::equal_range(pieces.begin(), pieces.end(), Piece{texel, -1, 0.0, Vec3(0.0)},
                              [](const Piece& x, const Piece& y) { return x.texel < y.texel; });
    };
    for (Pixmap::Cut& cut : pm.cuts) {
      const auto& parts = cut.triangles;
      auto part_area = [&](const std::vector<int>& tris, Vec3* moment) {
        double area = 0.0;
        const auto [lo, hi] = pieces_of(cut.texel);
        for (auto it = lo; it != hi; ++it)
          if (std::find(tris.begin(), tris.end(), it->triangle) != tris.end()) {
            area += it->area;
            if (moment) *moment += it->moment;
          }
        return area;
      };
      size_t largest = 0;
      for (size_t q = 1; q < parts.size(); ++q)
        if (part_area(parts[q], nullptr) > part_area(parts[largest], nullptr)) largest = q;
      const int i = cut.texel % pm.width, j = cut.texel / pm.width;
      for (size_t q = 0; q < parts.size(); ++q) {
        if (q == largest) continue;
        int best = -1;
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di) {
            const int x = i + di, y = j + dj;
            if ((di == 0 && dj == 0) || x < 0 || y < 0 || x >= pm.width || y >= pm.height) continue;
            const int n = y * pm.width + x;
            if (is_cut[n] || pm.coverage[n] < 0.25 * cell_area || (best >= 0 && pm.coverage[n] <= pm.coverage[best])) continue;
            const auto [lo, hi] = pieces_of(n);
            for (auto it = lo; it != hi; ++it)
              if (std::find(parts[q].begin(), parts[q].end(), it->triangle) != parts[q].end()) {
                best = n;
                break;
              }
          }
        if (best < 0) continue;
        Vec3 moment(0.0);
        const double area = part_area(parts[q], &moment);
        moves.push_back({cut.texel, best, area, moment});
        cut.owners[q] = best;
      }
    }
    // What stays with each texel: its coverage less the parts moved away
    // (coverage stays the area inside the texel); the centroid is the kept part's.
    std::vector<double> kept(pm.coverage);
    for (const Move& m : moves) {
      kept[m.from] -= m.area;
      pm.centroid[m.from] -= m.moment;
    }
    // Owners: a texel less than a quarter covered gives its area to its
    // most covered neighbour that is at least a quarter covered.
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
      if (pm.owner[idx] == idx) ++L.covered;
      pm.whole[idx] = pm.owner[idx] == idx && pm.area[idx] >= (1.0 - 1e-9) * cell_area &&
                      pm.coverage[idx] >= (1.0 - 1e-9) * cell_area;
    }

    // Shooters: blocks of owners, split where a contact line (a wall or
    // an object standing on the patch) runs between two of their texels'
    // centroids, so that no shooter sits on one side of a wall and shoots
    // the other side's power.
    std::vector<std::pair<St, St>> lines;
    for (const auto& [a, c] : contact_world[k]) lines.push_back({st_of(pm, a), st_of(pm, c)});
    // Per texel: the lines that touch it (the cost is the lines' length in
    // texels).
    std::vector<std::vector<int>> near_lines;
    if (!lines.empty()) {
      near_lines.resize(static_cast<size_t>(pm.texels()));
      for (size_t e = 0; e < lines.size(); ++e)
        for_each_texel_on(pm, lines[e].first, lines[e].second, [&](int texel) {
          auto& list = near_lines[static_cast<size_t>(texel)];
          if (list.empty() || list.back() != static_cast<int>(e)) list.push_back(static_cast<int>(e));
        });
    }
    // Whether the segment between the centroids of texels x and y of a
    // block crosses one of the block's contact lines (those near any of its
    // texels: the segment stays inside the block).
    std::vector<int> block_lines;
    auto separated = [&](int x, int y) {
      const St p = st_of(pm, pm.centroid[x]), q = st_of(pm, pm.centroid[y]);
      for (int e : block_lines)
        if (segments_cross(p, q, lines[static_cast<size_t>(e)].first, lines[static_cast<size_t>(e)].second)) return true;
      return false;
    };
    const int b = options.block;
    // Overhung texels: a surface (front or back) lies in front of the
    // texel's centroid, along the patch's normal, nearer than a block's
    // diagonal (a lamp hung under a ceiling, a low shelf over a floor).
    // One hemicube at a block's centroid cannot stand for texels on both
    // sides of an overhang's outline: under a lamp 1 cm below a ceiling it
    // sees the lamp's back, which receives nothing, and the lit texels of
    // the blocks straddling the lamp's outline lost their power there. So
    // the outline splits a block as a contact line does, and a group whose
    // centroid falls on the other side (an L of three open texels around a
    // covered one) shoots texel by texel.
    const double overhang_reach = std::sqrt(2.0) * b * std::max(pm.texel_u, pm.texel_v);
    auto overhung_at = [&](const Vec3& x) -> char {
      return vis && vis->first_hit(x, pm.normal, overhang_reach, pm.patches[0]) >= 0 ? 1 : 0;
    };
    std::vector<char> overhung(static_cast<size_t>(pm.texels()), 0);
    for (long long idx = 0; idx < pm.texels(); ++idx)
      if (pm.owner[idx] == idx) overhung[idx] = overhung_at(pm.centroid[idx]);
    for (int bj = 0; bj < pm.height; bj += b)
      for (int bi = 0; bi < pm.width; bi += b) {
        std::vector<int> owners;
        block_lines.clear();
        for (int j = bj; j < std::min(pm.height, bj + b); ++j)
          for (int i = bi; i < std::min(pm.width, bi + b); ++i) {
            const int idx = j * pm.width + i;
            if (!near_lines.empty())
              block_lines.insert(block_lines.end(), near_lines[static_cast<size_t>(idx)].begin(),
                                 near_lines[static_cast<size_t>(idx)].end());
            if (pm.owner[idx] == idx) owners.push_back(idx);
          }
        std::sort(block_lines.begin(), block_lines.end());
        block_lines.erase(std::unique(block_lines.begin(), block_lines.end()), block_lines.end());
        // Groups: owners joined where nothing separates them (neither a
        // contact line nor an overhang's outline).
        UnionFind groups(static_cast<int>(owners.size()));
        if (!block_lines.empty()) {
          for (size_t x = 0; x < owners.size(); ++x)
            for (size_t y = x + 1; y < owners.size(); ++y)
              if (overhung[owners[x]] == overhung[owners[y]] && !separated(owners[x], owners[y]))
                groups.unite(static_cast<int>(x), static_cast<int>(y));
        } else {
          int first[2] = {-1, -1};
          for (size_t x = 0; x < owners.size(); ++x) {
            int& f = first[static_cast<size_t>(overhung[owners[x]])];
            if (f < 0) f = static_cast<int>(x);
            groups.unite(f, static_cast<int>(x));
          }
        }
        auto add_shooter = [&](const std::vector<int>& texels) {
          Shooter sh;
          sh.pixmap = static_cast<int>(k);
          sh.texels = texels;
          Vec3 sum(0.0);
          double weight = 0.0;
          for (int idx : texels) {
            sh.area += pm.area[idx];
            sum += pm.coverage[idx] * pm.centroid[idx];
            weight += pm.coverage[idx];
          }
          sh.centre = sum / weight;
          L.shooters.push_back(std::move(sh));
        };
        std::vector<int> members;
        for (size_t g = 0; g < owners.size(); ++g) {
          if (groups.find(static_cast<int>(g)) != static_cast<int>(g)) continue;
          members.clear();
          for (size_t x = 0; x < owners.size(); ++x)
            if (groups.find(static_cast<int>(x)) == static_cast<int>(g)) members.push_back(owners[x]);
          add_shooter(members);
          const Shooter& group = L.shooters.back();
          if (members.size() > 1 && overhung[members[0]] != overhung_at(group.centre)) {
            L.shooters.pop_back();
            for (int idx : members) add_shooter({idx});
          }
        }
      }
  }
  return L;
}

// The method's mesh (pixmap_meshing_options): the dark part under a block
// follows the block's outline exactly.
Mesh outline_triangulation(const Scene& scene) { return mesh_scene(scene, pixmap_meshing_options(scene)); }

// Texels closer to a shooter's centre than this times the shooter's
// radius (plus a texel) take Lambert's exact form factor (the near field).
constexpr double kNearField = 1.5;

struct RowEntry {
  uint32_t texel;  // global index
  float f;
};

// A shooter's row. The far texels take the hemicube's factor from the
// block as a whole (a narrow pixmap's, Lambert's from the block's centre);
// the near ones, from each of the shooter's texels
// (sh.texels order) by Lambert's formula, so that a block straddling a
// shadow shoots its lit and dark texels' power from where they are. Each
// source texel i delivers far_scale[i] x its power along the far entries,
// which keeps its row's sum at the hemicube's (1 in a closed scene).
struct Row {
  std::vector<RowEntry> far;         // increasing texel; F from the block, before far_scale
  std::vector<uint32_t> near;        // increasing global texel
  std::vector<float> near_f;         // near.size() x sources: F from each source texel
  std::vector<float> far_scale;      // per source texel
  double bytes() const {
    return static_cast<double>(far.size() * sizeof(RowEntry) + near.size() * sizeof(uint32_t) +
                               (near_f.size() + far_scale.size()) * sizeof(float));
  }
};

}  // namespace

PixmapLayout make_pixmap_layout(const Scene& scene, const PixmapOptions& options, double memory_bytes) {
  check_options(options);
  const Visibility vis(scene);
  return layout_of(scene, outline_triangulation(scene), options, memory_bytes, &vis);
}

MeshingOptions pixmap_meshing_options(const Scene& scene) {
  MeshingOptions mo;
  mo.max_edge = scene.diagonal();
  mo.discontinuity = DiscontinuityMode::contacts;
  return mo;
}

std::string scene_fingerprint(const Scene& scene) {
  uint64_t h = 1469598103934665603ull;
  auto mix = [&h](const void* data, size_t n) {
    const unsigned char* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < n; ++i) {
      h ^= p[i];
      h *= 1099511628211ull;
    }
  };
  auto mix_int = [&](long long v) { mix(&v, sizeof v); };
  auto mix_vec = [&](const Vec3& v) {
    for (int c = 0; c < 3; ++c) {
      const double d = v[c] == 0.0 ? 0.0 : v[c];  // -0 and 0 alike
      mix(&d, sizeof d);
    }
  };
  mix_int(static_cast<long long>(scene.vertices.size()));
  for (const Vec3& v : scene.vertices) mix_vec(v);
  mix_int(static_cast<long long>(scene.materials.size()));
  for (const Material& m : scene.materials) {
    mix_vec(m.reflectance);
    mix_vec(m.emission);
  }
  mix_int(static_cast<long long>(scene.patches.size()));
  for (const Patch& p : scene.patches) {
    mix_int(p.material);
    mix_int(static_cast<long long>(p.outer.size()));
    for (int v : p.outer) mix_int(v);
    mix_int(static_cast<long long>(p.holes.size()));
    for (const auto& hole : p.holes) {
      mix_int(static_cast<long long>(hole.size()));
      for (int v : hole) mix_int(v);
    }
  }
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(h));
  return text;
}

void check_resumable(const PixmapState& state, const Scene& scene, const PixmapLayout& layout,
                     const PixmapOptions& options, const std::string& where) {
  auto refuse = [&](const std::string& why) {
    throw InputError(where + ": cannot resume: " + why, {"texel_size", "max_texels", "hemicube_res", "block"});
  };
  if (state.scene_fingerprint != scene_fingerprint(scene))
    refuse("it was made from another scene (or this one edited): fingerprint " + state.scene_fingerprint +
           ", this scene " + scene_fingerprint(scene));
  auto same = [&](const char* option, double saved, double now) {
    if (saved != now)
      refuse(std::string("it was made with ") + option + " " + format_number(saved) + ", this run has " + option +
             " " + format_number(now));
  };
  same("texel_size", state.texel_size, layout.texel_size);
  same("max_texels", static_cast<double>(state.max_texels), static_cast<double>(options.max_texels));
  same("hemicube_res", state.hemicube_res, options.hemicube_res);
  same("block", state.block, options.block);
  if (state.sizes.size() != layout.pixmaps.size())
    refuse(std::to_string(state.sizes.size()) + " pixmaps saved, this layout has " +
           std::to_string(layout.pixmaps.size()));
  for (size_t k = 0; k < layout.pixmaps.size(); ++k) {
    const Pixmap& pm = layout.pixmaps[k];
    const size_t n = static_cast<size_t>(pm.texels()) * 3;
    if (state.sizes[k][0] != pm.width || state.sizes[k][1] != pm.height || state.radiosity[k].size() != n ||
        state.unshot[k].size() != n)
      refuse("pixmap " + std::to_string(k) + " is " + std::to_string(state.sizes[k][0]) + " x " +
             std::to_string(state.sizes[k][1]) + " texels in the state, " + std::to_string(pm.width) + " x " +
             std::to_string(pm.height) + " here");
    for (size_t i = 0; i < n; ++i)
      if (!std::isfinite(state.radiosity[k][i]) || !std::isfinite(state.unshot[k][i]) ||
          state.radiosity[k][i] < 0.0f || state.unshot[k][i] < 0.0f)
        refuse("pixmap " + std::to_string(k) + " texel " + std::to_string(i / 3) + " holds a negative or non-finite value");
  }
  if (state.shots < 0) refuse("a negative shot count");
}

// ---- the solver ------------------------------------------------------------

struct PixmapSolver::Impl {
  const Scene scene;  // a copy: results that hold the solver may outlive the caller's scene
  PixmapOptions options;
  SolveOptions solve;
  Mesh coarse;
  PixmapLayout layout;
  std::vector<HemicubeTriangle> polygons;
  std::vector<Rgb> rho, emission;           // per pixmap
  std::vector<int> shooter_of;              // per global texel: its shooter (-1: none)
  double row_budget = 0.0;                  // bytes the cached rows may take
  Rgb power_emitted{0.0};                   // sum of E x area over the texels
  Rgb power_enclosed{0.0};                  // E x area of the emitting triangles inside closed objects
  std::vector<std::string> warnings;        // one per emitting patch with such triangles
  // The display mesh: geometry built once.
  Mesh display;
  std::vector<St> display_st;
  std::vector<int> display_pixmap;          // per display vertex
  std::vector<char> display_dark;           // per display vertex: of triangles inside closed objects
  std::vector<long long> display_texel;     // per display triangle: global texel
  // Per pixmap: its display triangles are [display_first[k],
  // display_first[k + 1]), and its lit area's extent, which tells when the
  // pixmap is narrow for a shooter (narrow_receiver).
  std::vector<size_t> display_first;
  struct Extent {
    Vec3 centre{0.0};    // area centroid
    double radius = 0.0;  // farthest vertex from it
    double width = 0.0;   // area / (2 radius): a strip's width, a disc's 1.6 radii
  };
  std::vector<Extent> extent;
  // The lit display triangles of each global owner texel, pieces[
  // pieces_begin[g] .. pieces_begin[g + 1]): the polygons a texel that is
  // not a plain square shoots from, and the parts of a texel a line cuts.
  std::vector<uint32_t> pieces_begin;
  std::vector<int> pieces;
  std::span<const int> pieces_of(long long g) const {
    return {pieces.data() + pieces_begin[static_cast<size_t>(g)],
            static_cast<size_t>(pieces_begin[static_cast<size_t>(g) + 1] - pieces_begin[static_cast<size_t>(g)])};
  }
  // The corners of display triangle d.
  std::array<Vec3, 3> piece_corners(int d) const {
    const auto& t = display.triangles[static_cast<size_t>(d)];
    return {display.positions[t[0]], display.positions[t[1]], display.positions[t[2]]};
  }
  // Shadow rays for the receivers the hemicube's pixels are too coarse for.
  std::unique_ptr<Visibility> vis;

  Impl(const Scene& s, const PixmapOptions& o, const SolveOptions& so) : scene(s), options(o), solve(so) {}

  long long global(int k, int idx) const { return layout.pixmaps[k].first + idx; }
  int pixmap_of_global(long long g) const {
    // Pixmaps are in increasing `first`.
    const auto it = std::upper_bound(layout.pixmaps.begin(), layout.pixmaps.end(), g,
                                     [](long long x, const Pixmap& p) { return x < p.first; });
    return static_cast<int>(it - layout.pixmaps.begin()) - 1;
  }

  Row compute_row(int s, Hemicube& cube, long long& spread_pixels) const;
  bool narrow_receiver(int k, const Shooter& sh, double pixel, double reach) const;
  // What a narrow pixmap receives from a shooter: its far texels through
  // `add` (far_sum in all), its near ones (within `reach`) from each source
  // texel.
  struct NarrowPart {
    // The share of its factor in front of other surfaces (the rest has open
    // sky behind it): what the hemicube gave those surfaces where it missed
    // the pixmap, the pixmap really hides.
    double behind = 1.0;
    double far_sum = 0.0;
    std::vector<uint32_t> near;   // increasing global texel
    std::vector<float> near_f;    // near.size() x sources
    std::vector<double> exact;    // per source texel: the sum over `near`
  };
  // A source texel's polygon: a plain texel's square, else one of the
  // pieces it owns (a texel along an outline may own a sliver on its far
  // side).
  struct SourcePolygon {
    size_t q;  // its texel, in sh.texels
    std::array<Vec3, 4> v;
    size_t count;
    Vec3 centroid() const {
      Vec3 c(0.0);
      for (size_t m = 0; m < count; ++m) c += v[m];
      return c / static_cast<double>(count);
    }
  };
  std::vector<SourcePolygon> source_polygons(const Shooter& sh) const;
  void receive_narrow(int k, const Shooter& sh, double reach, bool sky, const std::vector<SourcePolygon>& polygons,
                      const std::function<void(int, double)>& add, NarrowPart& out) const;
  void build_display();
};

namespace {

// The pixel rectangle of face f that the quad `corners` (world points) may
// cover, as seen by the hemicube: [x0, x1] x [y0, y1]; false when none.
bool projected_rect(const Hemicube& cube, int f, const std::array<Vec3, 4>& corners, int& x0, int& x1, int& y0,
                    int& y1) {
  const Hemicube::Face& F = cube.faces()[f];
  double xmin = INFINITY, xmax = -INFINITY, ymin = INFINITY, ymax = -INFINITY;
  bool any = false;
  // Project the quad clipped to z >= near (a corner behind the eye clips the
  // quad; the clipped polygon's points on the near plane count).
  struct P {
    double x, y, z;
  };
  P a[8];
  int n = 0;
  double scale = 0.0;
  for (const Vec3& c : corners) {
    const Vec3 d = c - cube.centre();
    a[n++] = {glm::dot(d, F.right), glm::dot(d, F.up), glm::dot(d, F.forward)};
    scale = std::max(scale, glm::length(d));
  }
  const double near = 1e-12 * scale;
  for (int i = 0; i < 4; ++i) {
    const P& p = a[i];
    const P& q = a[(i + 1) % 4];
    auto add = [&](double x, double y, double z) {
      xmin = std::min(xmin, x / z);
      xmax = std::max(xmax, x / z);
      ymin = std::min(ymin, y / z);
      ymax = std::max(ymax, y / z);
      any = true;
    };
    if (p.z >= near) add(p.x, p.y, p.z);
    if ((p.z >= near) != (q.z >= near)) {
      const double t = (near - p.z) / (q.z - p.z);
      add(p.x + t * (q.x - p.x), p.y + t * (q.y - p.y), near);
    }
  }
  if (!any) return false;
  const double px = cube.pixel_size();
  x0 = std::max(0, static_cast<int>(std::floor((std::max(xmin, -2.0) + 1.0) / px - 0.5)));
  x1 = std::min(F.width - 1, static_cast<int>(std::ceil((std::min(xmax, 2.0) + 1.0) / px - 0.5)));
  y0 = std::max(0, static_cast<int>(std::floor((std::max(ymin, F.y0 - 1.0) - F.y0) / px - 0.5)));
  y1 = std::min(F.height - 1, static_cast<int>(std::ceil((std::min(ymax, 2.0) - F.y0) / px - 0.5)));
  return x0 <= x1 && y0 <= y1;
}

}  // namespace

Row PixmapSolver::Impl::compute_row(int s, Hemicube& cube, long long& spread_pixels) const {
  const Shooter& sh = layout.shooters[s];
  const Pixmap& own = layout.pixmaps[sh.pixmap];
  cube.render(sh.centre, own.u, own.v, polygons);
  const int npm = static_cast<int>(layout.pixmaps.size());
  const size_t nsrc = sh.texels.size();
  std::vector<std::vector<RowEntry>> far_parts(static_cast<size_t>(npm));
  std::vector<std::vector<uint32_t>> near_parts(static_cast<size_t>(npm));
  std::vector<std::vector<float>> near_values(static_cast<size_t>(npm));
  // Per pixmap: the hemicube's factor to its near texels, and per source
  // texel the exact one (sum over the near texels).
  std::vector<double> near_hemicube(static_cast<size_t>(npm), 0.0);
  std::vector<std::vector<double>> near_exact(static_cast<size_t>(npm), std::vector<double>(nsrc, 0.0));
  std::vector<long long> over(static_cast<size_t>(npm), 0);
  // Per pixmap narrow for this shooter (narrow_receiver): the delta form
  // factors of the pixels that saw it, and the factors from the block's
  // centre put in their place (its near texels' go to near_exact).
  std::vector<double> pixels_dropped(static_cast<size_t>(npm), 0.0), exact_put(static_cast<size_t>(npm), 0.0);
  std::vector<double> behind(static_cast<size_t>(npm), 1.0);
  // The near field. A hemicube sees from one point, and the shooter's
  // exchange with texels closer than a few times its size (across an edge
  // it shares with them) is not that of its centre: there F is integrated
  // exactly instead, per source texel, by reciprocity: Lambert's factor to
  // each source texel's polygons (exact) from points of the receiving texel
  // (2 x 2 of a plain texel, 3 of each piece of another), for the texels
  // the hemicube saw. Taken the other way round (from 2 x 2 points of each
  // source texel to the receiving square; one point, the centroid, of a
  // texel an outline cuts), the faces of a box that a lamp crosses got 5%
  // too little of its light: their texels along the lamp receive from the
  // lamp's texels cut by the box's outline, where F varies fastest.
  const std::vector<SourcePolygon> polygons = source_polygons(sh);
  double reach = 0.0;
  for (size_t i = 0; i < nsrc; ++i) {
    const int t = sh.texels[i];
    reach = std::max(reach, glm::length(own.centroid[t] - sh.centre) + std::hypot(own.texel_u, own.texel_v));
  }
  reach *= kNearField;
  // Whether the hemicube sees open sky anywhere: if not, whatever lies
  // behind a narrow pixmap is the scene.
  bool sky = false;
  for (const Hemicube::Face& F : cube.faces())
    sky = sky || std::find(F.id.begin(), F.id.end(), Hemicube::kEmpty) != F.id.end();
  tbb::parallel_for(0, npm, [&](int k) {
    if (k == sh.pixmap) return;
    const Pixmap& pm = layout.pixmaps[k];
    const double h = glm::dot(pm.origin - sh.centre, pm.normal);
    const bool narrow = narrow_receiver(k, sh, cube.pixel_size(), reach);
    // A shooter whose centre is not in front of this pixmap sends it nothing,
    // unless the pixmap is narrow: then each source texel near it is taken
    // on its own (a block around a picture's corner, its centre a few
    // millimetres above the picture's underside, has texels right under it).
    if (!(h < 0.0) && !narrow) return;
    const std::array<Vec3, 4> corners = {point_of(pm, 0, 0), point_of(pm, pm.width, 0),
                                         point_of(pm, pm.width, pm.height), point_of(pm, 0, pm.height)};
    std::vector<double> acc;
    std::vector<int> touched;
    // Screen point (x, y) of a face to texel coordinates (s, t) of the
    // point its ray hits on this plane: a ratio of affine functions (the
    // ray w = forward + x right + y up meets the plane at c + h / (w.n) w).
    struct Homography {
      double d0, dx, dy, a0, ax, ay, b0, bx, by, cu, cv;
    } H{};
    const Vec3 co = sh.centre - pm.origin;
    auto set_face = [&](const Hemicube::Face& F) {
      H = {glm::dot(F.forward, pm.normal), glm::dot(F.right, pm.normal), glm::dot(F.up, pm.normal),
           h * glm::dot(F.forward, pm.u),  h * glm::dot(F.right, pm.u),  h * glm::dot(F.up, pm.u),
           h * glm::dot(F.forward, pm.v),  h * glm::dot(F.right, pm.v),  h * glm::dot(F.up, pm.v),
           glm::dot(co, pm.u),             glm::dot(co, pm.v)};
    };
    auto hit = [&](double x, double y, double& s, double& t) {
      const double d = H.d0 + H.dx * x + H.dy * y;
      if (!(d < 0.0)) return false;
      s = (H.cu + (H.a0 + H.ax * x + H.ay * y) / d) / pm.texel_u;
      t = (H.cv + (H.b0 + H.bx * x + H.by * y) / d) / pm.texel_v;
      return std::isfinite(s) && std::isfinite(t);
    };
    // The owner of the texel at (s, t), or -1 when it is not covered.
    auto owner_at = [&](double s, double t) {
      const int i = std::clamp(static_cast<int>(std::floor(s)), 0, pm.width - 1);
      const int j = std::clamp(static_cast<int>(std::floor(t)), 0, pm.height - 1);
      return owner_of_point(pm, coarse, j * pm.width + i, s, t);
    };
    auto add = [&](int texel, double f) {
      if (!(f > 0.0)) return;  // a zero weight would list the texel twice below
      if (acc.empty()) acc.assign(static_cast<size_t>(pm.texels()), 0.0);
      if (acc[texel] == 0.0) touched.push_back(texel);
      acc[texel] += f;
    };
    // A pixel's delta form factor is spread over the texels under its
    // footprint (the box around its four corners' points on this plane), in
    // proportion to their overlap: the limit of virtual oversampling, with
    // no samples to alias against the texel grid. Footprints of neighbouring
    // pixels share corners, so where the texel axes follow the screen's they
    // tile the plane exactly; otherwise their boxes overlap a little, which
    // blurs by at most one footprint and keeps each pixel's sum. A texel
    // that is not covered, or covered too little to be an element, passes
    // its share to its owner; with no owner the share goes to `fallback`
    // (the owner under the pixel's centre).
    std::vector<double> ws, wt;
    // A footprint a wall's foot crosses reaches the wall's other side,
    // which the pixel does not see (the wall hides it): its texels whose
    // part of the footprint lies beyond a foot, seen from the pixel's
    // centre, get nothing, and the others share the pixel. Spread over both
    // sides, the pixels seen just before a thin wall lit the room it seals
    // (0.5% of the lit side's radiosity where the wall stood on a texel
    // line). False when no foot touches the footprint.
    std::vector<int> near_feet;
    std::vector<double> kept_w;
    auto cut_by_wall = [&](double s0, double s1, double t0, double t1, int i0, int i1, int j0, int j1, double f,
                           int fallback, double sc, double tc) {
      near_feet.clear();
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
          const int idx = j * pm.width + i;
          if (!pm.wall_foot[static_cast<size_t>(idx)]) continue;
          const auto range = std::equal_range(pm.foot_at.begin(), pm.foot_at.end(), std::pair{idx, 0},
                                              [](const auto& x, const auto& y) { return x.first < y.first; });
          for (auto it = range.first; it != range.second; ++it) near_feet.push_back(it->second);
        }
      if (near_feet.empty()) return false;
      const int ci = std::clamp(static_cast<int>(std::floor(sc)), i0, i1),
                cj = std::clamp(static_cast<int>(std::floor(tc)), j0, j1);
      kept_w.assign(ws.size() * wt.size(), 0.0);
      double kept = 0.0;
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
          const double w = ws[i - i0] * wt[j - j0];
          if (!(w > 0.0)) continue;
          // The centre of the texel's part of the footprint.
          const St q{0.5 * (std::max(s0, static_cast<double>(i)) + std::min(s1, i + 1.0)),
                     0.5 * (std::max(t0, static_cast<double>(j)) + std::min(t1, j + 1.0))};
          bool beyond = false;
          if (i != ci || j != cj)
            for (const int n : near_feet) {
              const Pixmap::Foot& e = pm.feet[static_cast<size_t>(n)];
              if (segments_cross({sc, tc}, q, {e.s0, e.t0}, {e.s1, e.t1})) {
                beyond = true;
                break;
              }
            }
          if (beyond) continue;
          kept_w[static_cast<size_t>(j - j0) * ws.size() + (i - i0)] = w;
          kept += w;
        }
      if (!(kept > 0.0)) {
        add(fallback, f);
        return true;
      }
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
          const double w = kept_w[static_cast<size_t>(j - j0) * ws.size() + (i - i0)];
          if (!(w > 0.0)) continue;
          const int o = owner_of_point(pm, coarse, j * pm.width + i, sc, tc);
          add(o >= 0 ? o : fallback, f * w / kept);
        }
      ++over[k];
      return true;
    };
    auto spread = [&](double s0, double s1, double t0, double t1, double f, int fallback, double sc, double tc) {
      s0 = std::clamp(s0, 0.0, static_cast<double>(pm.width));
      s1 = std::clamp(s1, 0.0, static_cast<double>(pm.width));
      t0 = std::clamp(t0, 0.0, static_cast<double>(pm.height));
      t1 = std::clamp(t1, 0.0, static_cast<double>(pm.height));
      const int i0 = std::min(pm.width - 1, static_cast<int>(s0)), i1 = std::min(pm.width - 1, static_cast<int>(s1));
      const int j0 = std::min(pm.height - 1, static_cast<int>(t0)), j1 = std::min(pm.height - 1, static_cast<int>(t1));
      if (i0 == i1 && j0 == j1) {
        const int o = owner_of_point(pm, coarse, j0 * pm.width + i0, sc, tc);
        add(o >= 0 ? o : fallback, f);
        return;
      }
      // Overlap of [a, b] with each unit interval from i0 to i1; a footprint
      // of zero width (a pixel seen edge on) counts as one point.
      auto overlaps = [](double a, double b, int i0, int i1, std::vector<double>& w) {
        w.assign(static_cast<size_t>(i1 - i0 + 1), 0.0);
        if (i0 == i1 || !(b > a)) {
          w[0] = 1.0;
          return 1.0;
        }
        for (int i = i0; i <= i1; ++i) w[i - i0] = std::min(b, i + 1.0) - std::max(a, static_cast<double>(i));
        return b - a;
      };
      const double norm = f / (overlaps(s0, s1, i0, i1, ws) * overlaps(t0, t1, j0, j1, wt));
      if (!pm.wall_foot.empty() && cut_by_wall(s0, s1, t0, t1, i0, i1, j0, j1, f, fallback, sc, tc)) return;
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
          const int o = owner_of_point(pm, coarse, j * pm.width + i, sc, tc);
          add(o >= 0 ? o : fallback, norm * ws[i - i0] * wt[j - j0]);
        }
      ++over[k];
    };
    std::vector<double> cs, ct;
    std::vector<char> cok;
    for (int f = 0; f < 5; ++f) {
      int x0, x1, y0, y1;
      if (!projected_rect(cube, f, corners, x0, x1, y0, y1)) continue;
      const Hemicube::Face& F = cube.faces()[f];
      set_face(F);
      const double px = cube.pixel_size();
      // The points of the pixel corners (x - 1/2, y - 1/2), for x in
      // [x0, x1 + 1] and y in [y0, y1 + 1].
      const int cw = x1 - x0 + 2, ch = y1 - y0 + 2;
      cs.resize(static_cast<size_t>(cw) * ch);
      ct.resize(cs.size());
      cok.resize(cs.size());
      for (int b = 0; b < ch; ++b)
        for (int a = 0; a < cw; ++a) {
          const size_t c = static_cast<size_t>(b) * cw + a;
          cok[c] = hit(cube.pixel_x(x0 + a) - 0.5 * px, cube.pixel_y(f, y0 + b) - 0.5 * px, cs[c], ct[c]);
        }
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const int id = F.id[static_cast<size_t>(y) * F.width + x];
          if (id < 0 || layout.pixmap_of_patch[id] != k) continue;
          if (narrow) {
            pixels_dropped[k] += cube.delta(f, x, y);
            continue;
          }
          double s, t;
          if (!hit(cube.pixel_x(x), cube.pixel_y(f, y), s, t)) continue;
          int centre_owner = owner_at(s, t);
          if (centre_owner < 0) {
            // Rounding put the centre's point just outside the covered
            // part: the most covered texel around it.
            const int n = most_covered_around(pm, std::clamp(static_cast<int>(std::floor(s)), 0, pm.width - 1),
                                              std::clamp(static_cast<int>(std::floor(t)), 0, pm.height - 1), 0.0);
            if (n < 0) continue;
            centre_owner = pm.owner[n];
          }
          const double delta = cube.delta(f, x, y);
          const size_t c = static_cast<size_t>(y - y0) * cw + (x - x0);
          const size_t q[4] = {c, c + 1, c + cw, c + cw + 1};
          if (!(cok[q[0]] && cok[q[1]] && cok[q[2]] && cok[q[3]])) {
            // A corner beyond this plane's horizon: the centre's texel.
            add(centre_owner, delta);
            continue;
          }
          double s0 = cs[q[0]], s1 = s0, t0 = ct[q[0]], t1 = t0;
          for (int e = 1; e < 4; ++e) {
            s0 = std::min(s0, cs[q[e]]);
            s1 = std::max(s1, cs[q[e]]);
            t0 = std::min(t0, ct[q[e]]);
            t1 = std::max(t1, ct[q[e]]);
          }
          spread(s0, s1, t0, t1, delta, centre_owner, s, t);
        }
    }
    if (narrow) {
      NarrowPart part;
      receive_narrow(k, sh, reach, sky, polygons, add, part);
      exact_put[k] = part.far_sum;
      behind[k] = part.behind;
      near_parts[k] = std::move(part.near);
      near_values[k] = std::move(part.near_f);
      near_exact[k] = std::move(part.exact);
    }
    // The near field: every whole texel within reach that the hemicube saw,
    // or that the pixel toward its centre shows (a texel a hair away from
    // the shooter fills no pixel centre of its own).
    std::vector<char> near_texel;
    if (reach > 0.0 && !narrow) {
      const double cs = pm.s_of(sh.centre), ct = pm.t_of(sh.centre);
      const int i0 = std::max(0, static_cast<int>(std::floor(cs - reach / pm.texel_u)));
      const int i1 = std::min(pm.width - 1, static_cast<int>(std::ceil(cs + reach / pm.texel_u)));
      const int j0 = std::max(0, static_cast<int>(std::floor(ct - reach / pm.texel_v)));
      const int j1 = std::min(pm.height - 1, static_cast<int>(std::ceil(ct + reach / pm.texel_v)));
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
          const int texel = j * pm.width + i;
          if (!pm.whole[texel] || glm::length(pm.centroid[texel] - sh.centre) >= reach) continue;
          const bool seen = !acc.empty() && acc[texel] > 0.0;
          if (!seen) {
            const int id = cube.id_toward(pm.centroid[texel] - sh.centre);
            if (id < 0 || layout.pixmap_of_patch[id] != k) continue;
            if (acc.empty()) acc.assign(static_cast<size_t>(pm.texels()), 0.0);
            touched.push_back(texel);
          }
          if (near_texel.empty()) near_texel.assign(static_cast<size_t>(pm.texels()), 0);
          near_texel[texel] = 1;
        }
    }
    std::sort(touched.begin(), touched.end());
    std::vector<double> per(nsrc);
    std::vector<std::pair<Vec3, double>> points;
    for (int texel : touched) {
      const double f = acc[texel];
      if (near_texel.empty() || !near_texel[texel]) {
        if (f > 0.0) far_parts[k].push_back({static_cast<uint32_t>(pm.first + texel), static_cast<float>(f)});
        continue;
      }
      std::fill(per.begin(), per.end(), 0.0);
      points.clear();
      // A plain square no line cuts is one fan of two triangles.
      if (plain_square(pm, texel) && pieces_of(pm.first + texel).size() <= 2) {
        const double a = 0.25 * pm.texel_u * pm.texel_v;
        for (int q = 0; q < 4; ++q)
          points.emplace_back(pm.centroid[texel] + ((q % 2 ? 0.25 : -0.25) * pm.texel_u) * pm.u +
                                  ((q / 2 ? 0.25 : -0.25) * pm.texel_v) * pm.v,
                              a);
      } else {
        for (const int d : pieces_of(pm.first + texel)) {
          const std::array<Vec3, 3> p = piece_corners(d);
          const double a = triangle_area(p[0], p[1], p[2]) / 3.0;
          for (int m = 0; m < 3; ++m) points.emplace_back(rule_point(p, m), a);
        }
      }
      // F(q -> texel) = sum over the points of w F(x -> q's polygons) / A_q.
      for (const SourcePolygon& poly : polygons) {
        double f = 0.0;
        for (const auto& [x, w] : points) f += w * point_polygon_form_factor(x, pm.normal, poly.v.data(), poly.count, own.normal);
        per[poly.q] += f / own.area[sh.texels[poly.q]];
      }
      near_hemicube[k] += f;
      near_parts[k].push_back(static_cast<uint32_t>(pm.first + texel));
      for (size_t q = 0; q < nsrc; ++q) {
        near_values[k].push_back(static_cast<float>(per[q]));
        near_exact[k][q] += per[q];
      }
    }
  });
  // Each source texel's far entries give or take what the near field
  // changed, so that its row keeps the hemicube's sum (1 in a closed scene).
  double far = 0.0, hemicube = 0.0;
  std::vector<double> exact(nsrc, 0.0), open_gain(nsrc, 0.0);
  Row row;
  for (int k = 0; k < npm; ++k) {
    for (const RowEntry& e : far_parts[k]) far += e.f;
    // What the hemicube gave a narrow pixmap counts, so that the row keeps
    // the hemicube's sum (1 in a closed scene): the pixels that saw it would
    // have seen what lies behind it, and those that missed it saw what it
    // hides. Where open sky lies behind it, its own factors count instead.
    hemicube += near_hemicube[k] + pixels_dropped[k] - exact_put[k];
    for (size_t q = 0; q < nsrc; ++q)
      open_gain[q] += (1.0 - behind[k]) * (exact_put[k] + near_exact[k][q] - pixels_dropped[k]);
    for (size_t q = 0; q < nsrc; ++q) exact[q] += near_exact[k][q];
    row.far.insert(row.far.end(), far_parts[k].begin(), far_parts[k].end());
    row.near.insert(row.near.end(), near_parts[k].begin(), near_parts[k].end());
    row.near_f.insert(row.near_f.end(), near_values[k].begin(), near_values[k].end());
    spread_pixels += over[k];
  }
  hemicube += far;
  row.far_scale.resize(nsrc);
  for (size_t q = 0; q < nsrc; ++q)
    row.far_scale[q] = static_cast<float>(far > 0.0 ? std::max(0.0, (hemicube + open_gain[q] - exact[q]) / far) : 1.0);
  return row;
}

void PixmapSolver::Impl::build_display() {
  // Per pixmap: its coarse triangles cut at texel lines, vertices welded
  // within the pixmap.
  std::vector<std::vector<int>> triangles_of(layout.pixmaps.size());
  for (int t = 0; t < coarse.triangle_count(); ++t) triangles_of[layout.pixmap_of_patch[coarse.patch[t]]].push_back(t);
  for (size_t k = 0; k < layout.pixmaps.size(); ++k) {
    display_first.push_back(display.triangles.size());
    const Pixmap& pm = layout.pixmaps[k];
    // Welding: points within 1e-9 texel of each other are one vertex.
    std::unordered_map<long long, std::vector<int>> lit_cells;
    const double q = 1e-7;
    auto key = [](long long a, long long b) { return a * 1000003LL + b; };
    // Triangles inside closed objects get vertices of their own (value 0),
    // so that the lit texels next to them do not spread light under objects.
    std::unordered_map<long long, std::vector<int>> dark_cells;
    auto vertex = [&](const St& p, bool dark) {
      auto& cells = dark ? dark_cells : lit_cells;
      const long long a = std::llround(p.s / q), b = std::llround(p.t / q);
      for (long long da = -1; da <= 1; ++da)
        for (long long db = -1; db <= 1; ++db) {
          const auto it = cells.find(key(a + da, b + db));
          if (it == cells.end()) continue;
          for (int v : it->second)
            if (std::abs(display_st[v].s - p.s) < 1e-9 && std::abs(display_st[v].t - p.t) < 1e-9) return v;
        }
      const int v = static_cast<int>(display.positions.size());
      display.positions.push_back(point_of(pm, p.s, p.t));
      display_st.push_back(p);
      display_pixmap.push_back(static_cast<int>(k));
      display_dark.push_back(dark ? 1 : 0);
      cells[key(a, b)].push_back(v);
      return v;
    };
    for (int t : triangles_of[k]) {
      St tri[3];
      for (int c = 0; c < 3; ++c) tri[c] = st_of(pm, coarse.positions[coarse.triangles[t][c]]);
      const int patch = coarse.patch[t];
      // A piece's triangles (a fan), dark or lit.
      auto emit = [&](const St* poly, int n, long long texel, bool dark) {
        double a;
        St c;
        area_centroid(poly, n, a, c);
        if (a == 0.0) return;
        int ids[12];
        for (int m = 0; m < n; ++m) ids[m] = vertex(poly[m], dark);
        for (int m = 1; m + 1 < n; ++m) {
          std::array<int, 3> tri_ids = {ids[0], ids[m], ids[m + 1]};
          if (tri_ids[0] == tri_ids[1] || tri_ids[1] == tri_ids[2] || tri_ids[0] == tri_ids[2]) continue;
          // Counter-clockwise around the patch normal: (s, t) is a
          // right-handed frame with normal u x v.
          if (a < 0.0) std::swap(tri_ids[1], tri_ids[2]);
          display.triangles.push_back(tri_ids);
          display.patch.push_back(patch);
          display_texel.push_back(dark ? -1 : texel);
        }
      };
      const bool dark = layout.enclosed[t];
      for_each_piece(pm, tri, [&](int i, int j, const St* poly, int n) {
        const int owner = owner_of_piece(pm, j * pm.width + i, t);
        emit(poly, n, owner >= 0 && !dark ? pm.first + owner : -1, dark || owner < 0);
      });
    }
  }
  display_first.push_back(display.triangles.size());
  pieces_begin.assign(static_cast<size_t>(layout.texels) + 1, 0);
  for (const long long g : display_texel)
    if (g >= 0) ++pieces_begin[static_cast<size_t>(g) + 1];
  for (size_t g = 0; g + 1 < pieces_begin.size(); ++g) pieces_begin[g + 1] += pieces_begin[g];
  pieces.resize(pieces_begin.back());
  {
    std::vector<uint32_t> at(pieces_begin.begin(), pieces_begin.end() - 1);
    for (size_t d = 0; d < display_texel.size(); ++d)
      if (display_texel[d] >= 0) pieces[at[static_cast<size_t>(display_texel[d])]++] = static_cast<int>(d);
  }
  extent.resize(layout.pixmaps.size());
  for (size_t k = 0; k < layout.pixmaps.size(); ++k) {
    Extent& e = extent[k];
    double area = 0.0;
    for (size_t d = display_first[k]; d < display_first[k + 1]; ++d) {
      if (display_texel[d] < 0) continue;
      const auto& t = display.triangles[d];
      const double a = triangle_area(display.positions[t[0]], display.positions[t[1]], display.positions[t[2]]);
      e.centre += a * (display.positions[t[0]] + display.positions[t[1]] + display.positions[t[2]]) / 3.0;
      area += a;
    }
    if (!(area > 0.0)) continue;
    e.centre /= area;
    for (size_t d = display_first[k]; d < display_first[k + 1]; ++d)
      if (display_texel[d] >= 0)
        for (int v : display.triangles[d]) e.radius = std::max(e.radius, glm::length(display.positions[v] - e.centre));
    e.width = area / (2.0 * e.radius);
  }
}

bool PixmapSolver::Impl::narrow_receiver(int k, const Shooter& sh, double pixel, double reach) const {
  // Pixmap k is narrow for shooter sh when, at its nearest point to the
  // hemicube's centre, it is
  // - narrower than kSubPixel pixels of the top face's centre (where pixels
  //   subtend the widest angle): the item buffer, which samples pixel
  //   centres, would see it in no pixel or in whole rows of them, and its
  //   share would alias with the shooter's position (a 1 mm strip 3 m under
  //   a lamp came out at 0.2 and at 2.5 times its radiosity at hemicube
  //   resolutions 128 and 512); or
  // - narrower than the block (its radius plus a texel's diagonal) and
  //   within `reach` of it, where the near field's points on the source
  //   texels would see it edge on or not at all (a picture's 1 mm edges
  //   beside the wall it hangs on got a twentieth of the wall's light, and
  //   the 9 cm boxes of a box field 6% too little in all).
  constexpr double kSubPixel = 4.0;
  const Extent& e = extent[k];
  if (!(e.width > 0.0)) return false;
  const bool small = e.width < reach / kNearField;
  const double resolved = e.width / (kSubPixel * pixel);  // nearer than this, the pixels resolve it
  auto narrow_at = [&](double d) { return d >= resolved || (small && d < reach); };
  const double centre = glm::length(e.centre - sh.centre);
  const double lo = std::max(0.0, centre - e.radius), hi = centre + e.radius;
  if (narrow_at(lo) == narrow_at(hi) && (!small || lo >= reach || hi < reach)) return narrow_at(lo);
  double nearest = INFINITY;
  for (size_t d = display_first[k]; d < display_first[k + 1]; ++d) {
    if (display_texel[d] < 0) continue;
    const auto& t = display.triangles[d];
    nearest = std::min(nearest, distance_to_triangle(sh.centre, make_triangle(display.positions[t[0]], display.positions[t[1]],
                                                                               display.positions[t[2]], layout.pixmaps[k].normal)));
  }
  return narrow_at(nearest);
}

std::vector<PixmapSolver::Impl::SourcePolygon> PixmapSolver::Impl::source_polygons(const Shooter& sh) const {
  const Pixmap& own = layout.pixmaps[sh.pixmap];
  std::vector<SourcePolygon> polygons;
  for (size_t q = 0; q < sh.texels.size(); ++q) {
    const int src = sh.texels[q];
    if (plain_square(own, src)) {
      polygons.push_back({q, texel_square(own, src), 4});
      continue;
    }
    for (const int d : pieces_of(own.first + src)) {
      const std::array<Vec3, 3> p = piece_corners(d);
      polygons.push_back({q, {p[0], p[1], p[2], Vec3(0.0)}, 3});
    }
  }
  return polygons;
}

void PixmapSolver::Impl::receive_narrow(int k, const Shooter& sh, double reach, bool sky,
                                        const std::vector<SourcePolygon>& polygons,
                                        const std::function<void(int, double)>& add, NarrowPart& out) const {
  // Per lit display triangle (a piece of one texel). Its texel's centroid
  // beyond `reach`, as the hemicube would: Lambert's factor from the block's
  // centre, seen or not by one shadow ray to the piece's centroid. Within
  // it, from each source texel by reciprocity,
  // F = A_piece / A_texel x F(piece -> texel), the
  // latter Lambert's factor from three points of the piece (a rule exact
  // for quadratics) to each polygon of the texel, seen or not by a ray
  // between the centroids: a piece is narrow, so its points see what it
  // sees, and a face a millimetre off a wall gets the half of its light that
  // comes from the wall right beside it (from the block's centre the wall
  // sees it edge on).
  const Pixmap& pm = layout.pixmaps[k];
  const Pixmap& own = layout.pixmaps[sh.pixmap];
  const size_t nsrc = sh.texels.size();
  std::vector<Vec3> far_to;
  std::vector<double> far_f;
  std::vector<int> far_texel, far_patch;
  struct Piece {
    int texel, patch;
    std::array<Vec3, 3> v;
    Vec3 centroid;
    double area;
  };
  std::vector<Piece> near_pieces;
  for (size_t d = display_first[k]; d < display_first[k + 1]; ++d) {
    if (display_texel[d] < 0) continue;
    const auto& t = display.triangles[d];
    const std::array<Vec3, 3> p = {display.positions[t[0]], display.positions[t[1]], display.positions[t[2]]};
    const Vec3 c = (p[0] + p[1] + p[2]) / 3.0;
    const int texel = static_cast<int>(display_texel[d] - pm.first);
    if (glm::length(pm.centroid[texel] - sh.centre) < reach) {  // a texel is near or far as a whole
      near_pieces.push_back({texel, display.patch[d], p, c, triangle_area(p[0], p[1], p[2])});
      continue;
    }
    const double f = point_polygon_form_factor(sh.centre, own.normal, p.data(), 3, pm.normal);
    if (!(f > 0.0)) continue;
    far_to.push_back(c);
    far_f.push_back(f);
    far_texel.push_back(texel);
    far_patch.push_back(display.patch[d]);
  }
  // Whether a surface lies behind a piece, seen from the block's centre,
  // weighted by the piece's factor; asked only when the hemicube sees some
  // sky. (Behind a face of a closed object lies the back of another: in a
  // closed scene the pixels around the face's direction still see the
  // scene, and the row keeps its sum.)
  double weight = 0.0, weight_behind = 0.0;
  auto look_behind = [&](const Vec3& c, int patch, double w) {
    if (!sky) return;
    weight += w;
    if (vis->ray_end(c, c - sh.centre, patch) != Visibility::RayEnd::nowhere) weight_behind += w;
  };
  if (!far_to.empty()) {
    const std::vector<Vec3> from(far_to.size(), sh.centre);
    std::vector<unsigned char> seen(far_to.size());
    vis->visible_off_surfaces(from.data(), own.normal, far_to.data(), pm.normal, far_to.size(), -1, -1, seen.data());
    for (size_t i = 0; i < far_to.size(); ++i)
      if (seen[i]) {
        add(far_texel[i], far_f[i]);
        out.far_sum += far_f[i];
        look_behind(far_to[i], far_patch[i], far_f[i]);
      }
  }
  out.exact.assign(nsrc, 0.0);
  if (near_pieces.empty()) {
    if (weight > 0.0) out.behind = weight_behind / weight;
    return;
  }
  std::vector<Vec3> centres, from, to;
  for (const SourcePolygon& poly : polygons) centres.push_back(poly.centroid());
  for (const Piece& piece : near_pieces) {
    from.insert(from.end(), polygons.size(), piece.centroid);
    to.insert(to.end(), centres.begin(), centres.end());
  }
  std::vector<unsigned char> seen(from.size());
  vis->visible_off_surfaces(from.data(), pm.normal, to.data(), own.normal, from.size(), -1, -1, seen.data());
  std::map<int, std::vector<double>> per_texel;
  for (size_t n = 0; n < near_pieces.size(); ++n) {
    const Piece& piece = near_pieces[n];
    std::vector<double>& per = per_texel[piece.texel];
    per.resize(nsrc, 0.0);
    double received = 0.0;  // F from the block (area-weighted over its texels)
    for (size_t m = 0; m < polygons.size(); ++m) {
      if (!seen[n * polygons.size() + m]) continue;
      const SourcePolygon& poly = polygons[m];
      double f = 0.0;
      for (int a = 0; a < 3; ++a) {
        const Vec3 x = rule_point(piece.v, a);
        f += point_polygon_form_factor(x, pm.normal, poly.v.data(), poly.count, own.normal);
      }
      per[poly.q] += piece.area * f / (3.0 * own.area[sh.texels[poly.q]]);
      received += piece.area * f / (3.0 * sh.area);
    }
    if (received > 0.0) look_behind(piece.centroid, piece.patch, received);
  }
  if (weight > 0.0) out.behind = weight_behind / weight;
  for (const auto& [texel, per] : per_texel) {
    out.near.push_back(static_cast<uint32_t>(pm.first + texel));
    for (size_t q = 0; q < nsrc; ++q) {
      out.near_f.push_back(static_cast<float>(per[q]));
      out.exact[q] += per[q];
    }
  }
}

PixmapSolver::PixmapSolver(const Scene& input, const PixmapOptions& options, const SolveOptions& solve)
    : impl_(std::make_unique<Impl>(input, options, solve)) {
  Impl& m = *impl_;
  const Scene& scene = m.scene;
  check_options(options);
  m.coarse = outline_triangulation(scene);
  const double memory = memory_limit_bytes(solve);
  m.vis = std::make_unique<Visibility>(scene);
  m.layout = layout_of(scene, m.coarse, options, memory, m.vis.get());
  if (m.layout.texels >= (1LL << 32)) throw NumericalError(scene.source + ": more than 2^32 texels; use a larger texel_size", {"texel_size"});
  // The hemicube renders whole polygons (their coarsest triangulation): the
  // contact lines would only add triangles.
  const Mesh polygons = triangulate_patches(scene);
  for (int t = 0; t < polygons.triangle_count(); ++t) {
    const auto& tri = polygons.triangles[t];
    const int p = polygons.patch[t];
    m.polygons.push_back({polygons.positions[tri[0]], polygons.positions[tri[1]], polygons.positions[tri[2]],
                          scene.patches[p].normal, p});
  }
  for (const Pixmap& pm : m.layout.pixmaps) {
    m.rho.push_back(scene.materials[pm.material].reflectance);
    m.emission.push_back(scene.materials[pm.material].emission);
  }
  for (size_t k = 0; k < m.layout.pixmaps.size(); ++k) {
    const Pixmap& pm = m.layout.pixmaps[k];
    for (long long i = 0; i < pm.texels(); ++i)
      if (pm.owner[i] == i) m.power_emitted += m.emission[k] * pm.area[i];
  }
  {
    const ElementSet el = make_elements(scene, m.coarse);
    for (size_t t = 0; t < el.size(); ++t)
      if (m.layout.enclosed[t]) m.power_enclosed += el.emission[t] * el.triangle[t].area;
    m.warnings = enclosed_emitter_warnings(scene, el, m.layout.enclosed);
  }
  m.shooter_of.assign(static_cast<size_t>(m.layout.texels), -1);
  for (size_t s = 0; s < m.layout.shooters.size(); ++s)
    for (int t : m.layout.shooters[s].texels) m.shooter_of[m.global(m.layout.shooters[s].pixmap, t)] = static_cast<int>(s);
  m.row_budget = std::max(0.0, memory - kBytesPerTexel * static_cast<double>(m.layout.texels));
  m.build_display();
}

PixmapSolver::~PixmapSolver() = default;

const Scene& PixmapSolver::scene() const { return impl_->scene; }
const PixmapLayout& PixmapSolver::layout() const { return impl_->layout; }

Rgb PixmapSolver::power_emitted() const { return impl_->power_emitted; }
Rgb PixmapSolver::power_enclosed() const { return impl_->power_enclosed; }
const std::vector<std::string>& PixmapSolver::warnings() const { return impl_->warnings; }

PixmapState PixmapSolver::initial_state() const {
  const Impl& m = *impl_;
  PixmapState st;
  st.scene_fingerprint = scene_fingerprint(m.scene);
  st.texel_size = m.layout.texel_size;
  st.max_texels = m.options.max_texels;
  st.hemicube_res = m.options.hemicube_res;
  st.block = m.options.block;
  for (size_t k = 0; k < m.layout.pixmaps.size(); ++k) {
    const Pixmap& pm = m.layout.pixmaps[k];
    st.sizes.push_back({pm.width, pm.height});
    std::vector<float> b(static_cast<size_t>(pm.texels()) * 3, 0.0f);
    for (long long i = 0; i < pm.texels(); ++i)
      if (pm.owner[i] == i)
        for (int c = 0; c < 3; ++c) b[i * 3 + c] = static_cast<float>(m.emission[k][c]);
    st.radiosity.push_back(b);
    st.unshot.push_back(std::move(b));
  }
  return st;
}

Rgb PixmapSolver::ambient(const PixmapState& state) const {
  // Cohen et al. 1988: the unshot power spread over the scene's area,
  // times the interreflection factor 1 / (1 - mean rho); in an open scene
  // only the share of it that stays, taken as the share of the power ended
  // so far that was absorbed rather than escaped, so that the power the
  // ambient term absorbs is what the unshot power will leave in the scene.
  const Impl& m = *impl_;
  Rgb unshot(0.0), rho_area(0.0);
  double area = 0.0;
  for (size_t k = 0; k < m.layout.pixmaps.size(); ++k) {
    const Pixmap& pm = m.layout.pixmaps[k];
    for (long long i = 0; i < pm.texels(); ++i)
      if (pm.owner[i] == i) {
        for (int c = 0; c < 3; ++c) unshot[c] += static_cast<double>(state.unshot[k][i * 3 + c]) * pm.area[i];
        rho_area += m.rho[k] * pm.area[i];
        area += pm.area[i];
      }
  }
  if (!(area > 0.0)) return Rgb(0.0);
  Rgb amb(0.0);
  for (int c = 0; c < 3; ++c) {
    const double ended = state.power_absorbed[c] + state.power_escaped[c];
    const double stays = ended > 0.0 ? state.power_absorbed[c] / ended : 1.0;
    amb[c] = stays * unshot[c] / area / (1.0 - rho_area[c] / area);
  }
  return amb;
}

std::vector<std::vector<float>> PixmapSolver::display(const PixmapState& state, const Rgb& ambient) const {
  const Impl& m = *impl_;
  std::vector<std::vector<float>> out(m.layout.pixmaps.size());
  for (size_t k = 0; k < m.layout.pixmaps.size(); ++k) {
    const Pixmap& pm = m.layout.pixmaps[k];
    out[k].assign(static_cast<size_t>(pm.texels()) * 3, 0.0f);
    for (long long i = 0; i < pm.texels(); ++i) {
      const int o = pm.owner[i];
      if (o < 0) continue;
      for (int c = 0; c < 3; ++c)
        out[k][i * 3 + c] = static_cast<float>(static_cast<double>(state.radiosity[k][o * 3 + c]) + m.rho[k][c] * ambient[c]);
    }
  }
  return out;
}

std::vector<std::vector<std::pair<long long, double>>> PixmapSolver::form_factors(int s) const {
  if (s < 0 || s >= static_cast<int>(impl_->layout.shooters.size()))
    throw InputError("shooter " + std::to_string(s) + " does not exist");
  Hemicube cube(impl_->options.hemicube_res);
  long long over = 0;
  Row row;
  run_in_arena(impl_->solve.threads, [&] { row = impl_->compute_row(s, cube, over); });
  const size_t nsrc = row.far_scale.size();
  std::vector<std::vector<std::pair<long long, double>>> out(nsrc);
  for (size_t q = 0; q < nsrc; ++q) {
    for (const RowEntry& e : row.far) out[q].emplace_back(e.texel, static_cast<double>(e.f) * row.far_scale[q]);
    for (size_t n = 0; n < row.near.size(); ++n) out[q].emplace_back(row.near[n], row.near_f[n * nsrc + q]);
    std::sort(out[q].begin(), out[q].end());
  }
  return out;
}

PixmapRun PixmapSolver::run(PixmapState start, const PixmapCallbacks& cb) const {
  const Impl& m = *impl_;
  const PixmapLayout& L = m.layout;
  PixmapRun r;
  r.state = std::move(start);
  PixmapState& st = r.state;
  r.power_emitted = m.power_emitted;
  const size_t ns = L.shooters.size();
  std::vector<double> power(ns, 0.0);  // sum of the channels' unshot power
  auto shooter_power = [&](size_t s) {
    const Shooter& sh = L.shooters[s];
    const Pixmap& pm = L.pixmaps[sh.pixmap];
    double p = 0.0;
    for (int t : sh.texels)
      for (int c = 0; c < 3; ++c) p += static_cast<double>(st.unshot[sh.pixmap][t * 3 + c]) * pm.area[t];
    return p;
  };
  for (size_t s = 0; s < ns; ++s) power[s] = shooter_power(s);
  const double emitted = r.power_emitted.x + r.power_emitted.y + r.power_emitted.z;
  const double target = m.options.unshot * emitted;
  std::vector<Row> cache(ns);
  std::vector<char> cached(ns, 0);
  double cache_bytes = 0.0;
  std::vector<long long> stamp(ns, -1);
  std::vector<int> touched;
  std::vector<Rgb> phis;  // per source texel of the shooter: its unshot power
  Hemicube cube(m.options.hemicube_res);
  const double log_goal = target > 0.0 && emitted > 0.0 ? std::log(target / emitted) : 0.0;

  run_in_arena(m.solve.threads, [&] {
    while (true) {
      double unshot = 0.0;
      size_t best = ns;
      for (size_t s = 0; s < ns; ++s) {
        unshot += power[s];
        if (power[s] > 0.0 && (best == ns || power[s] > power[best])) best = s;
      }
      r.unshot_fraction = emitted > 0.0 ? unshot / emitted : 0.0;
      if (cb.progress && emitted > 0.0) {
        double f = log_goal < 0.0 && unshot > 0.0 ? std::log(unshot / emitted) / log_goal : 1.0;
        if (m.options.shots > 0) f = std::max(f, static_cast<double>(st.shots) / static_cast<double>(m.options.shots));
        cb.progress("shots", std::clamp(f, 0.0, 1.0));
      }
      if (best == ns || unshot <= target) break;
      if (m.options.shots > 0 && st.shots >= m.options.shots) break;
      if (cb.cancelled && cb.cancelled()) {
        r.interrupted = true;
        break;
      }
      // The row of the shooter: cached, or rendered now.
      const auto t0 = Clock::now();
      Row fresh;
      const Row* row = &cache[best];
      if (!cached[best]) {
        fresh = m.compute_row(static_cast<int>(best), cube, r.pixels_spread);
        ++r.rows_computed;
        const double bytes = fresh.bytes();
        if (cache_bytes + bytes <= m.row_budget) {
          cache[best] = std::move(fresh);
          cached[best] = 1;
          cache_bytes += bytes;
          ++r.rows_cached;
        } else {
          row = &fresh;
        }
      }
      r.seconds_hemicubes += seconds_since(t0);
      const auto t1 = Clock::now();
      // Shoot: the block's unshot power leaves; each texel it reaches gets
      // rho times the power arriving / its area: along the far entries the
      // source texels' power times their far_scale, along the near ones
      // each source texel's own.
      const Shooter& sh = L.shooters[best];
      const Pixmap& spm = L.pixmaps[sh.pixmap];
      const size_t nsrc = sh.texels.size();
      phis.assign(nsrc, Rgb(0.0));
      Rgb phi(0.0), phi_far(0.0);
      for (size_t q = 0; q < nsrc; ++q) {
        const int t = sh.texels[q];
        for (int c = 0; c < 3; ++c) {
          float& u = st.unshot[sh.pixmap][t * 3 + c];
          phis[q][c] = static_cast<double>(u) * spm.area[t];
          u = 0.0f;
        }
        phi += phis[q];
        phi_far += phis[q] * static_cast<double>(row->far_scale[q]);
      }
      power[best] = 0.0;
      Rgb received(0.0);
      int k = -1;
      long long k_end = 0;
      ++st.shots;
      ++r.shots_this_run;
      touched.clear();
      auto deposit = [&](uint32_t texel, const Rgb& arriving) {
        if (k < 0 || texel < L.pixmaps[k].first || texel >= k_end) {
          k = m.pixmap_of_global(texel);
          k_end = L.pixmaps[k].first + L.pixmaps[k].texels();
        }
        const Pixmap& pm = L.pixmaps[k];
        const long long i = texel - pm.first;
        received += arriving;
        for (int c = 0; c < 3; ++c) {
          const double dh = arriving[c] / pm.area[i];
          const double db = m.rho[k][c] * dh;
          float& b = st.radiosity[k][i * 3 + c];
          float& u = st.unshot[k][i * 3 + c];
          b = static_cast<float>(static_cast<double>(b) + db);
          u = static_cast<float>(static_cast<double>(u) + db);
          st.power_absorbed[c] += (1.0 - m.rho[k][c]) * arriving[c];
        }
        const int s = m.shooter_of[texel];
        if (s >= 0 && stamp[s] != st.shots) {
          stamp[s] = st.shots;
          touched.push_back(s);
        }
      };
      for (const RowEntry& e : row->far) deposit(e.texel, phi_far * static_cast<double>(e.f));
      for (size_t n = 0; n < row->near.size(); ++n) {
        Rgb arriving(0.0);
        for (size_t q = 0; q < nsrc; ++q) arriving += phis[q] * static_cast<double>(row->near_f[n * nsrc + q]);
        deposit(row->near[n], arriving);
      }
      for (int c = 0; c < 3; ++c) st.power_escaped[c] += std::max(0.0, phi[c] - received[c]);
      for (int s : touched) power[s] = shooter_power(static_cast<size_t>(s));
      r.seconds_shots += seconds_since(t1);
      if (cb.on_snapshot && cb.snapshot_every > 0 && st.shots % cb.snapshot_every == 0) cb.on_snapshot(st);
    }
  });
  r.ambient = ambient(st);
  for (int c = 0; c < 3; ++c) {
    double bmax = 0.0, umax = 0.0;
    for (size_t k = 0; k < L.pixmaps.size(); ++k)
      for (size_t i = static_cast<size_t>(c); i < st.radiosity[k].size(); i += 3) {
        bmax = std::max(bmax, static_cast<double>(st.radiosity[k][i]));
        umax = std::max(umax, static_cast<double>(st.unshot[k][i]));
      }
    r.residual[c] = bmax > 0.0 ? umax / bmax : 0.0;
  }
  return r;
}

void PixmapSolver::display_mesh(const std::vector<std::vector<float>>& texels, Mesh& mesh, Solution& solution,
                                std::vector<int>& texel_of_triangle) const {
  const Impl& m = *impl_;
  const PixmapLayout& L = m.layout;
  mesh = m.display;
  solution.element.assign(mesh.triangles.size(), Rgb(0.0));
  texel_of_triangle.assign(mesh.triangles.size(), -1);
  auto value = [&](long long g) {
    const int k = m.pixmap_of_global(g);
    const size_t i = static_cast<size_t>(g - L.pixmaps[k].first) * 3;
    return Rgb(texels[k][i], texels[k][i + 1], texels[k][i + 2]);
  };
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const long long g = m.display_texel[t];
    // Inside a closed object: no light, but what an emitter emits there
    // (power_enclosed).
    if (m.display_dark[static_cast<size_t>(mesh.triangles[t][0])])
      solution.element[t] = m.emission[static_cast<size_t>(m.display_pixmap[static_cast<size_t>(mesh.triangles[t][0])])];
    if (g < 0) continue;
    solution.element[t] = value(g);
    texel_of_triangle[t] = static_cast<int>(g - L.pixmaps[m.pixmap_of_global(g)].first);
  }
  NodalField& nodal = solution.nodal;
  nodal.points = mesh.positions;
  nodal.source_vertex.resize(mesh.positions.size());
  std::iota(nodal.source_vertex.begin(), nodal.source_vertex.end(), 0);
  nodal.corners = mesh.triangles;
  nodal.radiosity.assign(mesh.positions.size(), Rgb(0.0));
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    if (m.display_dark[v]) {
      nodal.radiosity[v] = m.emission[static_cast<size_t>(m.display_pixmap[v])];
      continue;
    }
    const int k = m.display_pixmap[v];
    const Pixmap& pm = L.pixmaps[k];
    const St p = m.display_st[v];
    // Bilinear over the texel centres around p, covered texels only.
    const int i0 = static_cast<int>(std::floor(p.s - 0.5)), j0 = static_cast<int>(std::floor(p.t - 0.5));
    const double fs = p.s - 0.5 - i0, ft = p.t - 0.5 - j0;
    Rgb sum(0.0);
    double wsum = 0.0;
    for (int dj = 0; dj <= 1; ++dj)
      for (int di = 0; di <= 1; ++di) {
        const int i = i0 + di, j = j0 + dj;
        if (i < 0 || j < 0 || i >= pm.width || j >= pm.height) continue;
        const size_t idx = static_cast<size_t>(j) * pm.width + i;
        if (pm.owner[idx] < 0) continue;
        const double w = (di ? fs : 1.0 - fs) * (dj ? ft : 1.0 - ft);
        sum += w * Rgb(texels[k][idx * 3], texels[k][idx * 3 + 1], texels[k][idx * 3 + 2]);
        wsum += w;
      }
    if (wsum > 1e-12) {
      nodal.radiosity[v] = sum / wsum;
    } else {
      // A vertex with no covered texel centre around it with weight: the
      // texel it lies in (clamped to the grid).
      const int i = std::clamp(static_cast<int>(std::floor(p.s)), 0, pm.width - 1);
      const int j = std::clamp(static_cast<int>(std::floor(p.t)), 0, pm.height - 1);
      const int o = pm.owner[static_cast<size_t>(j) * pm.width + i];
      if (o >= 0) nodal.radiosity[v] = Rgb(texels[k][o * 3], texels[k][o * 3 + 1], texels[k][o * 3 + 2]);
    }
  }
}

void PixmapSolver::display_uv(std::vector<std::array<double, 2>>& uv, std::vector<int>& pixmap) const {
  const Impl& m = *impl_;
  uv.resize(m.display_st.size());
  for (size_t v = 0; v < uv.size(); ++v) {
    const Pixmap& pm = m.layout.pixmaps[m.display_pixmap[v]];
    uv[v] = {m.display_st[v].s / pm.width, m.display_st[v].t / pm.height};
  }
  pixmap = m.display_pixmap;
}

}  // namespace radmesh
