// Per-vertex radiosity for display.

#include "radmesh/solve.h"

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <numbers>
#include <numeric>
#include <optional>

namespace radmesh {

namespace {

// Least-squares plane through the element values at the centroids of
// `tris`, evaluated at vertex v; empty when the centroids (nearly) line up.
std::optional<Rgb> fit_plane_at(const Scene& scene, const Mesh& mesh, const std::vector<Rgb>& element, int v,
                                const std::vector<int>& tris) {
  const Vec3 n = scene.patches[static_cast<size_t>(mesh.patch[static_cast<size_t>(tris[0])])].normal;
  const Vec3 u = glm::normalize(std::abs(n.x) < 0.6 ? glm::cross(Vec3(1, 0, 0), n) : glm::cross(Vec3(0, 1, 0), n));
  const Vec3 w = glm::cross(n, u);
  double m[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  Rgb rhs[3] = {Rgb(0.0), Rgb(0.0), Rgb(0.0)};
  double scale = 0.0;
  for (int t : tris) {
    const Vec3 d = mesh.centroid(t) - mesh.positions[static_cast<size_t>(v)];
    const double row[3] = {1.0, glm::dot(d, u), glm::dot(d, w)};
    const double a = mesh.area(t);
    scale = std::max(scale, glm::length(d));
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) m[r][c] += a * row[r] * row[c];
      rhs[r] += a * row[r] * element[static_cast<size_t>(t)];
    }
  }
  // Cramer's rule for the constant term, with a conditioning check.
  const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                     m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  if (!(std::abs(det) > 1e-6 * m[0][0] * m[0][0] * m[0][0] * std::pow(scale, 4))) return std::nullopt;
  Rgb c0(0.0);
  for (int ch = 0; ch < 3; ++ch) {
    const double r0 = rhs[0][ch], r1 = rhs[1][ch], r2 = rhs[2][ch];
    c0[ch] = (r0 * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (r1 * m[2][2] - m[1][2] * r2) +
              m[0][2] * (r1 * m[2][1] - m[1][1] * r2)) /
             det;
  }
  return c0;
}

// Triangles across each edge, as sorted (edge key, triangle): made on first
// use (widening a degenerate fit, rare).
struct EdgeNeighbours {
  const Mesh& mesh;
  const FeatureEdges& features;
  std::vector<std::pair<uint64_t, int>> edge_tris;

  // The triangles across t's edges that are not feature edges.
  std::vector<int> operator()(int t) {
    const size_t nt = mesh.triangles.size();
    if (edge_tris.empty()) {
      edge_tris.reserve(3 * nt);
      for (size_t u = 0; u < nt; ++u) {
        const auto& tri = mesh.triangles[u];
        for (size_t c = 0; c < 3; ++c)
          edge_tris.push_back({undirected_edge_key(tri[c], tri[(c + 1) % 3]), static_cast<int>(u)});
      }
      std::sort(edge_tris.begin(), edge_tris.end());
    }
    std::vector<int> out;
    for (int c = 0; c < 3; ++c) {
      const int x = mesh.triangles[static_cast<size_t>(t)][static_cast<size_t>(c)];
      const int y = mesh.triangles[static_cast<size_t>(t)][static_cast<size_t>((c + 1) % 3)];
      if (features.contains(x, y)) continue;
      const uint64_t k = undirected_edge_key(x, y);
      for (auto it = std::lower_bound(edge_tris.begin(), edge_tris.end(), std::pair<uint64_t, int>{k, -1});
           it != edge_tris.end() && it->first == k; ++it)
        if (it->second != t) out.push_back(it->second);
    }
    return out;
  }
};

}  // namespace

NodalField compute_nodal(const Scene& scene, const Mesh& mesh, const std::vector<Rgb>& element,
                         double crease_angle_degrees, NodalMethod method) {
  const bool fit = method == NodalMethod::linear_fit;
  const size_t nv = mesh.positions.size();
  const size_t nt = mesh.triangles.size();
  const double cos_crease = std::cos(crease_angle_degrees * std::numbers::pi / 180.0);

  // Triangles around each vertex (CSR).
  std::vector<int> start(nv + 1, 0);
  for (const auto& t : mesh.triangles)
    for (int v : t) ++start[static_cast<size_t>(v) + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<int> around(static_cast<size_t>(start[nv]));
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (size_t t = 0; t < nt; ++t)
    for (int v : mesh.triangles[t]) around[static_cast<size_t>(fill[static_cast<size_t>(v)]++)] = static_cast<int>(t);

  auto compatible = [&](int a, int b) {
    const Patch& pa = scene.patches[static_cast<size_t>(mesh.patch[static_cast<size_t>(a)])];
    const Patch& pb = scene.patches[static_cast<size_t>(mesh.patch[static_cast<size_t>(b)])];
    return pa.material == pb.material && glm::dot(pa.normal, pb.normal) >= cos_crease;
  };
  const FeatureEdges features(mesh);
  auto share_edge_at = [&](int a, int b, int v) {
    // Triangles a and b both contain v; they share an edge through v when they
    // have a second vertex in common, unless that edge is a discontinuity line.
    for (int x : mesh.triangles[static_cast<size_t>(a)])
      if (x != v)
        for (int y : mesh.triangles[static_cast<size_t>(b)])
          if (x == y) return !features.contains(v, x);
    return false;
  };

  EdgeNeighbours edge_neighbours{mesh, features, {}};

  NodalField field;
  field.corners.assign(nt, {-1, -1, -1});
  std::vector<int> group, display;
  std::vector<double> weight;
  auto find = [&group](int x) {
    while (group[static_cast<size_t>(x)] != x) x = group[static_cast<size_t>(x)] = group[static_cast<size_t>(group[static_cast<size_t>(x)])];
    return x;
  };
  for (size_t v = 0; v < nv; ++v) {
    const int b = start[v], e = start[v + 1];
    const int k = e - b;
    // Union-find over the triangles around v, joining compatible neighbours.
    group.resize(static_cast<size_t>(k));
    std::iota(group.begin(), group.end(), 0);
    for (int i = 0; i < k; ++i)
      for (int j = i + 1; j < k; ++j) {
        const int ta = around[static_cast<size_t>(b + i)], tb = around[static_cast<size_t>(b + j)];
        if (compatible(ta, tb) && share_edge_at(ta, tb, static_cast<int>(v))) group[static_cast<size_t>(find(i))] = find(j);
      }
    // One display vertex per group: the area-weighted mean of its elements.
    display.assign(static_cast<size_t>(k), -1);
    for (int i = 0; i < k; ++i) {
      const int root = find(i);
      if (display[static_cast<size_t>(root)] < 0) {
        display[static_cast<size_t>(root)] = static_cast<int>(field.points.size());
        field.points.push_back(mesh.positions[v]);
        field.source_vertex.push_back(static_cast<int>(v));
        field.radiosity.push_back(Rgb(0.0));
      }
    }
    weight.assign(static_cast<size_t>(k), 0.0);
    for (int i = 0; i < k; ++i) {
      const int t = around[static_cast<size_t>(b + i)];
      const int root = find(i);
      const int d = display[static_cast<size_t>(root)];
      const double a = mesh.area(t);
      field.radiosity[static_cast<size_t>(d)] += a * element[static_cast<size_t>(t)];
      weight[static_cast<size_t>(root)] += a;
      auto& tri = mesh.triangles[static_cast<size_t>(t)];
      for (int c = 0; c < 3; ++c)
        if (tri[static_cast<size_t>(c)] == static_cast<int>(v)) field.corners[static_cast<size_t>(t)][static_cast<size_t>(c)] = d;
    }
    for (int i = 0; i < k; ++i)
      if (find(i) == i && weight[static_cast<size_t>(i)] > 0.0)
        field.radiosity[static_cast<size_t>(display[static_cast<size_t>(i)])] /= weight[static_cast<size_t>(i)];
    if (!fit) continue;
    // Linear fit: per group, the plane through the element values at the
    // element centroids (area-weighted least squares, in the group's plane),
    // evaluated at the vertex. Unlike the mean it extrapolates at a patch
    // boundary, where the mean is biased towards the interior. Where the
    // group's centroids line up (a corner with one or two triangles), the
    // triangles next to the group across ordinary edges join the fit (up to
    // three rings).
    for (int i = 0; i < k; ++i) {
      if (find(i) != i) continue;
      std::vector<int> tris;
      for (int j = 0; j < k; ++j)
        if (find(j) == i) tris.push_back(around[static_cast<size_t>(b + j)]);
      std::optional<Rgb> value = fit_plane_at(scene, mesh, element, static_cast<int>(v), tris);
      for (int grow = 0; !value && grow < 3; ++grow) {
        const std::vector<int> ring = tris;
        for (int t : ring)
          for (int nb : edge_neighbours(t))
            if (compatible(t, nb) && std::find(tris.begin(), tris.end(), nb) == tris.end()) tris.push_back(nb);
        if (tris.size() == ring.size()) break;
        value = fit_plane_at(scene, mesh, element, static_cast<int>(v), tris);
      }
      if (!value) continue;  // keep the mean
      // Radiosity is never below the surface's own emission.
      const Patch& patch = scene.patches[static_cast<size_t>(mesh.patch[static_cast<size_t>(tris[0])])];
      const Rgb floor = scene.material_of(patch).emission;
      field.radiosity[static_cast<size_t>(display[static_cast<size_t>(i)])] = glm::max(*value, floor);
    }
  }
  return field;
}

}  // namespace radmesh
