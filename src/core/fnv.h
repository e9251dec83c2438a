// FNV-1a, 64 bits, byte by byte: a fingerprint of data that a saved file
// must match when it is read back (a scene a state was made from, a state's
// own contents). Not a cryptographic hash: it finds damage and mix-ups, not
// forgery.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

namespace radmesh::internal {

class Fnv1a {
public:
  void add(const void* data, size_t n) {
    const unsigned char* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < n; ++i) h_ = (h_ ^ p[i]) * 1099511628211ull;
  }
  uint64_t value() const { return h_; }
  // 16 hexadecimal digits.
  std::string hex() const {
    char text[17];
    std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(h_));
    return text;
  }

private:
  uint64_t h_ = 1469598103934665603ull;
};

}  // namespace radmesh::internal
