// The memory budget: what the links, terms and clusters will hold, checked
// against SolveOptions::max_memory together with what the process holds,
// before a generation of links or a block of terms is made, so that a run
// that would not fit stops with a message instead of the system's
// out-of-memory killer.

#include "radiosity/hierarchical/solver.h"

namespace radmesh::internal {

// The memory limit holds for the whole process, after every generation of
// links, the leaf terms and the published mesh: the larger of what the
// process held when the solver began plus the solver's own count (links,
// link numbers, leaf terms, clusters: known before the allocator shows
// them) and the resident memory now (all the rest: the element tree, the
// mesh, the visibility structure, the allocator's slack): the own count
// alone misses what the rest of the process grows by.
void Hierarchical::check_memory() {
  const long long links = count_links();
  const double own = static_cast<double>(links) * kLinkBytes + static_cast<double>(next_id_) * kLinkIdBytes +
                     static_cast<double>(group_visible_.size()) * sizeof(float) +
                     static_cast<double>(out_.stats.leaf_terms) * sizeof(Term) +
                     ClusterTree::bytes(static_cast<double>(ct_.size()), static_cast<double>(ct_.group_count())) +
                     (ct_.empty() ? 0.0 : bin_bytes(static_cast<double>(ct_.group_count()), out_.tree.root_count()));
  const double counted = held_before_ + own, resident = resident_memory_bytes();
  if (std::max(counted, resident) <= limit_) return;
  // Say which figure passed the limit, and what it is made of.
  const std::string made = links > 0 ? "reached " + std::to_string(links) + " links" : "had stored no link yet";
  const std::string needs =
      resident >= counted
          ? "the process holds " + format_number(resident / kGiB) + " GiB (" + format_number(own / kGiB) +
                " of it the solver's links, leaf terms and clusters)"
          : "with them the process needs " + format_number(counted / kGiB) + " GiB (" + format_number(held_before_ / kGiB) +
                " held when the solve began, " + format_number(own / kGiB) + " for the links, leaf terms and clusters)";
  throw NumericalError(scene_.source + ": hierarchical refinement " + made + "; " + needs + ", more than the " +
                           format_number(limit_ / kGiB) + " GiB allowed; raise epsilon or min_area, or raise max_memory",
                       {"epsilon", "min_area", "max_memory"});
}

// Between blocks of link pairs and of leaf terms (in_blocks), the
// resident memory alone (one read of /proc), so that a generation of
// millions of pairs or a round's terms cannot run far past the limit.
void Hierarchical::check_resident() {
  if (resident_memory_bytes() > limit_) check_memory();
}

// For the messages of the checks before any linking.
std::string Hierarchical::held_text() const {
  return held_before_ > 0.0 ? " on top of the " + format_number(held_before_ / kGiB) + " GiB the process holds" : "";
}

}  // namespace radmesh::internal
