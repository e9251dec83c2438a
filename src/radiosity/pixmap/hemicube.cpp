// The hemicube's item buffer: each triangle is clipped to a face's frustum in
// 3-D (so projected coordinates stay within the screen), projected, and
// rasterised at pixel centres with a depth test on 1 / distance, which is
// affine in screen space.

#include "radiosity/pixmap/hemicube.h"

#include "radmesh/errors.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <tuple>

namespace radmesh {

void Hemicube::check_resolution(int resolution) {
  if (resolution < 2 || resolution % 2 != 0 || resolution > 16384)
    throw InputError("hemicube_res " + std::to_string(resolution) + ": expected an even number in [2, 16384]",
                     {"hemicube_res"});
}

Hemicube::Hemicube(int resolution) : resolution_(resolution) {
  check_resolution(resolution);
  pixel_ = 2.0 / resolution;
  double total = 0.0;
  for (int f = 0; f < 5; ++f) {
    Face& F = faces_[f];
    F.width = resolution;
    F.height = f == 0 ? resolution : resolution / 2;
    F.y0 = f == 0 ? -1.0 : 0.0;
    F.id.assign(static_cast<size_t>(F.width) * F.height, kEmpty);
    F.depth.assign(F.id.size(), 0.0);
    delta_[f].resize(F.id.size());
    for (int y = 0; y < F.height; ++y)
      for (int x = 0; x < F.width; ++x) {
        const double sx = pixel_x(x), sy = pixel_y(f, y);
        const double r2 = sx * sx + sy * sy + 1.0;
        // The top face sees along the normal; a side pixel's cosine at the
        // centre is its height sy over the distance.
        const double d = (f == 0 ? 1.0 : sy) * pixel_ * pixel_ / (std::numbers::pi * r2 * r2);
        delta_[f][static_cast<size_t>(y) * F.width + x] = d;
        total += d;
      }
  }
  for (auto& face : delta_)
    for (double& d : face) d /= total;
}

void Hemicube::render(const Vec3& centre, const Vec3& u, const Vec3& v, const std::vector<HemicubeTriangle>& triangles) {
  centre_ = centre;
  const Vec3 n = glm::cross(u, v);
  const std::array<std::array<Vec3, 3>, 5> axes = {{{u, v, n}, {v, n, u}, {-v, n, -u}, {-u, n, v}, {u, n, -v}}};
  for (int f = 0; f < 5; ++f) {
    faces_[f].right = axes[f][0];
    faces_[f].up = axes[f][1];
    faces_[f].forward = axes[f][2];
  }
  // One near plane for all triangles, so that two triangles sharing an
  // edge clip it at the same point.
  double scale = 0.0;
  for (const HemicubeTriangle& t : triangles)
    scale = std::max({scale, glm::length(t.a - centre), glm::length(t.b - centre), glm::length(t.c - centre)});
  const double near = 1e-12 * scale;
  tbb::parallel_for(0, 5, [&](int f) { render_face(f, triangles, near, kEdgeOn * scale); });
}

namespace {

struct Clip {
  double x, y, z;  // camera coordinates
};

// Depths (1 / distance) this close, relative, are one surface's.
constexpr double kDepthTie = 1e-9;

bool before(const Clip& p, const Clip& q) { return std::tie(p.x, p.y, p.z) < std::tie(q.x, q.y, q.z); }

// Sutherland-Hodgman against the half-space a x + b y + c z >= 0. An edge's
// crossing is computed from its end points in a fixed order, so that the two
// triangles sharing the edge cut it at the same point.
int clip_plane(const Clip* in, int n, Clip* out, double a, double b, double c) {
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const Clip& p = in[i];
    const Clip& q = in[(i + 1) % n];
    const double dp = a * p.x + b * p.y + c * p.z, dq = a * q.x + b * q.y + c * q.z;
    if (dp >= 0.0) out[m++] = p;
    if ((dp >= 0.0) != (dq >= 0.0)) {
      const bool swap = before(q, p);
      const Clip& u = swap ? q : p;
      const Clip& w = swap ? p : q;
      const double du = swap ? dq : dp, dw = swap ? dp : dq;
      const double t = du / (du - dw);
      out[m++] = {u.x + t * (w.x - u.x), u.y + t * (w.y - u.y), u.z + t * (w.z - u.z)};
    }
  }
  return m;
}

// The edge function of (a, b) at p: twice the signed area of (a, b, p),
// computed from the end points in a fixed order, so that the two triangles
// sharing an edge get exactly opposite values and a pixel centre on it is
// drawn by at least one of them.
double edge(double ax, double ay, double bx, double by, double px, double py) {
  if (std::tie(bx, by) < std::tie(ax, ay)) return -((ax - bx) * (py - by) - (ay - by) * (px - bx));
  return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}

}  // namespace

void Hemicube::render_face(int f, const std::vector<HemicubeTriangle>& triangles, double near, double edge_on) {
  Face& F = faces_[f];
  std::fill(F.id.begin(), F.id.end(), kEmpty);
  std::fill(F.depth.begin(), F.depth.end(), 0.0);
  // The frustum, one pixel wider than the screen so that the clipped
  // polygon covers every pixel centre the triangle covers.
  const double m = 1.0 + pixel_;
  const double ylo = F.y0 - pixel_;
  for (const HemicubeTriangle& t : triangles) {
    const Vec3 da = t.a - centre_, db = t.b - centre_, dc = t.c - centre_;
    // A plane through the centre up to rounding (the shooter's own patch,
    // and those in its plane) is seen edge on: 3e-10 behind the top of a
    // box moved 10^6 from the origin, the box's top drew itself from
    // behind over a quarter of the hemicube.
    if (std::abs(glm::dot(t.normal, da)) <= edge_on) continue;
    Clip a[10], b[10];
    int k = 0;
    for (const Vec3& d : {da, db, dc}) a[k++] = {glm::dot(d, F.right), glm::dot(d, F.up), glm::dot(d, F.forward)};
    if (a[0].z < near && a[1].z < near && a[2].z < near) continue;
    // z >= near, then |x| <= m z, y in [ylo z, m z].
    for (int i = 0; i < k; ++i) a[i].z -= near;
    k = clip_plane(a, k, b, 0, 0, 1);
    for (int i = 0; i < k; ++i) b[i].z += near;
    k = clip_plane(b, k, a, 1, 0, m);
    k = clip_plane(a, k, b, -1, 0, m);
    k = clip_plane(b, k, a, 0, 1, -ylo);
    k = clip_plane(a, k, b, 0, -1, m);
    if (k < 3) continue;
    const bool front = glm::dot(t.normal, centre_ - t.a) > 0.0;
    const int id = front ? t.id : kBack;
    // Depth (1 / the forward distance) from the triangle's plane: along the
    // ray of screen point (x, y), n . (x right + y up + forward) / (n . da).
    // Interpolated over the clipped polygon's fan instead, a sliver of it
    // (a floor's edge seen along the screen's diagonal, a corner clipped
    // at the near plane) would give a pixel centre on its edges a weight on
    // that corner's huge depth, and a far floor would show through a nearer
    // wall.
    const Vec3 n = glm::cross(t.b - t.a, t.c - t.a);
    const double plane = glm::dot(n, da);
    if (plane == 0.0) continue;  // a triangle of no area
    const double dR = glm::dot(n, F.right) / plane, dU = glm::dot(n, F.up) / plane,
                 dF = glm::dot(n, F.forward) / plane;
    double sx[10], sy[10];
    for (int i = 0; i < k; ++i) {
      const double w = 1.0 / b[i].z;
      sx[i] = b[i].x * w;
      sy[i] = b[i].y * w;
    }
    // The clipped polygon is convex: a fan.
    for (int i = 1; i + 1 < k; ++i) {
      const int v0 = 0, v1 = i, v2 = i + 1;
      const double area = (sx[v1] - sx[v0]) * (sy[v2] - sy[v0]) - (sy[v1] - sy[v0]) * (sx[v2] - sx[v0]);
      if (area == 0.0) continue;
      const double sign = area > 0.0 ? 1.0 : -1.0;
      const double xmin = std::min({sx[v0], sx[v1], sx[v2]}), xmax = std::max({sx[v0], sx[v1], sx[v2]});
      const double ymin = std::min({sy[v0], sy[v1], sy[v2]}), ymax = std::max({sy[v0], sy[v1], sy[v2]});
      const int x0 = std::max(0, static_cast<int>(std::ceil((xmin + 1.0) / pixel_ - 0.5)));
      const int x1 = std::min(F.width - 1, static_cast<int>(std::floor((xmax + 1.0) / pixel_ - 0.5)));
      const int y0 = std::max(0, static_cast<int>(std::ceil((ymin - F.y0) / pixel_ - 0.5)));
      const int y1 = std::min(F.height - 1, static_cast<int>(std::floor((ymax - F.y0) / pixel_ - 0.5)));
      for (int y = y0; y <= y1; ++y) {
        const double py = pixel_y(f, y);
        for (int x = x0; x <= x1; ++x) {
          const double px = pixel_x(x);
          // Barycentric weights from the edge functions (inclusive edges:
          // a centre on a shared edge is drawn by both triangles).
          const double e0 = sign * edge(sx[v1], sy[v1], sx[v2], sy[v2], px, py);
          const double e1 = sign * edge(sx[v2], sy[v2], sx[v0], sy[v0], px, py);
          const double e2 = sign * edge(sx[v0], sy[v0], sx[v1], sy[v1], px, py);
          if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) continue;
          const double depth = dR * px + dU * py + dF;
          const size_t pix = static_cast<size_t>(y) * F.width + x;
          // Nearer wins; at a tie (within rounding) a front side beats a
          // back: the two sides of a panel are one quad written twice, and
          // whichever came first would otherwise hide the lit side.
          const double held = F.depth[pix];
          const bool tie = std::abs(depth - held) <= kDepthTie * held;
          if (tie ? (id != kBack && F.id[pix] == kBack) : depth > held) {
            F.depth[pix] = depth;
            F.id[pix] = id;
          }
        }
      }
    }
  }
}

int Hemicube::id_toward(const Vec3& d) const {
  // The face the direction leaves the unit half cube through.
  int best = -1;
  double most = 0.0;
  for (int f = 0; f < 5; ++f) {
    const double z = glm::dot(d, faces_[f].forward);
    if (z > most) {
      most = z;
      best = f;
    }
  }
  if (best < 0) return kEmpty;
  const Face& F = faces_[best];
  const double sx = glm::dot(d, F.right) / most, sy = glm::dot(d, F.up) / most;
  if (sy < F.y0) return kEmpty;
  const int x = std::clamp(static_cast<int>(std::floor((sx + 1.0) / pixel_)), 0, F.width - 1);
  const int y = std::clamp(static_cast<int>(std::floor((sy - F.y0) / pixel_)), 0, F.height - 1);
  return F.id[static_cast<size_t>(y) * F.width + x];
}

double Hemicube::form_factor(int id) const {
  double sum = 0.0;
  for (int f = 0; f < 5; ++f)
    for (size_t p = 0; p < faces_[f].id.size(); ++p)
      if (faces_[f].id[p] == id) sum += delta_[f][p];
  return sum;
}

}  // namespace radmesh
