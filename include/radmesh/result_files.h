// The files of a run, as the radmesh program writes them: one call writes
// them all or none.
#pragma once

#include "radmesh/method.h"
#include "radmesh/probe.h"
#include "radmesh/run.h"
#include "radmesh/summary.h"

#include <string>
#include <vector>

namespace radmesh {

// What a run leaves to be written. `result` null: a mesh without a solve
// (mesh.vtu instead of radiosity.vtu).
struct RunFiles {
  RunInfo info;                 // for summary.json; write_run_files adds the "write" phase
  const Scene* scene = nullptr;
  const Mesh* mesh = nullptr;   // the initial mesh (written when there is no result)
  const MethodResult* result = nullptr;
  std::vector<MethodResult> rounds;  // snapshots per refinement round: radiosity_round_K.vtu + radiosity.pvd
  std::vector<Probe> probes;         // with probe_results: probes.csv
  std::vector<ProbeResult> probe_results;
  bool png = true;                   // radiosity.png, where a display can be had
};

// Writes into `out_dir`: radiosity.vtu (or mesh.vtu), summary.json (and
// patches.csv when the scene has more than kSummaryPatches patches), the
// round series, the result's line sets (NAME.vtu), discontinuities.vtu
// where the mesh has contact or shadow lines, the method's own files,
// probes.csv and radiosity.png. Every file goes under a temporary name and
// is renamed at the end (OutputBatch): when one cannot be written (IoError)
// none is left and the folder is as it was; the files an earlier run left
// there that this one does not write again are removed. Returns the paths
// written, in order; `notes` gets why the PNG was skipped (no display).
std::vector<std::string> write_run_files(const std::string& out_dir, RunFiles files,
                                         std::vector<std::string>* notes = nullptr);

// radmesh::solve's result written as `radmesh run` writes it (without
// rounds or probes).
std::vector<std::string> write_result_files(const std::string& out_dir, const Result& result, bool png = true,
                                            std::vector<std::string>* notes = nullptr);

// The regular expression of every name write_run_files may write (the
// methods' own files included): what it removes of an earlier run.
std::string run_file_pattern();

}  // namespace radmesh
