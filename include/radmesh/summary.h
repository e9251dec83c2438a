// Machine-readable summary of a run (summary.json) and the CSV tables
// beside it (patches.csv, quality.csv).
#pragma once

#include "radmesh/mesh.h"
#include "radmesh/method.h"
#include "radmesh/options.h"
#include "radmesh/run.h"
#include "radmesh/scene.h"
#include "radmesh/solution.h"
#include "radmesh/solve.h"

#include <string>
#include <utility>
#include <vector>

namespace radmesh {

struct RunInfo {
  std::string command;  // "run" or "mesh"
  std::string scene_path;
  MeshingOptions meshing;  // as resolved
  SolveOptions solve;
  MeshReport mesh_report;
  std::vector<std::pair<std::string, double>> seconds;  // phase -> wall seconds, in order
  std::string method = "none";  // the solver (methods() name), "none" for mesh only
  std::vector<OptionValue> method_options;  // the method's options as solved with (empty for mesh only)
  std::string preset = "default";  // the preset the options were filled from (Method::presets)
};

// Writes the summary document atomically (tmp + rename; IoError); `result`
// may be null (mesh only). The "solver" object holds the method's name, the
// common solve counts, every option of the method (as given or its default)
// and every counter it published (units, where a counter has one, in
// "solver.units").
//
// Per patch values: "objects" always (patches grouped by name: patch count,
// area, area-weighted mean radiosity of the field and of the elements);
// "patches" (one entry per patch) when the scene has at most
// kSummaryPatches patches, else "patches_csv": "patches.csv", which
// write_patches_csv writes beside it.
void write_summary(const std::string& path, const RunInfo& info, const Scene& scene, const Mesh& mesh,
                   const TriangleQuality& quality, const MethodResult* result);
// What radmesh::solve's result says of its run ("seconds": its phases).
RunInfo run_info(const Result& result);
// The summary of radmesh::solve's result.
void write_summary(const std::string& path, const Result& result);
// The text write_summary(path, result) writes.
std::string summary_text(const Result& result);

inline constexpr size_t kSummaryPatches = 10000;
bool patches_in_summary(const Scene& scene);

// patches.csv: id,name,material,area (and with a solution mean_r,mean_g,mean_b,
// element_mean_r,element_mean_g,element_mean_b), one row per patch. Written
// atomically. Throws IoError.
void write_patches_csv(const std::string& path, const Scene& scene, const Mesh& mesh, const Solution* solution);

// quality.csv: one row per patch and a total row (patch_id -1, name "total"):
// patch_id,name,triangles,min_angle,max_angle,aspect_p50,aspect_p95,aspect_max,
// contact_segments,d1_segments,d2_segments,zero_area. Written atomically. Throws IoError.
void write_quality_csv(const std::string& path, const std::vector<std::string>& patch_names,
                       const std::vector<PatchQuality>& rows);

}  // namespace radmesh
