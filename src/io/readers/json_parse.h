// Parsing JSON input with its nesting bounded.
#pragma once

#include "radmesh/errors.h"

#include <nlohmann/json.hpp>

#include <set>
#include <string>
#include <utility>
#include <vector>

namespace radmesh {

// Deeper nesting is refused while parsing, before it is built: a parsed
// value is destroyed and printed recursively, and a file of many thousands
// of '[' would overflow the stack (a segmentation fault instead of an error). No
// scene, glTF or state file nests anywhere near this.
inline constexpr int kMaxJsonDepth = 256;

// nlohmann::json::parse(in), throwing InputError naming `path` past
// kMaxJsonDepth levels and, with `unique_keys`, at a key written twice in
// one object (nlohmann keeps the last value silently: a scene with two
// "materials" would lose the first list); its own parse errors are left to the
// caller.
template <class Input>
nlohmann::json parse_json_bounded(Input&& in, const std::string& path, bool unique_keys = true) {
  std::vector<std::set<std::string>> keys;  // per open object, the keys read so far
  return nlohmann::json::parse(
      std::forward<Input>(in), [&](int depth, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
        if (depth > kMaxJsonDepth)
          throw InputError(path + ": JSON nested more than " + std::to_string(kMaxJsonDepth) + " levels deep");
        if (!unique_keys) return true;
        using Event = nlohmann::json::parse_event_t;
        if (event == Event::object_start) {
          keys.emplace_back();
        } else if (event == Event::object_end) {
          if (!keys.empty()) keys.pop_back();
        } else if (event == Event::key && !keys.empty() && parsed.is_string()) {
          const std::string& k = parsed.get_ref<const std::string&>();
          if (!keys.back().insert(k).second)
            throw InputError(path + ": key '" + k + "' is written twice in one object (at depth " +
                             std::to_string(keys.size()) + "); only one value can stand");
        }
        return true;
      });
}

}  // namespace radmesh
