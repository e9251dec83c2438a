// The hemicube (Cohen & Greenberg 1985) with an item buffer: five faces of a
// half cube around a point, each pixel holding the id of the nearest polygon
// it sees and its delta form factor. The sum of the delta form factors of
// the pixels holding an id is the point-to-polygon form factor, occlusion
// included.
#pragma once

#include "radmesh/geometry.h"

#include <array>
#include <vector>

namespace radmesh {

// A triangle to render: `id` >= 0 is written where its front faces the
// hemicube's centre (counter-clockwise around `normal`); its back writes
// Hemicube::kBack, which still hides what lies behind it.
struct HemicubeTriangle {
  Vec3 a, b, c;
  Vec3 normal;  // the front side
  int id = -1;
};

class Hemicube {
public:
  static constexpr int kEmpty = -1;  // sees nothing
  static constexpr int kBack = -2;   // sees the back of a polygon

  // One face: a camera looking along `forward` with screen axes `right` and
  // `up`; the screen spans x in [-1, 1] and y in [y0, 1] at distance 1.
  struct Face {
    Vec3 right, up, forward;
    int width = 0, height = 0;
    double y0 = -1.0;
    std::vector<int> id;        // per pixel, row-major (row = y)
    std::vector<double> depth;  // per pixel: 1 / distance along `forward` of what it sees
  };

  // `resolution` pixels along the top face's side (even, >= 2); the four
  // side faces are resolution x resolution / 2.
  explicit Hemicube(int resolution);
  // InputError naming --hemicube-res unless `resolution` is even and in [2, 16384].
  static void check_resolution(int resolution);
  // The bytes a hemicube of `resolution` holds: 3 x resolution^2 pixels,
  // each an id, a depth and a delta form factor.
  static double bytes(int resolution) {
    return 3.0 * static_cast<double>(resolution) * resolution * (sizeof(int) + 2 * sizeof(double));
  }

  int resolution() const { return resolution_; }

  // Renders `triangles` as seen from `centre` into the hemisphere around
  // `normal` = cross(u, v) (u, v orthonormal: the top face's screen axes).
  // Faces render in parallel (TBB); the result does not depend on threads.
  void render(const Vec3& centre, const Vec3& u, const Vec3& v, const std::vector<HemicubeTriangle>& triangles);

  const std::array<Face, 5>& faces() const { return faces_; }
  const Vec3& centre() const { return centre_; }

  // The delta form factor of pixel (x, y) of face f. Normalised: the
  // pixels of all five faces sum to 1 (to rounding).
  double delta(int f, int x, int y) const { return delta_[f][static_cast<size_t>(y) * faces_[f].width + x]; }
  // Screen coordinates of pixel (x, y)'s centre.
  double pixel_x(int x) const { return -1.0 + (x + 0.5) * pixel_; }
  double pixel_y(int f, int y) const { return faces_[f].y0 + (y + 0.5) * pixel_; }
  double pixel_size() const { return pixel_; }

  // The id the pixel in direction d (from the centre, into the hemisphere)
  // holds; kEmpty for a direction below the horizon.
  int id_toward(const Vec3& d) const;

  // Sum of the delta form factors of the pixels that hold `id`.
  double form_factor(int id) const;

private:
  void render_face(int f, const std::vector<HemicubeTriangle>& triangles, double near, double edge_on);
  // A triangle whose plane passes this close to the centre, relative to
  // the furthest corner, is seen edge on and not drawn.
  static constexpr double kEdgeOn = 1e-9;

  int resolution_;
  double pixel_;
  std::array<Face, 5> faces_;
  std::array<std::vector<double>, 5> delta_;
  Vec3 centre_{0.0};
};

}  // namespace radmesh
