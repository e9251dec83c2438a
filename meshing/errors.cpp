#include "meshing/errors.h"

namespace radmesh {

std::string where(const std::string& file, int line) {
  std::string s;
  s.append(file);
  if (line > 0) {
    s.push_back(':');
    s.append(std::to_string(line));
  }
  if (!s.empty()) s.append(": ");
  return s;
}

}  // namespace radmesh
