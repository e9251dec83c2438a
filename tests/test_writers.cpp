// The writers on a full disk: every write is checked, a failed one throws an
// IoError naming its file, leaves no temporary file and keeps the file that
// was there before. Real failures come from a file-size limit (RLIMIT_FSIZE
// in a forked child: a write past it fails with EFBIG, as one on a full disk
// fails with ENOSPC), with no mount and no root; a disk that fills at any
// byte of a run's files, and a rename that fails, come from the writers'
// fault injection (internal::inject_write_faults).

#include "io/writers/atomic_file.h"
#include "radmesh/radmesh.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace radmesh;

namespace {

using test::kData;
using test::folder;
using test::names;

// How a child that ran a write ended.
enum ChildExit { kWritten = 0, kIoErrorNamingTheFile = 10, kIoErrorNotNamingIt = 11, kOtherException = 12 };

// Runs write() in a forked child whose files may not grow past `limit`
// bytes, SIGXFSZ ignored so that the write fails instead; returns the
// child's wait status (its exit code: ChildExit, `path` the file the error
// must name). The child's free memory is filled with a pattern first, and
// what it allocates (glibc), so that a writer that reads memory it never
// set (VTK's XML writer freed such a pointer on a failed write) fails every
// time, not only when the heap happens to hold garbage there.
int write_under_limit(long limit, const std::string& path, const std::function<void()>& write) {
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
#ifdef M_PERTURB
    ::mallopt(M_PERTURB, 0x5a);
#endif
    std::vector<void*> blocks;
    for (int round = 0; round < 8; ++round)
      for (std::size_t size = 16; size <= 4096; size += 16) {
        void* p = std::malloc(size);
        std::memset(p, 0xa5, size);
        blocks.push_back(p);
      }
    for (void* p : blocks) std::free(p);
    std::signal(SIGXFSZ, SIG_IGN);
    const rlimit r{static_cast<rlim_t>(limit), static_cast<rlim_t>(limit)};
    ::setrlimit(RLIMIT_FSIZE, &r);
    try {
      write();
    } catch (const IoError& e) {
      ::_exit(test::contains(e.what(), path) ? kIoErrorNamingTheFile : kIoErrorNotNamingIt);
    } catch (...) {
      ::_exit(kOtherException);
    }
    ::_exit(kWritten);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return status;
}

std::string describe(int status) {
  if (WIFSIGNALED(status)) return "killed by signal " + std::to_string(WTERMSIG(status));
  switch (WEXITSTATUS(status)) {
    case kWritten: return "written";
    case kIoErrorNamingTheFile: return "IoError naming the file";
    case kIoErrorNotNamingIt: return "IoError not naming the file";
    case kOtherException: return "another exception";
    default: return "exit " + std::to_string(WEXITSTATUS(status));
  }
}

// The results the writers write, made once: the parallel plates by the
// pixmap method (a display mesh of many small triangles: its .vtu is where
// VTK's XML writer crashed on a full disk) and by the matrix method (with a
// probe), the box on the floor by the hierarchical method with its links
// and contact lines.
struct Results {
  Result pixmap, matrix, hierarchical;
  std::vector<MethodResult> rounds;  // the hierarchical method's, one per refinement round
  std::vector<Probe> probes;
  std::vector<ProbeResult> probe_results;
  std::vector<std::string> patch_names;
  std::vector<PatchQuality> quality_rows;

  Results() {
    const Scene plates = read_scene(kData + "/parallel_plates/parallel_plates.obj");
    pixmap = solve(plates, PixmapOptions{});
    matrix = solve(plates, MatrixOptions{});
    HierarchicalOptions h;
    h.epsilon = 0.01;
    h.export_links = true;
    SolveCallbacks cb;
    cb.on_round = [this](const MethodResult& r, int) { rounds.push_back(r); };
    hierarchical = solve(read_scene(kData + "/box_on_floor/box_on_floor.obj"), h, SolveOptions{}, cb);
    Probe p;
    p.label = "centre";
    p.point = Vec3(0.5, 0.5, 1.0);
    p.normal = Vec3(0.0, 0.0, -1.0);
    probes = {p};
    probe_results = evaluate_probes(plates, matrix.mesh, matrix.solution.element, probes, SolveOptions{});
    for (const Patch& patch : hierarchical.scene->patches) patch_names.push_back(patch.name);
    const Mesh& m = hierarchical.mesh;
    quality_rows = patch_quality(static_cast<int>(patch_names.size()), m, compute_quality(m),
                                 hierarchical.mesh_report.discontinuities);
  }
};

const Results& results() {
  static const Results r;
  return r;
}

// One writer of one file: its name, and the call that writes it to a path
// (false when it cannot write here: no display for a picture).
struct OneFileWriter {
  std::string file;
  std::function<bool(const std::string&)> write;
};

std::vector<OneFileWriter> one_file_writers() {
  const Results& r = results();
  std::vector<OneFileWriter> w;
  auto always = [](std::function<void(const std::string&)> f) {
    return [f](const std::string& path) {
      f(path);
      return true;
    };
  };
  w.push_back({"radiosity.vtu", always([&r](const std::string& p) { write_vtu(p, r.pixmap); })});
  w.push_back({"matrix.vtu", always([&r](const std::string& p) { write_vtu(p, r.matrix); })});
  w.push_back({"mesh.vtu", always([&r](const std::string& p) {
                 write_mesh_vtu(p, *r.matrix.scene, r.matrix.mesh, compute_quality(r.matrix.mesh));
               })});
  w.push_back({"links.vtu", always([&r](const std::string& p) {
                 for (const auto& [stem, lines] : r.hierarchical.line_sets)
                   if (stem == "links") write_lines_vtu(p, lines);
               })});
  w.push_back({"discontinuities.vtu", always([&r](const std::string& p) {
                 write_discontinuities_vtu(p, r.hierarchical.mesh_report.discontinuities);
               })});
  w.push_back({"radiosity.pvd", always([](const std::string& p) {
                 write_pvd(p, {"radiosity_round_0.vtu", "radiosity_round_1.vtu"});
               })});
  w.push_back({"summary.json", always([&r](const std::string& p) { write_summary(p, r.hierarchical); })});
  w.push_back({"patches.csv", always([&r](const std::string& p) {
                 write_patches_csv(p, *r.hierarchical.scene, r.hierarchical.mesh, &r.hierarchical.solution);
               })});
  w.push_back({"probes.csv", always([&r](const std::string& p) {
                 write_probe_csv(p, *r.matrix.scene, r.probes, r.probe_results);
               })});
  w.push_back({"quality.csv", always([&r](const std::string& p) {
                 write_quality_csv(p, r.patch_names, r.quality_rows);
               })});
  w.push_back({"radiosity.png", [&r](const std::string& p) {
                 RenderOptions o;
                 o.width = o.height = 96;
                 std::string why;
                 return render_png(p, *r.matrix.scene, r.matrix.mesh, r.matrix.solution, o, &why);
               }});
  w.push_back({"histogram.png", [](const std::string& p) {
                 std::string why;
                 return plot_histogram(p, "angles", "angle", {1.0, 2.0, 2.5, 3.0}, 4, &why);
               }});
  return w;
}

}  // namespace

// Each writer of one file, its file limited to 0, 1, a third of its size and
// its size less one byte: an IoError naming the file (never a crash), and the
// file that was there before is all the folder holds, unchanged. At its full
// size it is written.
TEST(Writers, UnderAFileSizeLimitEveryWriterThrowsIoErrorNamingItsFileAndKeepsTheOneBefore) {
  const test::TempDir tmp;
  for (const OneFileWriter& w : one_file_writers()) {
    const fs::path whole_dir = tmp / ("whole_" + w.file), dir = tmp / w.file;
    fs::create_directories(whole_dir);
    fs::create_directories(dir);
    const std::string whole = (whole_dir / w.file).string(), path = (dir / w.file).string();
    if (!w.write(whole)) {
      std::printf("%s: not written here (no display): skipped\n", w.file.c_str());
      continue;
    }
    const long size = static_cast<long>(fs::file_size(whole));
    std::ofstream(path) << "an earlier run's file\n";
    const auto before = folder(dir);
    for (const long limit : {0L, 1L, size / 3, size - 1}) {
      const int status = write_under_limit(limit, path, [&] { w.write(path); });
      EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == kIoErrorNamingTheFile)
          << w.file << " (" << size << " bytes) limited to " << limit << " bytes: " << describe(status);
      EXPECT_TRUE(folder(dir) == before) << w.file << " limited to " << limit << " bytes left " << names(folder(dir));
    }
    const int status = write_under_limit(size, path, [&] { w.write(path); });
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == kWritten) << w.file << ": " << describe(status);
    EXPECT_TRUE(folder(dir) == folder(whole_dir)) << w.file;
  }
}

namespace {

// A run's files as the radmesh program writes them, in one OutputBatch:
// the hierarchical result's .vtu, round files, .pvd, links and contact
// lines, the pixmap result's own files (its state, lightmaps, OBJ and MTL),
// a probe table, the picture (where there is a display), the summary and
// the patch table. Returns the files written, in order.
std::vector<std::string> write_a_run(const fs::path& dir) {
  const Results& r = results();
  OutputBatch batch;
  batch.create_directories(dir.string());
  // An earlier run's round file that this one does not write: removed at the commit.
  batch.remove_on_commit((dir / "radiosity_round_7.vtu").string());
  const Result& h = r.hierarchical;
  write_vtu((dir / "radiosity.vtu").string(), h);
  std::vector<std::string> rounds;
  for (size_t k = 0; k < r.rounds.size(); ++k) {
    const MethodResult& snap = r.rounds[k];
    rounds.push_back("radiosity_round_" + std::to_string(k) + ".vtu");
    write_vtu((dir / rounds.back()).string(), *h.scene, snap.mesh, compute_quality(snap.mesh), snap.solution,
              snap.cell_fields);
  }
  write_pvd((dir / "radiosity.pvd").string(), rounds);
  for (const auto& [stem, lines] : h.line_sets) write_lines_vtu((dir / (stem + ".vtu")).string(), lines);
  write_discontinuities_vtu((dir / "discontinuities.vtu").string(), h.mesh_report.discontinuities);
  r.pixmap.files.write(dir.string(), r.pixmap.mesh);
  write_probe_csv((dir / "probes.csv").string(), *r.matrix.scene, r.probes, r.probe_results);
  RenderOptions o;
  o.width = o.height = 96;
  std::string why;
  render_png((dir / "radiosity.png").string(), *h.scene, h.mesh, h.solution, o, &why);
  write_summary((dir / "summary.json").string(), h);
  write_patches_csv((dir / "patches.csv").string(), *h.scene, h.mesh, &h.solution);
  std::vector<std::string> files = batch.files();
  batch.commit();
  return files;
}

// An earlier run's files of every name `files` has (and a stale round file
// and a user's file) in `dir`.
void write_an_earlier_run(const fs::path& dir, const std::vector<std::string>& files) {
  for (const std::string& f : files) {
    fs::create_directories(fs::path(f).parent_path());
    std::ofstream(f) << "an earlier run's " << fs::path(f).filename().string() << "\n";
  }
  std::ofstream(dir / "radiosity_round_7.vtu") << "an earlier run's round 7\n";
  std::ofstream(dir / "notes.txt") << "the user's notes\n";
}

// Clears the injected faults when a test ends, however it ends.
struct NoFaultsAfter {
  ~NoFaultsAfter() { internal::inject_write_faults(-1, -1); }
};

}  // namespace

// The disk fills in the middle of each file of a run in turn (and at its
// first and last byte): an IoError naming that file, and the folder as it
// was: an earlier run's files unchanged, the stale round file still there,
// no file of this run, no temporary file. Where it never fills, the run's
// files are all there and the stale round file is gone.
TEST(Writers, ADiskThatFillsAtAnyFileOfARunLeavesTheFolderAsItWas) {
  const test::TempDir tmp;
  const NoFaultsAfter reset;
  const fs::path whole = tmp / "whole", dir = tmp / "run";
  const std::vector<std::string> files = write_a_run(whole);
  ASSERT_GE(files.size(), 15u);
  std::vector<std::string> in_dir;
  for (const std::string& f : files) in_dir.push_back((dir / fs::relative(f, whole)).string());
  write_an_earlier_run(dir, in_dir);
  const auto before = folder(dir);
  long long start = 0;
  for (size_t k = 0; k < files.size(); ++k) {
    const long long size = static_cast<long long>(fs::file_size(files[k]));
    for (const long long at : {start, start + size / 2, start + size - 1}) {
      internal::inject_write_faults(at);
      const test::Thrown e = test::thrown<IoError>([&] { write_a_run(dir); });
      internal::inject_write_faults(-1);
      EXPECT_TRUE(e.says({in_dir[k] + ": ", "No space left on device"})) << "full at byte " << at;
      const auto after = folder(dir);
      EXPECT_TRUE(after == before) << "full at byte " << at << " of " << files[k] << ": " << names(after);
    }
    start += size;
  }
  EXPECT_EQ(write_a_run(dir), in_dir);
  auto expected = folder(whole);
  expected["notes.txt"] = "the user's notes\n";
  EXPECT_TRUE(folder(dir) == expected) << names(folder(dir));
}

// A rename at the commit fails (the first, one in the middle, the last):
// an IoError naming that file, and no file of the run is left, neither
// those renamed before it (the earlier run's files of those names are gone:
// they cannot come back) nor the temporary ones.
TEST(Writers, ARenameThatFailsAtTheCommitLeavesNoFileOfTheRun) {
  const test::TempDir tmp;
  const NoFaultsAfter reset;
  const fs::path whole = tmp / "whole", dir = tmp / "run";
  const std::vector<std::string> files = write_a_run(whole);
  std::vector<std::string> in_dir;
  for (const std::string& f : files) in_dir.push_back((dir / fs::relative(f, whole)).string());
  for (const size_t k : {size_t{0}, files.size() / 2, files.size() - 1}) {
    fs::remove_all(dir);
    write_an_earlier_run(dir, in_dir);
    auto expected = folder(dir);
    for (size_t j = 0; j < k; ++j) expected.erase(fs::relative(in_dir[j], dir).string());
    internal::inject_write_faults(-1, static_cast<long long>(k));
    const test::Thrown e = test::thrown<IoError>([&] { write_a_run(dir); });
    internal::inject_write_faults(-1);
    EXPECT_TRUE(e.says({in_dir[k] + ": cannot rename"})) << e.message;
    EXPECT_TRUE(folder(dir) == expected) << "rename " << k << " failed: " << names(folder(dir));
  }
}

// Into a folder the run makes: a failure leaves no folder either (the
// pixmap state's and the lightmaps' folders included).
TEST(Writers, AFailedRunRemovesTheFoldersItMade) {
  const test::TempDir tmp;
  const NoFaultsAfter reset;
  const fs::path dir = tmp / "a" / "b" / "out";
  internal::inject_write_faults(-1, 3);
  EXPECT_TRUE(test::thrown<IoError>([&] { write_a_run(dir); }).says({"cannot rename"}));
  EXPECT_FALSE(fs::exists(tmp / "a"));
  internal::inject_write_faults(1000);
  EXPECT_TRUE(test::thrown<IoError>([&] { write_a_run(dir); }).says({"radiosity.vtu: "}));
  EXPECT_FALSE(fs::exists(tmp / "a"));
  // A folder that held something before is kept.
  fs::create_directories(dir / "pixmaps");
  std::ofstream(dir / "pixmaps" / "mine.txt") << "mine\n";
  internal::inject_write_faults(-1, 0);
  EXPECT_TRUE(test::thrown<IoError>([&] { write_a_run(dir); }).says({"cannot rename"}));
  const auto left = folder(tmp.path());
  EXPECT_EQ(left.size(), 1u) << names(left);
  EXPECT_TRUE(fs::exists(dir / "pixmaps" / "mine.txt"));
}

// Inside a batch, files appear only at its commit: until then they are
// temporary files beside their names, and an earlier file of that name is
// untouched; a batch given up removes them. One batch per thread.
TEST(Writers, ABatchShowsItsFilesOnlyAtItsCommit) {
  const test::TempDir tmp;
  const Results& r = results();
  const std::string vtu = (tmp / "radiosity.vtu").string(), summary = (tmp / "summary.json").string();
  std::ofstream(summary) << "earlier\n";
  std::ofstream(tmp / "links.vtu") << "earlier links\n";
  {
    OutputBatch batch;
    EXPECT_THROW(OutputBatch second, std::logic_error);
    write_vtu(vtu, r.matrix);
    write_summary(summary, r.matrix);
    EXPECT_FALSE(fs::exists(vtu));
    EXPECT_TRUE(fs::exists(vtu + ".tmp"));
    EXPECT_EQ(folder(tmp.path())["summary.json"], "earlier\n");
    EXPECT_EQ(batch.files(), (std::vector<std::string>{vtu, summary}));
  }  // given up
  EXPECT_EQ(folder(tmp.path()).size(), 2u) << names(folder(tmp.path()));
  EXPECT_EQ(folder(tmp.path())["summary.json"], "earlier\n");
  {
    OutputBatch batch;
    write_vtu(vtu, r.matrix);
    write_summary(summary, r.matrix);
    batch.remove_on_commit((tmp / "links.vtu").string());
    EXPECT_TRUE(fs::exists(tmp / "links.vtu"));
    batch.commit();
  }
  EXPECT_TRUE(fs::exists(vtu));
  EXPECT_NE(folder(tmp.path())["summary.json"], "earlier\n");
  EXPECT_FALSE(fs::exists(tmp / "links.vtu"));
  EXPECT_EQ(folder(tmp.path()).size(), 2u) << names(folder(tmp.path()));
  // After the batch, a writer renames at once again.
  write_summary(summary, r.pixmap);
  EXPECT_FALSE(fs::exists(summary + ".tmp"));
}
