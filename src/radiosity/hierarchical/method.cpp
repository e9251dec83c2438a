// Hierarchical radiosity as an entry of the method table: its options, its
// recommended meshing, and its result (conforming mesh, cell fields, links,
// counters).

#include "radmesh/hierarchical.h"
#include "radmesh/method.h"
#include "radmesh/run.h"

#include <algorithm>

namespace radmesh {

namespace {

// The links of a hierarchical solution as lines from the receiver's centroid
// to the source's, with the nodes' levels and patches, F x visibility, the
// visible fraction, and the radiosity the link adds to its receiver
// (rho_receiver x F x V x B_source, largest channel). Links with a cluster
// end (HierarchicalClusterLink) have level and patch -1 at that end.
LineSet link_line_set(const Scene& scene, const HierarchicalSolution& h) {
  LineSet out;
  std::vector<int> rl, sl, rp, sp;
  std::vector<double> ff, vis, transport;
  for (size_t r = 0; r < h.links.size(); ++r) {
    const int rn = static_cast<int>(r);
    const Patch& patch = scene.patches[static_cast<size_t>(h.tree.node(rn).patch)];
    const Rgb& rho = scene.material_of(patch).reflectance;
    for (const HierarchicalLink& l : h.links[r]) {
      out.segments.push_back({h.tree.centroid(rn), h.tree.centroid(l.source)});
      rl.push_back(h.tree.node(rn).level);
      sl.push_back(h.tree.node(l.source).level);
      rp.push_back(h.tree.node(rn).patch);
      sp.push_back(h.tree.node(l.source).patch);
      ff.push_back(l.form_factor);
      vis.push_back(l.visible);
      const Rgb t = rho * h.node_radiosity[static_cast<size_t>(l.source)] * l.form_factor;
      transport.push_back(max3(t));
    }
  }
  // Links with a cluster end: level and patch -1 at that end.
  for (const HierarchicalClusterLink& c : h.cluster_links) {
    out.segments.push_back({c.receiver, c.source});
    rl.push_back(c.receiver_node >= 0 ? h.tree.node(c.receiver_node).level : -1);
    sl.push_back(c.source_node >= 0 ? h.tree.node(c.source_node).level : -1);
    rp.push_back(c.receiver_node >= 0 ? h.tree.node(c.receiver_node).patch : -1);
    sp.push_back(c.source_node >= 0 ? h.tree.node(c.source_node).patch : -1);
    ff.push_back(c.form_factor);
    vis.push_back(c.visible);
    transport.push_back(c.transport);
  }
  out.int_fields = {{"receiver_level", rl}, {"source_level", sl}, {"receiver_patch", rp}, {"source_patch", sp}};
  out.real_fields = {{"form_factor", ff}, {"visible", vis}, {"transport", transport}};
  return out;
}

// The per-cell level, zero_area flag and link count of a hierarchical
// solution's conforming mesh.
std::vector<std::pair<std::string, std::vector<int>>> hierarchical_fields(const HierarchicalSolution& h) {
  std::vector<int> level, zero, links;
  for (int leaf : h.leaf_of) {
    level.push_back(leaf >= 0 ? h.tree.node(leaf).level : -1);
    zero.push_back(leaf < 0 ? 1 : 0);
    links.push_back(leaf >= 0 ? h.node_links[static_cast<size_t>(leaf)] : 0);
  }
  return {{"level", level}, {"zero_area", zero}, {"links", links}};
}

std::vector<double> as_doubles(const auto& v) { return std::vector<double>(v.begin(), v.end()); }

}  // namespace

const OptionTable<HierarchicalOptions>& hierarchical_option_table() {
  static const OptionTable<HierarchicalOptions> table = [] {
    OptionTable<HierarchicalOptions> t("method hierarchical");
    using H = HierarchicalOptions;
    t.real("epsilon", &H::epsilon, "", "link refinement threshold, relative to the largest reflected radiosity", 1e-9,
           1.0);
    t.real("area_weight", &H::area_weight, "",
           "weigh the oracle's error for a receiver smaller than the mean initial triangle by (its area / that "
           "area)^this: 0 = off, 1 = the transported power's error (fewer links on small elements)",
           0.0, 2.0);
    t.choice("tvertex", &H::tvertex,
             "vertex values on a neighbour's unsplit edge: free (from the finer side), anchor (the edge's "
             "interpolant, no shading jump) or split (split neighbours until no T-vertex is left, no zero-area "
             "triangles)",
             {{"free", TVertexMode::free}, {"anchor", TVertexMode::anchor}, {"split", TVertexMode::split}});
    t.real("min_area", &H::min_area, "scene units^2",
           "links are not refined below this area, an input triangle smaller than it weighs the oracle's error by "
           "its share of it, and Baum's criterion splits leaves down to a quarter of it "
           "(0 = (scene diagonal / 150)^2 / 2)",
           0.0, 1e300);
    t.real("baum", &H::baum, "",
           "also split a leaf whose vertex values differ by more than this fraction of the largest reflected "
           "radiosity (Baum's criterion; 0 = off)",
           0.0, 1.0);
    t.real("marginal_refinement", &H::marginal_refinement, "",
           "after the first refinement round, make a round only where a link the oracle would refine is over its "
           "threshold by more than this factor (those left are counted in the summary's skips; 1 = refine every "
           "link over the threshold)",
           1.0, 1e6);
    t.choice("clusters", &H::clusters,
             "what sits above the initial mesh's triangles: volume (a box hierarchy of clusters with oriented "
             "normal groups, links grow about linearly), shape (Tanaka and Noma's hierarchical shape "
             "approximation: octree vertex clustering, the same groups and linking) or off (every pair of initial "
             "triangles is linked)",
             {{"volume", ClusterMode::volume}, {"shape", ClusterMode::shape}, {"off", ClusterMode::off}});
    t.flag("export_links", &H::export_links,
           "also write links.vtu, every link as a line from receiver to source (fields receiver_level, "
           "source_level, receiver_patch, source_patch, form_factor, visible, transport; level and patch -1 at a "
           "cluster end)");
    return t;
  }();
  return table;
}

namespace {

constexpr const char* kName = "hierarchical";

}  // namespace

Method make_hierarchical_method() {
  Method m = make_method<HierarchicalOptions>(
      kName,
      "Hanrahan's hierarchical radiosity on an element hierarchy closed by zero-area triangles (also writes "
      "radiosity.pvd, one file per refinement round)",
      hierarchical_option_table(),
      [](const Scene& scene, const Mesh& mesh, const SolveOptions& so, const HierarchicalOptions& ho,
         const SolveCallbacks& cb) {
        std::function<void(const HierarchicalSolution&, int)> on_round;
        if (cb.on_round)
          on_round = [&](const HierarchicalSolution& h, int round) {
            MethodResult snapshot;
            snapshot.mesh = h.mesh;
            snapshot.solution = h.solution;
            snapshot.cell_fields = hierarchical_fields(h);
            cb.on_round(snapshot, round);
          };
        HierarchicalSolution h = solve_hierarchical(scene, mesh, so, ho, on_round, cb.progress);
        MethodResult r;
        r.cell_fields = hierarchical_fields(h);
        if (ho.export_links) r.line_sets.emplace_back("links", link_line_set(scene, h));
        const HierarchicalStats& hs = h.stats;
        r.counters = {count("rounds", hs.rounds),
                      count("links", static_cast<double>(hs.links)),
                      count_series("links_per_round", as_doubles(hs.links_per_round)),
                      count_series("leaves_per_round", as_doubles(hs.leaves_per_round)),
                      count("leaves", hs.leaves),
                      count("zero_area_triangles", hs.zero_area_triangles),
                      count("leaf_terms", static_cast<double>(hs.leaf_terms)),
                      count("links_examined", static_cast<double>(hs.links_examined)),
                      count("sweeps", hs.sweeps),
                      measure("last_change", hs.last_change),
                      measure("row_sum_min", hs.row_sum_min),
                      measure("row_sum_max", hs.row_sum_max),
                      count("conforming_splits", hs.conforming_splits),
                      measure("max_tvertex_jump", hs.max_tvertex_jump),
                      measure("min_area", hs.min_area, "scene units^2"),
                      count("baum_splits", hs.baum_splits),
                      count("clusters", hs.clusters),
                      count("cluster_groups", hs.cluster_groups),
                      count("cluster_links", static_cast<double>(hs.cluster_links))};
        r.seconds = {{"link", hs.seconds_link}, {"solve", hs.seconds_solve}};
        r.report = std::to_string(hs.leaves) + " leaves, " + std::to_string(hs.links) + " links, " +
                   std::to_string(hs.zero_area_triangles) + " zero-area triangles, " + std::to_string(hs.rounds) +
                   " rounds";
        r.mesh = std::move(h.mesh);
        r.solution = std::move(h.solution);
        return r;
      });
  // Measured on the Cornell box and the 8 x 8 box field (docs/methods.md,
  // "Presets").
  m.presets = {{"draft", "a quarter to half the default's time; object means within 0.3%, dim faces up to 5% off",
                {{"epsilon", "0.01"}}},
               {"fine", "about three times the default's time; a finer transport and half the shadow rays' noise",
                {{"epsilon", "0.0005"}, {"rays", "64"}}}};
  m.meshing = [](const Scene& scene) {
    // Hierarchical radiosity refines by itself: coarse roots, and the shadow
    // lines left to refinement (full lines make many roots, and every pair
    // of roots is linked).
    MeshingOptions mo;
    mo.max_edge = scene.diagonal() / 5.0;
    mo.discontinuity = DiscontinuityMode::contacts;
    return mo;
  };
  return m;
}

Result solve(const Scene& scene, const HierarchicalOptions& options, const SolveOptions& common,
             const SolveCallbacks& callbacks) {
  return solve(scene, find_method(kName), MethodOptions::checked(hierarchical_option_table(), options), common,
               callbacks);
}

}  // namespace radmesh
