// Writing a file all at once: to PATH.tmp, every write checked, then renamed
// onto PATH (or, inside an OutputBatch, left for the batch to rename with
// the run's other files), so that a failure never leaves a half-written
// result behind and never touches the file that was there.
#pragma once

#include <functional>
#include <memory>
#include <ostream>
#include <streambuf>
#include <string>
#include <vector>

namespace radmesh {

// Calls write(stream) on a temporary file next to `path` and renames it onto
// `path` (inside an OutputBatch: leaves it to the batch). Throws IoError
// naming the path when any step fails (opening, a write, the close, the
// rename), with the system's reason; the temporary file is removed and a
// file already at `path` is left as it was.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

namespace internal {

// A file being written that never reports a failure to the code writing
// into it: the first failed write (a full disk, a file-size limit, an I/O
// error) is remembered and every later byte dropped, and close() throws
// it. VTK's XML writers cannot take a failing stream: on one they free a
// pointer they never set (vtkXMLUnstructuredDataWriter::WriteAPiece calls
// DeletePositionArrays, whose arrays only the appended mode allocates) and
// crash. Seekable (VTK goes back to fill in compressed blocks' sizes):
// positions are kept as if every write had succeeded.
class CheckedFile : public std::streambuf {
public:
  // Creates (or truncates) `path`. IoError naming `name` when it cannot.
  CheckedFile(const std::string& path, const std::string& name);
  ~CheckedFile() override;
  CheckedFile(const CheckedFile&) = delete;
  CheckedFile& operator=(const CheckedFile&) = delete;

  // Writes what is buffered and closes the file; IoError naming `name`,
  // with the reason of the first failure, when anything failed.
  void close();

protected:
  int_type overflow(int_type c) override;
  std::streamsize xsputn(const char* s, std::streamsize n) override;
  int sync() override;
  pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode which) override;
  pos_type seekpos(pos_type pos, std::ios_base::openmode which) override;

private:
  void flush_buffer();
  void write_at(long long offset, const char* data, std::size_t n);

  std::string name_;
  int fd_ = -1;
  int error_ = 0;             // errno of the first failure; 0 while none
  std::unique_ptr<char[]> buffer_;  // the put area
  long long start_ = 0;             // the file offset of buffer_[0]
  long long end_ = 0;               // the file's size as written so far
};

// Creating a folder and removing an earlier run's file the way the writers
// do: inside an OutputBatch through it (made folders removed again, files
// removed only at the commit), otherwise at once.
void create_output_directories(const std::string& dir);
void remove_output_file(const std::string& path);
// Makes `dir` and removes the files in it whose names match `pattern` (a
// regular expression) and are not in `keep`: what an earlier run left that
// this one does not write again, so that the folder holds one run's
// results. Inside an OutputBatch through it, as above.
void prepare_output_dir(const std::string& dir, const std::string& pattern, const std::vector<std::string>& keep);

// Fault injection, for tests and fuzz targets only: the disk fills (a write
// fails with ENOSPC) once `bytes` more bytes have been added to files, and
// the rename after `renames` more renames fails (EIO). -1: never. For the
// whole process; reset by the next call.
void inject_write_faults(long long bytes, long long renames = -1);

}  // namespace internal
}  // namespace radmesh
