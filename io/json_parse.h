// Parsing JSON input with its nesting bounded.
#pragma once

#include "meshing/errors.h"

#include <nlohmann/json.hpp>

#include <string>
#include <utility>

namespace radmesh {

// Deeper nesting is refused while parsing, before it is built: a parsed
// value is destroyed and printed recursively, and a file of 100,000 '['
// overflowed the stack (a segmentation fault instead of an error). No
// scene, glTF or state file nests anywhere near this.
inline constexpr int kMaxJsonDepth = 256;

// nlohmann::json::parse(in), throwing InputError naming `path` past
// kMaxJsonDepth levels; its own parse errors are left to the caller.
template <class Input>
nlohmann::json parse_json_bounded(Input&& in, const std::string& path) {
  return nlohmann::json::parse(std::forward<Input>(in),
                               [&path](int depth, nlohmann::json::parse_event_t, nlohmann::json&) {
                                 if (depth > kMaxJsonDepth)
                                   throw InputError(path + ": JSON nested more than " + std::to_string(kMaxJsonDepth) +
                                                    " levels deep");
                                 return true;
                               });
}

}  // namespace radmesh
