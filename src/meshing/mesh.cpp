#include "radmesh/mesh.h"

#include <algorithm>

namespace radmesh {

double Mesh::area(int t) const {
  const auto& tri = triangles[static_cast<size_t>(t)];
  return triangle_area(positions[tri[0]], positions[tri[1]], positions[tri[2]]);
}

bool Mesh::zero_area(int t) const {
  const auto& tri = triangles[static_cast<size_t>(t)];
  const Vec3 &a = positions[tri[0]], &b = positions[tri[1]], &c = positions[tri[2]];
  const double longest = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
  return area(t) <= 1e-12 * longest * longest;
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

}  // namespace radmesh
