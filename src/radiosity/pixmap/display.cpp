// The display mesh and its values: each pixmap's coarse triangles cut at
// the texel lines, so that every display triangle lies in one texel and
// shows that texel's value (its owner's), with vertex values interpolated
// between texel centres within the pixmap. The mesh is built once with the
// solver, since the rows use it too: its lit triangles are the pieces a
// texel that is not a plain square shoots from, and the extent of each
// pixmap's lit area tells when the pixmap is narrow for a shooter.

#include "radiosity/pixmap/solver.h"

#include <numeric>
#include <unordered_map>

namespace radmesh {

using internal::St;

namespace {

// The lit display triangles of each global texel, as the index
// pieces_begin (per texel and one past the last) into `pieces`, in
// display triangle order.
void index_pieces(const std::vector<long long>& display_texel, long long texels, std::vector<uint32_t>& pieces_begin,
                  std::vector<int>& pieces) {
  pieces_begin.assign(static_cast<size_t>(texels) + 1, 0);
  for (const long long g : display_texel)
    if (g >= 0) ++pieces_begin[static_cast<size_t>(g) + 1];
  for (size_t g = 0; g + 1 < pieces_begin.size(); ++g) pieces_begin[g + 1] += pieces_begin[g];
  pieces.resize(pieces_begin.back());
  std::vector<uint32_t> at(pieces_begin.begin(), pieces_begin.end() - 1);
  for (size_t d = 0; d < display_texel.size(); ++d)
    if (display_texel[d] >= 0) pieces[at[static_cast<size_t>(display_texel[d])]++] = static_cast<int>(d);
}

}  // namespace

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
      display.positions.push_back(internal::point_of(pm, p.s, p.t));
      display_st.push_back(p);
      display_pixmap.push_back(static_cast<int>(k));
      display_dark.push_back(dark ? 1 : 0);
      cells[key(a, b)].push_back(v);
      return v;
    };
    for (int t : triangles_of[k]) {
      St tri[3];
      for (int c = 0; c < 3; ++c) tri[c] = internal::st_of(pm, coarse.positions[coarse.triangles[t][c]]);
      const int patch = coarse.patch[t];
      // A piece's triangles (a fan), dark or lit.
      auto emit = [&](const St* poly, int n, long long texel, bool dark) {
        double a;
        St c;
        internal::area_centroid(poly, n, a, c);
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
      internal::for_each_piece(pm, tri, [&](int i, int j, const St* poly, int n) {
        const int owner = internal::owner_of_piece(pm, j * pm.width + i, t);
        emit(poly, n, owner >= 0 && !dark ? pm.first + owner : -1, dark || owner < 0);
      });
    }
  }
  display_first.push_back(display.triangles.size());
  index_pieces(display_texel, layout.texels, pieces_begin, pieces);
  // Each pixmap's lit area: its centroid, radius and width (Extent).
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
    return Rgb(texels[k][i], texels[k][i + 1], texels[k][i + 2]) * m.unit;
  };
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const long long g = m.display_texel[t];
    // Inside a closed object: no light, but what an emitter emits there
    // (power_enclosed).
    if (m.display_dark[static_cast<size_t>(mesh.triangles[t][0])])
      solution.element[t] =
          m.emission[static_cast<size_t>(m.display_pixmap[static_cast<size_t>(mesh.triangles[t][0])])] * m.unit;
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
      nodal.radiosity[v] = m.emission[static_cast<size_t>(m.display_pixmap[v])] * m.unit;
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
      nodal.radiosity[v] = sum / wsum * m.unit;
    } else {
      // A vertex with no covered texel centre around it with weight: the
      // texel it lies in (clamped to the grid).
      const int i = std::clamp(static_cast<int>(std::floor(p.s)), 0, pm.width - 1);
      const int j = std::clamp(static_cast<int>(std::floor(p.t)), 0, pm.height - 1);
      const int o = pm.owner[static_cast<size_t>(j) * pm.width + i];
      if (o >= 0) nodal.radiosity[v] = Rgb(texels[k][o * 3], texels[k][o * 3 + 1], texels[k][o * 3 + 2]) * m.unit;
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
