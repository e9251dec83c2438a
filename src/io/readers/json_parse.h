// Parsing JSON input with its nesting bounded.
#pragma once

#include "radmesh/errors.h"

#include <nlohmann/json.hpp>

#include <cstddef>
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

namespace internal {

// A JSON value as a message shows it: its text, cut at 60 characters.
template <class Json>
std::string dumped(const Json& v) {
  std::string s = v.dump();
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  return s;
}

// nlohmann's DOM builder, with the nesting counted and (with unique_keys)
// the keys of each open object. Not nlohmann's parse callback: its
// parser scans an array's elements at the end of each object in it, so
// that an array of 100,000 objects (a glTF's nodes) took 2 s to parse and
// one of a million hours.
class BoundedJsonBuilder : public nlohmann::detail::json_sax_dom_parser<nlohmann::json> {
public:
  using Base = nlohmann::detail::json_sax_dom_parser<nlohmann::json>;
  BoundedJsonBuilder(nlohmann::json& root, const std::string& path, bool unique_keys)
      : Base(root, /*allow_exceptions=*/true), path_(path), unique_keys_(unique_keys) {}

  bool start_object(std::size_t n) {
    enter();
    if (unique_keys_) keys_.emplace_back();
    return Base::start_object(n);
  }
  bool end_object() {
    --depth_;
    if (unique_keys_) keys_.pop_back();
    return Base::end_object();
  }
  bool start_array(std::size_t n) {
    enter();
    return Base::start_array(n);
  }
  bool end_array() {
    --depth_;
    return Base::end_array();
  }
  bool key(nlohmann::json::string_t& k) {
    if (unique_keys_ && !keys_.back().insert(k).second)
      throw InputError(path_ + ": key '" + k + "' is written twice in one object (at depth " +
                       std::to_string(keys_.size()) + "); only one value can stand");
    return Base::key(k);
  }

private:
  void enter() {
    if (++depth_ > kMaxJsonDepth)
      throw InputError(path_ + ": JSON nested more than " + std::to_string(kMaxJsonDepth) + " levels deep");
  }

  const std::string& path_;
  bool unique_keys_;
  int depth_ = 0;
  std::vector<std::set<std::string>> keys_;  // per open object, the keys read so far
};

}  // namespace internal

// nlohmann::json::parse(in), throwing InputError naming `path` past
// kMaxJsonDepth levels and, with `unique_keys`, at a key written twice in
// one object (nlohmann keeps the last value silently: a scene with two
// "materials" would lose the first list); its own parse errors are left to the
// caller. Linear in the input.
template <class Input>
nlohmann::json parse_json_bounded(Input&& in, const std::string& path, bool unique_keys = true) {
  nlohmann::json root;
  internal::BoundedJsonBuilder builder(root, path, unique_keys);
  nlohmann::json::sax_parse(std::forward<Input>(in), &builder);
  return root;
}

}  // namespace radmesh
