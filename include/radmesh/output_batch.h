// Writing a run's files all or none. While an OutputBatch is open on a
// thread, every radmesh writer called on that thread (write_vtu,
// write_summary, the CSV tables, the pictures, a method's own files) leaves
// its finished file under a temporary name beside the target (PATH.tmp);
// commit() renames them all into place at the end. A batch destroyed
// without a commit (a write failed and an exception is on its way) removes
// every temporary file it holds and the folders it made, so that the output
// folder is left as it was:
//
//   radmesh::OutputBatch batch;
//   batch.create_directories("out");
//   radmesh::write_vtu("out/radiosity.vtu", result);
//   radmesh::write_summary("out/summary.json", result);  // IoError: nothing of the two is left
//   batch.commit();
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace radmesh {

class OutputBatch {
public:
  // Opens the batch on the calling thread; std::logic_error when one is
  // open there already.
  OutputBatch();
  // Not committed: removes the temporary files written in it and the
  // folders create_directories made (those left empty), and closes it.
  ~OutputBatch();
  OutputBatch(const OutputBatch&) = delete;
  OutputBatch& operator=(const OutputBatch&) = delete;

  // Makes `dir` and its missing parents; IoError naming it when that fails.
  // The folders made here are removed again if the batch is not committed
  // (when nothing else has been put in them).
  void create_directories(const std::string& dir);

  // Removes `path` when the batch is committed (an earlier run's file that
  // this one does not write again), not before.
  void remove_on_commit(const std::string& path);

  // Renames every file written in the batch onto its name, in the order
  // written, then removes what remove_on_commit named. A file already there
  // under a name is replaced (and cannot come back). When a rename fails:
  // IoError naming the file, and the batch removes the files it has
  // already renamed and the temporary files left, as if nothing had been
  // written. Closes the batch.
  void commit();

  // The files written in the batch so far (their final names), in order.
  std::vector<std::string> files() const;

  struct State;

private:
  std::unique_ptr<State> state_;
};

}  // namespace radmesh
