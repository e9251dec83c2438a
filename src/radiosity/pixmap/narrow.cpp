// Narrow receivers: the pixmaps a shooter's hemicube cannot resolve (a thin
// strip seen from afar, the edge of a picture right beside the block) and
// the exact factors they take instead, with shadow rays for the occlusion
// the item buffer would have given. Also the polygons a shooter's texels
// shoot from, which the near field of every row (rows.cpp) integrates over.

#include "radiosity/pixmap/solver.h"

#include "radmesh/form_factor.h"

#include <map>

namespace radmesh {

using internal::kNearField;

bool PixmapSolver::Impl::narrow_receiver(int k, const Shooter& sh, double pixel, double reach) const {
  // Pixmap k is narrow for shooter sh when, at its nearest point to the
  // hemicube's centre, it is
  // - narrower than kSubPixel pixels of the top face's centre (where pixels
  //   subtend the widest angle): the item buffer, which samples pixel
  //   centres, would see it in no pixel or in whole rows of them, and its
  //   share would alias with the shooter's position (a thin strip far under
  //   a lamp would come out at a fraction or a multiple of its radiosity,
  //   depending on the hemicube's resolution); or
  // - narrower than the block (its radius plus a texel's diagonal) and
  //   within `reach` of it, where the near field's points on the source
  //   texels would see it edge on or not at all (the thin edges of a
  //   picture beside the wall it hangs on would get a small fraction of the
  //   wall's light).
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
    if (internal::plain_square(own, src)) {
      polygons.push_back({q, internal::texel_square(own, src), 4});
      continue;
    }
    for (const int d : pieces_of(own.first + src)) {
      const std::array<Vec3, 3> p = piece_corners(d);
      polygons.push_back({q, {p[0], p[1], p[2], Vec3(0.0)}, 3});
    }
  }
  return polygons;
}

// What narrow pixmap k receives from shooter sh, phase by phase: its lit
// display triangles sorted into far and near pieces, the far ones seen
// from the block's centre, the near ones from each source polygon.
struct PixmapSolver::Impl::NarrowReceiver {
  const Impl& m;
  const Shooter& sh;
  const Pixmap& pm;
  const Pixmap& own;
  const size_t nsrc;
  const bool sky;
  NarrowPart& out;
  // The far pieces: their centroids, factors, texels and patches.
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
  // The factors weighed by look_behind, and those with a surface behind.
  double weight = 0.0, weight_behind = 0.0;

  NarrowReceiver(const Impl& m, int k, const Shooter& sh, bool sky, NarrowPart& out)
      : m(m), sh(sh), pm(m.layout.pixmaps[k]), own(m.layout.pixmaps[sh.pixmap]), nsrc(sh.texels.size()), sky(sky),
        out(out) {}
  void sort_pieces(int k, double reach);
  void look_behind(const Vec3& c, int patch, double w);
  void receive_far(const std::function<void(int, double)>& add);
  void receive_near(const std::vector<SourcePolygon>& polygons);
};

// The lit display triangles of pixmap k (each a piece of one texel), near
// or far as their texel's centroid is within `reach` of the block's centre
// or not; a far one with its factor from the block's centre.
void PixmapSolver::Impl::NarrowReceiver::sort_pieces(int k, double reach) {
  const Mesh& display = m.display;
  for (size_t d = m.display_first[k]; d < m.display_first[k + 1]; ++d) {
    if (m.display_texel[d] < 0) continue;
    const auto& t = display.triangles[d];
    const std::array<Vec3, 3> p = {display.positions[t[0]], display.positions[t[1]], display.positions[t[2]]};
    const Vec3 c = (p[0] + p[1] + p[2]) / 3.0;
    const int texel = static_cast<int>(m.display_texel[d] - pm.first);
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
}

// Whether a surface lies behind a piece, seen from the block's centre,
// weighted by the piece's factor; asked only when the hemicube sees some
// sky. (Behind a face of a closed object lies the back of another: in a
// closed scene the pixels around the face's direction still see the
// scene, and the row keeps its sum.)
void PixmapSolver::Impl::NarrowReceiver::look_behind(const Vec3& c, int patch, double w) {
  if (!sky) return;
  weight += w;
  if (m.vis->ray_end(c, c - sh.centre, patch) != Visibility::RayEnd::nowhere) weight_behind += w;
}

// The far pieces, as the hemicube would see them: Lambert's factor from the
// block's centre, seen or not by one shadow ray to the piece's centroid.
void PixmapSolver::Impl::NarrowReceiver::receive_far(const std::function<void(int, double)>& add) {
  if (far_to.empty()) return;
  const std::vector<Vec3> from(far_to.size(), sh.centre);
  std::vector<unsigned char> seen(far_to.size());
  m.vis->visible_off_surfaces(from.data(), own.normal, far_to.data(), pm.normal, far_to.size(), -1, -1, seen.data());
  for (size_t i = 0; i < far_to.size(); ++i)
    if (seen[i]) {
      add(far_texel[i], far_f[i]);
      out.far_sum += far_f[i];
      look_behind(far_to[i], far_patch[i], far_f[i]);
    }
}

// The near pieces, from each source texel by reciprocity,
// F = A_piece / A_texel x F(piece -> texel), the latter Lambert's factor
// from three points of the piece (a rule exact for quadratics) to each
// polygon of the texel, seen or not by a ray between the centroids: a
// piece is narrow, so its points see what it sees, and a face a millimetre
// off a wall gets the half of its light that comes from the wall right
// beside it (from the block's centre the wall sees it edge on).
void PixmapSolver::Impl::NarrowReceiver::receive_near(const std::vector<SourcePolygon>& polygons) {
  std::vector<Vec3> centres, from, to;
  for (const SourcePolygon& poly : polygons) centres.push_back(poly.centroid());
  for (const Piece& piece : near_pieces) {
    from.insert(from.end(), polygons.size(), piece.centroid);
    to.insert(to.end(), centres.begin(), centres.end());
  }
  std::vector<unsigned char> seen(from.size());
  m.vis->visible_off_surfaces(from.data(), pm.normal, to.data(), own.normal, from.size(), -1, -1, seen.data());
  std::map<int, std::vector<double>> per_texel;
  for (size_t n = 0; n < near_pieces.size(); ++n) {
    const Piece& piece = near_pieces[n];
    std::vector<double>& per = per_texel[piece.texel];
    per.resize(nsrc, 0.0);
    double received = 0.0;  // F from the block (area-weighted over its texels)
    for (size_t i = 0; i < polygons.size(); ++i) {
      if (!seen[n * polygons.size() + i]) continue;
      const SourcePolygon& poly = polygons[i];
      double f = 0.0;
      for (int a = 0; a < 3; ++a) {
        const Vec3 x = internal::rule_point(piece.v, a);
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

// Per lit display triangle (a piece of one texel): its texel's centroid
// beyond `reach`, as the hemicube would (receive_far); within it, from
// each source texel (receive_near).
void PixmapSolver::Impl::receive_narrow(int k, const Shooter& sh, double reach, bool sky,
                                        const std::vector<SourcePolygon>& polygons,
                                        const std::function<void(int, double)>& add, NarrowPart& out) const {
  NarrowReceiver r(*this, k, sh, sky, out);
  r.sort_pieces(k, reach);
  r.receive_far(add);
  out.exact.assign(r.nsrc, 0.0);
  if (r.near_pieces.empty()) {
    if (r.weight > 0.0) out.behind = r.weight_behind / r.weight;
    return;
  }
  r.receive_near(polygons);
}

}  // namespace radmesh
