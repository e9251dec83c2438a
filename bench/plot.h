// Error-versus-time plots of the benchmarks, as PNG files through VTK's charts.
// VTK stays inside plot.cpp.
#pragma once

#include <string>
#include <vector>

namespace radmesh::bench {

struct Series {            // one line on the plot: e.g. "cornell_box / matrix"
  std::string name;
  std::vector<double> x;   // wall time, seconds (> 0)
  std::vector<double> y;   // error (> 0)
};

// Writes a log-log PNG plot (x: wall time [s], y: relative error) with one
// line+markers per series and a legend. Points with a non-positive or
// non-finite coordinate are skipped (log scale); a series left with no point
// is not drawn. Returns false and sets *why when no X display can be opened
// (VTK needs one); throws radmesh::InputError when a series has x and y of
// different lengths, radmesh::IoError (radmesh/errors.h) when writing fails.
bool plot_error_vs_time(const std::string& path, const std::string& title, const std::string& y_label,
                        const std::vector<Series>& series, std::string* why,
                        const std::string& x_label = "wall time [s]");

}  // namespace radmesh::bench
