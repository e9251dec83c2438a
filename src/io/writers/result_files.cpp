// write_run_files: the radmesh program's files of a run, all or none.

#include "radmesh/result_files.h"

#include "io/writers/atomic_file.h"
#include "radmesh/output_batch.h"
#include "radmesh/png_render.h"
#include "radmesh/probe_file.h"
#include "radmesh/vtk_writer.h"

#include <cctype>
#include <chrono>
#include <filesystem>

namespace radmesh {

std::string run_file_pattern() {
  std::string ours = R"((radiosity|mesh|links|discontinuities)\.vtu|radiosity_round_[0-9]+\.vtu|radiosity\.pvd|)"
                     R"(probes\.csv|radiosity\.png|summary\.json|patches\.csv)";
  for (const Method& m : methods())
    for (const std::string& name : m.files) {
      ours += '|';
      for (char c : name) {
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') ours += '\\';
        ours += c;
      }
    }
  return ours;
}

std::vector<std::string> write_run_files(const std::string& out_dir, RunFiles files, std::vector<std::string>* notes) {
  namespace fs = std::filesystem;
  const auto start = std::chrono::steady_clock::now();
  const MethodResult* result = files.result;
  const Scene& scene = *files.scene;
  const Mesh& out_mesh = result ? result->mesh : *files.mesh;
  const TriangleQuality out_quality = compute_quality(out_mesh);
  const std::vector<DiscontinuitySegment>& lines = files.info.mesh_report.discontinuities;
  std::vector<std::string> outputs = {result ? "radiosity.vtu" : "mesh.vtu", "summary.json"};
  if (!patches_in_summary(scene)) outputs.push_back("patches.csv");
  if (!files.rounds.empty()) outputs.push_back("radiosity.pvd");
  for (size_t r = 0; r < files.rounds.size(); ++r) outputs.push_back("radiosity_round_" + std::to_string(r) + ".vtu");
  if (result)
    for (const auto& ls : result->line_sets) outputs.push_back(ls.first + ".vtu");
  if (!lines.empty()) outputs.push_back("discontinuities.vtu");
  if (!files.probes.empty()) outputs.push_back("probes.csv");
  if (result && files.png) outputs.push_back("radiosity.png");
  if (result)
    for (const std::string& name : result->files.names) outputs.push_back(name);
  OutputBatch batch;
  internal::prepare_output_dir(out_dir, run_file_pattern(), outputs);  // through the batch: removed at its commit

  std::vector<std::string> written;
  auto path_in_out = [&](const std::string& name) { return (fs::path(out_dir) / name).string(); };
  const std::string vtu = path_in_out(result ? "radiosity.vtu" : "mesh.vtu");
  if (result)
    write_vtu(vtu, scene, out_mesh, out_quality, result->solution, result->cell_fields);
  else
    write_mesh_vtu(vtu, scene, out_mesh, out_quality);
  written.push_back(vtu);
  if (!files.rounds.empty()) {
    // One file per refinement round and a .pvd collection to step through them.
    std::vector<std::string> names;
    for (size_t r = 0; r < files.rounds.size(); ++r) {
      const std::string name = "radiosity_round_" + std::to_string(r) + ".vtu";
      const MethodResult& snap = files.rounds[r];
      write_vtu(path_in_out(name), scene, snap.mesh, compute_quality(snap.mesh), snap.solution, snap.cell_fields);
      names.push_back(name);
    }
    const std::string pvd = path_in_out("radiosity.pvd");
    write_pvd(pvd, names);
    written.push_back(pvd);
  }
  if (result)
    for (const auto& [stem, set] : result->line_sets) {
      const std::string path = path_in_out(stem + ".vtu");
      write_lines_vtu(path, set);
      written.push_back(path);
    }
  if (!lines.empty()) {
    const std::string path = path_in_out("discontinuities.vtu");
    write_discontinuities_vtu(path, lines);
    written.push_back(path);
  }
  if (result && result->files.write)
    for (const std::string& f : result->files.write(out_dir, out_mesh)) written.push_back(f);
  if (!files.probes.empty()) {
    const std::string csv = path_in_out("probes.csv");
    write_probe_csv(csv, scene, files.probes, files.probe_results);
    written.push_back(csv);
  }
  if (result && files.png) {
    const std::string png = path_in_out("radiosity.png");
    std::string why;
    if (render_png(png, scene, out_mesh, result->solution, RenderOptions{}, &why))
      written.push_back(png);
    else if (notes)
      notes->push_back("PNG skipped: " + why);
  }
  files.info.seconds.push_back(
      {"write", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()});
  const std::string summary = path_in_out("summary.json");
  write_summary(summary, files.info, scene, out_mesh, out_quality, result);
  written.push_back(summary);
  if (!patches_in_summary(scene)) {
    const std::string csv = path_in_out("patches.csv");
    write_patches_csv(csv, scene, out_mesh, result ? &result->solution : nullptr);
    written.push_back(csv);
  }
  batch.commit();
  return written;
}

std::vector<std::string> write_result_files(const std::string& out_dir, const Result& result, bool png,
                                            std::vector<std::string>* notes) {
  RunFiles files;
  files.info = run_info(result);
  files.scene = result.scene.get();
  files.result = &result;
  files.png = png;
  return write_run_files(out_dir, std::move(files), notes);
}

}  // namespace radmesh
