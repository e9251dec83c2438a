// The mesh's per-triangle measures, its feature edges, and the meshing
// options a user sets: their table and their resolution against a scene.

#include "radmesh/mesh.h"

#include "radmesh/errors.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace radmesh {

double Mesh::area(int t) const {
  const auto& tri = triangles[static_cast<size_t>(t)];
  return triangle_area(positions[tri[0]], positions[tri[1]], positions[tri[2]]);
}

bool Mesh::zero_area(int t) const {
  const auto& tri = triangles[static_cast<size_t>(t)];
  const Vec3 &a = positions[tri[0]], &b = positions[tri[1]], &c = positions[tri[2]];
  const double longest = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
  // Far from the origin for its size (a room moved by 10^6), a triangle's
  // corners carry the rounding of their coordinates' magnitude, which can
  // be more than 1e-12 of its edge: the middle vertex of a zero-area
  // triangle lies off the long edge by up to that, which bounds its area.
  const Vec3 m = glm::max(glm::abs(a), glm::max(glm::abs(b), glm::abs(c)));
  const double far = std::max({m.x, m.y, m.z});
  const double rounding = 8.0 * std::numeric_limits<double>::epsilon() * far;
  return area(t) <= 1e-12 * longest * longest + rounding * longest;
}

Vec3 Mesh::centroid(int t) const {
  const auto& tri = triangles[static_cast<size_t>(t)];
  return (positions[tri[0]] + positions[tri[1]] + positions[tri[2]]) / 3.0;
}

FeatureEdges::FeatureEdges(const Mesh& mesh) {
  keys_.reserve(mesh.feature_edges.size());
  for (const auto& e : mesh.feature_edges) keys_.push_back(undirected_edge_key(e[0], e[1]));
  std::sort(keys_.begin(), keys_.end());
}

bool FeatureEdges::contains(int a, int b) const {
  return std::binary_search(keys_.begin(), keys_.end(), undirected_edge_key(a, b));
}

const OptionTable<MeshingOptions>& meshing_option_table() {
  static const OptionTable<MeshingOptions> table = [] {
    OptionTable<MeshingOptions> t("meshing");
    t.real("max_edge", &MeshingOptions::max_edge, "scene units",
           "longest mesh edge (0: the method's choice, scene diagonal / 12 for mesh and quality)", 0.0, 1e300);
    t.real("min_angle", &MeshingOptions::min_angle, "degrees",
           "smallest triangle angle wanted (CGAL's mesher may not terminate above about 30)", 0.0, 30.0);
    t.choice("discontinuity", &MeshingOptions::discontinuity,
             "discontinuity lines built into the initial mesh: off, contacts (where patches meet) or full (contacts "
             "and the D1/D2 shadow boundaries of every emitter)",
             {{"off", DiscontinuityMode::off}, {"contacts", DiscontinuityMode::contacts},
              {"full", DiscontinuityMode::full}});
    t.add({"max_shadow_lines", OptionSpec::Kind::integer, "",
           "with discontinuity full: shadow-line segments kept per receiving patch", 0.0, 0.0, 1e6, {}},
          [](const MeshingOptions& o) { return static_cast<double>(o.shadow.max_lines_per_receiver); },
          [](MeshingOptions& o, double v) { o.shadow.max_lines_per_receiver = static_cast<int>(v); });
    return t;
  }();
  return table;
}

MeshingOptions resolve_meshing_options(const Scene& scene, MeshingOptions options) {
  meshing_option_table().check(options);
  if (options.max_edge == 0.0) options.max_edge = scene.diagonal() / 12.0;
  // Equilateral triangles of side max_edge: the fewest the mesher can make.
  double area = 0.0;
  for (size_t p = 0; p < scene.patches.size(); ++p) area += scene.patch_area(static_cast<int>(p));
  const double per_element = std::sqrt(3.0) / 4.0 * options.max_edge * options.max_edge;
  const double estimate = area / per_element;
  // Past double range (--max-edge 1e-300) the count is written as a power
  // of ten, not "inf".
  const std::string count =
      std::isfinite(estimate)
          ? format_number(std::round(estimate))
          : "10^" + format_number(std::floor(std::log10(area) - 2.0 * std::log10(options.max_edge) -
                                             std::log10(std::sqrt(3.0) / 4.0)));
  if (estimate > options.max_elements)
    throw InputError("max_edge " + format_number(options.max_edge) + " would make at least " + count +
                         " elements (total area " + format_number(area) + "), more than the " +
                         format_number(options.max_elements) + " allowed; use max_edge " +
                         format_number(std::sqrt(area / (options.max_elements * std::sqrt(3.0) / 4.0))) + " or more",
                     {"max_edge"});
  return options;
}

}  // namespace radmesh
