// The options every method shares (SolveOptions): their table, their
// checks and the memory they allow.

#include "radmesh/solve.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace radmesh {

const OptionTable<SolveOptions>& solve_option_table() {
  static const OptionTable<SolveOptions> table = [] {
    OptionTable<SolveOptions> t("solve");
    t.real("tolerance", &SolveOptions::tolerance, "",
           "Gauss-Seidel stops when a sweep changes radiosity by less than this fraction of the largest value",
           1e-15, 0.999);
    t.integer("threads", &SolveOptions::threads, "", "worker threads, 0 = all cores (results do not depend on it)",
              0, 4096);
    t.integer("rays", &SolveOptions::rays, "", "shadow rays per element pair (and per part a field point gathers from)",
              1, 4096);
    t.real("max_memory", &SolveOptions::max_memory, "GiB",
           "memory the matrix method's form factors, the pixmap method's texels (with their display and files) and "
           "cached rows, or the whole run while the hierarchical method solves, may use (0 = half the memory)",
           0.0, 1e6);
    t.choice("field", &SolveOptions::field,
             "vertex values: gather (exact direct light and a final gather of the solved radiosity at every "
             "vertex), fit (least-squares plane through the element values around the vertex), mean (their "
             "area-weighted mean) or auto (gather, by clusters of patches on large scenes, unless that would pass "
             "a budget of (vertex, source) pairs, then fit; a method with a field of its own keeps it)",
             {{"auto", FieldMode::automatic}, {"gather", FieldMode::gather}, {"fit", FieldMode::fit},
              {"mean", FieldMode::mean}});
    t.real("display_tolerance", &SolveOptions::display_tolerance, "",
           "with the gather field: refine the display where the field at an edge midpoint differs from the "
           "mean of the edge's ends by more than this fraction of the largest reflected radiosity (0: the "
           "display is the solver's mesh)",
           0.0, 1.0);
    return t;
  }();
  return table;
}

void check_solve_options(const SolveOptions& o) {
  // A method's own field is no value to ask for, but what run_method
  // resolves automatic to; every other field is checked by the table.
  SolveOptions checked = o;
  if (checked.field == FieldMode::own) checked.field = FieldMode::automatic;
  solve_option_table().check(checked);
  auto bad = [](const std::string& what, double v, const std::string& range) {
    throw InputError(what + " " + format_number(v) + " (solve): out of range " + range, {what});
  };
  if (o.max_iterations < 1) bad("max_iterations", o.max_iterations, "[1, inf)");
  if (!(o.quadrature.closeness > 0.0)) bad("closeness", o.quadrature.closeness, "(0, inf)");
  if (o.quadrature.max_level < 0 || o.quadrature.max_level > kMaxQuadratureLevel)
    bad("max_level", o.quadrature.max_level, "[0, " + std::to_string(kMaxQuadratureLevel) + "]");
  if (!(o.crease_angle >= 0.0 && o.crease_angle <= 180.0)) bad("crease_angle", o.crease_angle, "[0, 180]");
}

namespace {

double physical_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? static_cast<double>(pages) * static_cast<double>(page) : 8e9;
}

}  // namespace

double memory_limit_bytes(const SolveOptions& options) {
  double limit = options.max_memory > 0.0 ? options.max_memory * 1024.0 * 1024.0 * 1024.0 : 0.5 * physical_memory_bytes();
  // Under a limit on the process's address space or data (ulimit -v, -d)
  // an allocation past it fails whatever the machine holds: half of it is
  // what the run's counted structures may take (the libraries, the
  // allocator's slack and what is not counted take the rest).
  for (const int resource : {RLIMIT_AS, RLIMIT_DATA}) {
    rlimit r{};
    if (getrlimit(resource, &r) == 0 && r.rlim_cur != RLIM_INFINITY)
      limit = std::min(limit, 0.5 * static_cast<double>(r.rlim_cur));
  }
  return limit;
}

double resident_memory_bytes() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return 0.0;
  long size = 0, resident = 0;
  const bool ok = std::fscanf(f, "%ld %ld", &size, &resident) == 2;
  std::fclose(f);
  const long page = sysconf(_SC_PAGE_SIZE);
  return ok && page > 0 ? static_cast<double>(resident) * static_cast<double>(page) : 0.0;
}

}  // namespace radmesh
