// A piece of a source patch that the field's gather takes whole: its
// moments, and the form factor and first-order radiosity term they give at a
// point (internal; see FieldEvaluator in field.h).
#pragma once

#include "radmesh/form_factor.h"

#include <glm/mat3x3.hpp>

#include <array>
#include <vector>

namespace radmesh::internal {

struct GatherNode {
  Vec3 centre{0.0};  // area centroid
  double area = 0.0;
  double radius = 0.0;  // largest distance from the centre to a corner
  Rgb reflected{0.0};   // area-weighted mean of R = B - E
  std::array<Vec3, 4> rect{};    // a rectangle in the plane around the triangles (for the shaft test)
  glm::dmat3 second{0.0};        // integral of (y - centre)(y - centre)^T dA
  std::array<Vec3, 3> moment{};  // per channel: integral of (y - centre) R(y) dA
};

// The moments of coplanar triangles t[k] (plane normal `normal`) carrying
// the constant reflected radiosity r[k].
GatherNode gather_node(const std::vector<const Triangle*>& t, const std::vector<Rgb>& r, const Vec3& normal);

// The node seen from x (unit normal n; m the node's unit normal): f, the
// integral over the node of the point form factor's kernel
//   K(y) = (n . r) (-m . r) / (pi |r|^4),  r = y - x,
// and `first`, the first-order part of the integral of K R. The Taylor
// expansion of K about the centroid c gives
//   f         = K(c) A + 1/2 tr(H I2) + O((radius / distance)^3) f,
//   int K R   = K(c) A R_mean + grad K . M + 1/2 tr(H I2) R_mean + ...
// with I2 and M the node's second moment and first moment of R about c
// (the first moment of area vanishes about the centroid). On a planar node
// I2 m = 0 and m . M = 0, which leaves
//   pi grad K   = (b n - a m - 4 a b r / s) / s^2,
//   pi tr(H I2) = -8 b (n . I2 r) / s^3 + 24 a b (r . I2 r) / s^4 - 4 a b tr(I2) / s^3,
// a = n . r, b = -m . r, s = r . r at y = c. `smooth` when the whole node is
// in front of x's tangent plane (where K has a kink); otherwise f is the
// point form factor K(c) A and `first` is zero.
struct NodeTerm {
  double f = 0.0;
  Rgb first{0.0};
  bool smooth = false;
};
NodeTerm node_term(const GatherNode& node, const Vec3& x, const Vec3& n, const Vec3& m);

}  // namespace radmesh::internal
