// Machine-readable summary of a run (summary.json).
#pragma once

#include "radmesh/mesh.h"
#include "radmesh/scene.h"
#include "radmesh/method.h"
#include "radmesh/solution.h"
#include "radmesh/solve.h"

#include <nlohmann/json.hpp>

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
  MethodOptions method_options;  // the method's options as solved with (empty for mesh only)
};

// The summary document; `result` may be null (mesh only). The "solver"
// object holds the method's name, the common solve counts, every option of
// the method (as given or its default) and every counter it published
// (units, where a counter has one, in "solver.units").
//
// Per patch values: "objects" always (patches grouped by name: patch count,
// area, area-weighted mean radiosity of the field and of the elements);
// "patches" (one entry per patch) when the scene has at most
// kSummaryPatches patches, else "patches_csv": "patches.csv", which
// write_patches_csv writes beside it.
nlohmann::json make_summary(const RunInfo& info, const Scene& scene, const Mesh& mesh,
                            const TriangleQuality& quality, const MethodResult* result);

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

// Writes JSON atomically (tmp + rename). Throws IoError.
void write_json(const std::string& path, const nlohmann::json& doc);

// A CSV field: quoted (quotes doubled) when it holds a comma, a quote or a
// line break (patch, material and probe names in patches.csv, probes.csv).
std::string csv_field(const std::string& text);

}  // namespace radmesh
