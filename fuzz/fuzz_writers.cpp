// libFuzzer target: a run's files written the way the radmesh program writes
// them (one OutputBatch) while the disk fills at a byte the input chooses, or
// a rename at the commit fails. The files are those of three small results
// solved once (the parallel plates by the hierarchical method with its links
// and rounds, by the pixmap method with its state and lightmaps, by the
// matrix method with a probe). Input: byte 0 picks the groups of files
// (bits 0-2; none: all), byte 1 the fault (even: the disk fills, odd: a
// rename fails), bytes 2-5 where, as a fraction of the bytes (renames) the
// set takes (2^32: past the end, no fault).
//
// Checks: a fault that falls inside the set is an IoError naming the file it
// falls in (never a crash, another error or silence); after it the output
// folder is as it was (an earlier run's files unchanged, none of this run's,
// no temporary file, no folder it made); without a fault every file is
// there.

#include "fuzz/fuzz_util.h"
#include "io/writers/atomic_file.h"
#include "radmesh/radmesh.h"

#include <cstring>
#include <map>

namespace {

using namespace radmesh;
namespace fs = std::filesystem;

struct Solved {
  Result hierarchical, pixmap, matrix;
  std::vector<MethodResult> rounds;
  std::vector<Probe> probes;
  std::vector<ProbeResult> probe_results;
};

const Solved& solved() {
  static const Solved* s = [] {
    auto* r = new Solved;
    const Scene plates = read_scene(std::string(RADMESH_FUZZ_DATA) + "/parallel_plates/parallel_plates.obj");
    HierarchicalOptions h;
    h.export_links = true;
    SolveCallbacks cb;
    cb.on_round = [r](const MethodResult& m, int) { r->rounds.push_back(m); };
    r->hierarchical = solve(plates, h, SolveOptions{}, cb);
    PixmapOptions p;
    p.texel_size = 0.125;
    r->pixmap = solve(plates, p);
    r->matrix = solve(plates, MatrixOptions{});
    Probe probe;
    probe.label = "centre";
    probe.point = Vec3(0.5, 0.5, 1.0);
    probe.normal = Vec3(0.0, 0.0, -1.0);
    r->probes = {probe};
    r->probe_results = evaluate_probes(plates, r->matrix.mesh, r->matrix.solution.element, r->probes, SolveOptions{});
    return r;
  }();
  return *s;
}

// The groups of files: 1 the hierarchical result's (.vtu, rounds, .pvd,
// links), 2 the pixmap method's own (state, lightmaps, OBJ, MTL), 4 the
// tables (probes.csv, summary.json, patches.csv).
void write_set(int groups, const fs::path& dir, std::vector<std::string>* files) {
  const Solved& s = solved();
  OutputBatch batch;
  batch.create_directories(dir.string());
  batch.remove_on_commit((dir / "radiosity_round_7.vtu").string());
  if (groups & 1) {
    const Result& h = s.hierarchical;
    write_vtu((dir / "radiosity.vtu").string(), h);
    std::vector<std::string> names;
    for (size_t k = 0; k < s.rounds.size(); ++k) {
      names.push_back("radiosity_round_" + std::to_string(k) + ".vtu");
      write_vtu((dir / names.back()).string(), *h.scene, s.rounds[k].mesh, compute_quality(s.rounds[k].mesh),
                s.rounds[k].solution, s.rounds[k].cell_fields);
    }
    write_pvd((dir / "radiosity.pvd").string(), names);
    for (const auto& [stem, lines] : h.line_sets) write_lines_vtu((dir / (stem + ".vtu")).string(), lines);
  }
  if (groups & 2) s.pixmap.files.write(dir.string(), s.pixmap.mesh);
  if (groups & 4) {
    write_probe_csv((dir / "probes.csv").string(), *s.matrix.scene, s.probes, s.probe_results);
    write_summary((dir / "summary.json").string(), s.matrix);
    write_patches_csv((dir / "patches.csv").string(), *s.matrix.scene, s.matrix.mesh, &s.matrix.solution);
  }
  if (files) *files = batch.files();
  batch.commit();
}

// What a set writes: its files (relative to the folder), in order, and their sizes.
struct Measured {
  std::vector<std::string> files;
  std::vector<long long> sizes;
  long long total = 0;
};

const Measured& measured(int groups) {
  static std::map<int, Measured> cache;
  auto it = cache.find(groups);
  if (it != cache.end()) return it->second;
  const fs::path dir = fuzz::scratch_dir() / ("measure_" + std::to_string(groups));
  std::vector<std::string> files;
  write_set(groups, dir, &files);
  Measured m;
  for (const std::string& f : files) {
    m.files.push_back(fs::relative(f, dir).string());
    m.sizes.push_back(static_cast<long long>(fs::file_size(f)));
    m.total += m.sizes.back();
  }
  std::error_code ec;
  fs::remove_all(dir, ec);
  return cache.emplace(groups, m).first->second;
}

// Every file under `dir` (relative name -> content), and whether it holds
// anything but regular files and the folders they are in.
std::map<std::string, std::string> listing(const fs::path& dir) {
  std::map<std::string, std::string> out;
  std::error_code ec;
  for (const auto& e : fs::recursive_directory_iterator(dir, ec)) {
    const std::string name = fs::relative(e.path(), dir).string();
    if (e.is_directory()) {
      if (fs::is_empty(e.path(), ec)) out[name + "/"] = "";
      continue;
    }
    std::ifstream in(e.path(), std::ios::binary);
    out[name] = std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }
  return out;
}

// The output folder as an earlier run and the user left it.
std::map<std::string, std::string> earlier_run(const fs::path& dir) {
  std::error_code ec;
  fs::remove_all(dir, ec);
  fs::create_directories(dir);
  const std::map<std::string, std::string> files = {{"summary.json", "an earlier run's summary\n"},
                                                     {"radiosity_round_7.vtu", "an earlier run's round 7\n"},
                                                     {"notes.txt", "the user's notes\n"}};
  for (const auto& [name, content] : files) std::ofstream(dir / name, std::ios::binary) << content;
  return files;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 6) return 0;
  int groups = data[0] & 7;
  if (groups == 0) groups = 7;
  const bool rename_fault = (data[1] & 1) != 0;
  uint32_t where = 0;
  std::memcpy(&where, data + 2, 4);
  const Measured& m = measured(groups);
  const long long span = rename_fault ? static_cast<long long>(m.files.size()) : m.total;
  const long long at = static_cast<long long>((static_cast<unsigned long long>(where) * (span + 1)) >> 32);
  const bool fault = at < span;
  // The file the fault falls in.
  size_t k = 0;
  if (rename_fault) {
    k = static_cast<size_t>(at);
  } else {
    for (long long start = 0; k < m.files.size() && start + m.sizes[k] <= at; ++k) start += m.sizes[k];
  }

  const fs::path dir = fuzz::scratch_dir() / "out";
  const auto before = earlier_run(dir);
  internal::inject_write_faults(rename_fault ? -1 : at, rename_fault ? at : -1);
  std::string failure;
  try {
    write_set(groups, dir, nullptr);
  } catch (const IoError& e) {
    failure = e.what();
  } catch (const std::exception& e) {
    internal::inject_write_faults(-1, -1);
    fuzz::defect(std::string("not an IoError: ") + e.what());
  }
  internal::inject_write_faults(-1, -1);

  const auto after = listing(dir);
  if (!fault) {
    if (!failure.empty()) fuzz::defect("no fault injected, yet: " + failure);
    for (const std::string& f : m.files)
      if (!after.count(f)) fuzz::defect(f + " missing after a run that succeeded");
    if (after.count("radiosity_round_7.vtu")) fuzz::defect("the earlier run's round 7 left after a run that succeeded");
    return 0;
  }
  if (failure.empty()) fuzz::defect("a fault at " + std::to_string(at) + " went unreported");
  const std::string file = (dir / m.files[k]).string();
  if (failure.rfind(file + ": ", 0) != 0) fuzz::defect("the error names another file than " + file + ": " + failure);
  for (const auto& [name, content] : after) {
    const auto was = before.find(name);
    if (was == before.end()) fuzz::defect(name + " left after a failed run: " + failure);
    if (was->second != content) fuzz::defect(name + " changed by a failed run: " + failure);
  }
  // A failed rename removes what the batch renamed before it: an earlier
  // file of such a name is gone. Nothing else may be.
  for (const auto& [name, content] : before) {
    if (after.count(name)) continue;
    bool renamed_before = false;
    for (size_t j = 0; j < k && rename_fault; ++j) renamed_before |= m.files[j] == name;
    if (!renamed_before) fuzz::defect("the earlier " + name + " removed by a failed run: " + failure);
  }
  return 0;
}
