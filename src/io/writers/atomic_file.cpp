// Files written whole: to a temporary name beside the target, renamed into
// place once complete, so that a failure leaves no half-written file and an
// existing file untouched.

#include "io/writers/atomic_file.h"

#include "radmesh/errors.h"

#include <filesystem>
#include <fstream>

namespace radmesh {

namespace {

void rename_into_place(const std::string& tmp, const std::string& path) {
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw IoError(path + ": cannot rename the finished file into place");
  }
}

}  // namespace

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw IoError(path + ": cannot open for writing");
    try {
      write(out);
    } catch (...) {
      out.close();
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw;
    }
    out.flush();
    if (!out) {
      out.close();
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw IoError(path + ": write failed (disk full?)");
    }
  }
  rename_into_place(tmp, path);
}

void write_file_atomically_by_name(const std::string& path, const std::function<void(const std::string&)>& write) {
  const std::string tmp = path + ".tmp";
  try {
    write(tmp);
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw;
  }
  rename_into_place(tmp, path);
}

}  // namespace radmesh
