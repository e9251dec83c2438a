// Histogram pictures for mesh studies (radmesh quality), through VTK's charts.
#pragma once

#include <string>
#include <vector>

namespace radmesh {

// Writes a bar chart of `values` in `bins` equal bins between the smallest
// and largest finite value. Returns false and sets *why when no X display can
// be opened (VTK needs one); throws IoError when writing fails.
bool plot_histogram(const std::string& path, const std::string& title, const std::string& x_label,
                    const std::vector<double>& values, int bins, std::string* why);

}  // namespace radmesh
