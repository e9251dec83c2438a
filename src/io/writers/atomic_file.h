// Writing a file all at once: to PATH.tmp, then renamed onto PATH, so that a
// failure never leaves a half-written result behind.
#pragma once

#include <functional>
#include <ostream>
#include <string>

namespace radmesh {

// Calls write(stream) on a temporary file next to `path` and renames it onto
// `path`. Throws IoError naming the path when any step fails; the temporary
// file is removed.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

// For a writer that opens files by name (VTK's XML writers): calls
// write(temporary) with the temporary file's name, then renames it onto
// `path`; the temporary file is removed when write throws or the rename fails.
void write_file_atomically_by_name(const std::string& path, const std::function<void(const std::string&)>& write);

}  // namespace radmesh
