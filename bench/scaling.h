// The scaling benchmark: closed rooms lit from the ceiling holding ever more
// input triangles (a tessellated sphere, a field of small boxes) and the
// scanned bunny, also cut finer; every run is the command line `radmesh run` in its own
// process, timed per phase (summary.json) with its peak memory (wait4's
// rusage). One CSV row per run, two log-log plots (time and links against
// input triangles, one series per clusters mode).
#pragma once

#include <string>
#include <vector>

namespace radmesh::bench {

struct ScalingOptions {
  std::string out_dir = "bench-out";
  std::string radmesh;        // the radmesh program
  std::string data;           // the data directory (for the bunny)
  double max_triangles = 1e5;  // the largest generated scene
  std::vector<std::string> modes = {"volume", "off"};  // --clusters of the hierarchical runs
  double time_limit = 600.0;   // seconds per run; a run past it is killed and noted
  double matrix_up_to = 3000;  // also run --method matrix on scenes of at most this many input faces
};

// Writes scaling.csv, scaling_time.png and scaling_links.png under out_dir
// (the scenes under out_dir/scaling/). Returns the exit status.
int scaling_benchmark(const ScalingOptions& options);

// The generated scenes, for tests and for people: OBJ + MTL in `dir`.
// sphere: an icosphere of 20 x 4^level triangles floating in the room;
// boxes: k x k boxes of five faces standing on the floor. Return the OBJ path.
std::string write_sphere_room(const std::string& dir, int level);
std::string write_boxes_room(const std::string& dir, int k);
// bunny: the bundled bunny room (`data`/bunny) with each bunny triangle cut
// into 4^level by midpoint subdivision (the same surface); returns the JSON
// scene's path (bunny_<level>.json beside bunny_<level>.obj).
std::string write_bunny_room(const std::string& dir, const std::string& data, int level);

}  // namespace radmesh::bench
