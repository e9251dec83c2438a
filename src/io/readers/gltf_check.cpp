// A glTF file read and checked before assimp sees it (gltf_check.h).

#include "io/readers/gltf_check.h"

#include "io/readers/json_parse.h"
#include "core/text_syntax.h"
#include "radmesh/errors.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <vector>

namespace radmesh::internal {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

std::string count_of(uint64_t n, const std::string& one, const std::string& many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

std::string index_of(const char* array, uint64_t i) { return std::string(array) + "[" + std::to_string(i) + "]"; }

// The bytes of one buffer: held (a data URI, the BIN chunk) or in a file.
struct Buffer {
  uint64_t length = 0;
  const std::string* held = nullptr;
  std::string decoded;  // a data URI's
  std::string file;     // else
  std::string at(uint64_t offset, uint64_t n) const {
    if (held) return held->substr(offset, n);
    std::ifstream in(file, std::ios::binary);
    in.seekg(static_cast<std::streamoff>(offset));
    std::string out(n, '\0');
    in.read(out.data(), static_cast<std::streamsize>(n));
    return out;
  }
};

std::optional<std::string> base64_decode(std::string_view in) {
  auto value = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
  };
  if (in.size() % 4 != 0) return std::nullopt;
  size_t pad = 0;
  while (pad < 2 && pad < in.size() && in[in.size() - 1 - pad] == '=') ++pad;
  std::string out;
  out.reserve(in.size() / 4 * 3);
  for (size_t i = 0; i < in.size(); i += 4) {
    uint32_t v = 0;
    for (size_t k = 0; k < 4; ++k) {
      const size_t at = i + k;
      const int d = at >= in.size() - pad ? 0 : value(in[at]);
      if (d < 0) return std::nullopt;
      v = v << 6 | static_cast<uint32_t>(d);
    }
    out += static_cast<char>(v >> 16);
    out += static_cast<char>(v >> 8 & 0xFF);
    out += static_cast<char>(v & 0xFF);
  }
  out.resize(out.size() - pad);
  return out;
}

struct Accessor {
  uint64_t count = 0;
  uint64_t component = 0;  // componentType
  std::string type;
  uint64_t element = 0;  // bytes
  uint64_t stride = 0;
  uint64_t offset = 0;  // in its buffer
  uint64_t buffer = 0;
};

class Checker {
public:
  Checker(const std::string& path, const GltfFile& file) : path_(path), file_(file), g_(file.json) {}

  void run() {
    if (!g_.is_object()) throw InputError(path_ + ": the glTF JSON is not an object");
    nodes();
    scenes();
    buffers();
    views();
    accessors();
    meshes();
    triangles();
  }

private:
  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw InputError(path_ + ": " + key + ": " + what);
  }

  // The array at `key` of the document ([] when absent).
  const Json& array(const char* key) const {
    static const Json empty = Json::array();
    if (!g_.contains(key)) return empty;
    if (!g_[key].is_array()) fail(key, "expected an array, got " + dumped(g_[key]));
    return g_[key];
  }

  const Json& object(const Json& v, const std::string& key) const {
    if (!v.is_object()) fail(key, "expected an object, got " + dumped(v));
    return v;
  }

  // A whole number at `name` of `o` (nullopt when absent): assimp's parser
  // skips or defaults one written 1.0 or -1.
  std::optional<uint64_t> whole(const Json& o, const char* name, const std::string& key) const {
    if (!o.contains(name)) return std::nullopt;
    const Json& v = o[name];
    if (!v.is_number_unsigned()) fail(key + "." + name, "expected a whole number >= 0, got " + dumped(v));
    return v.get<uint64_t>();
  }

  uint64_t required(const Json& o, const char* name, const std::string& key) const {
    const auto v = whole(o, name, key);
    if (!v) fail(key, "missing \"" + std::string(name) + "\"");
    return *v;
  }

  // An index into the array `of` (of `size` items), written as a whole number.
  uint64_t index(const Json& v, const std::string& key, const char* of, size_t size) const {
    if (!v.is_number_unsigned())
      fail(key, std::string("expected the index of one of the file's ") + of + " (a whole number), got " + dumped(v));
    const uint64_t i = v.get<uint64_t>();
    const std::string many = of;
    const std::string one = many == "meshes" ? "mesh" : many.substr(0, many.size() - 1);
    if (i >= size) fail(key, std::to_string(i) + " is not one of the file's " + count_of(size, one, many));
    return i;
  }

  void numbers(const Json& node, const char* name, size_t n, const std::string& key) const {
    if (!node.contains(name)) return;
    const Json& v = node[name];
    if (!v.is_array() || v.size() != n || !std::all_of(v.begin(), v.end(), [](const Json& x) { return x.is_number(); }))
      fail(key + "." + name, "expected " + std::to_string(n) + " numbers, got " + dumped(v));
  }

  // ---------------------------------------------------------------- nodes

  void nodes() {
    const Json& ns = array("nodes");
    const size_t n = ns.size();
    if (n > kMaxGltfNodes)
      fail("nodes", count_of(n, "node", "nodes") + "; radmesh reads at most " + std::to_string(kMaxGltfNodes) +
                        " (assimp keeps 2 KB a node)");
    children_.assign(n, {});
    const size_t meshes = array("meshes").size();
    for (size_t i = 0; i < n; ++i) {
      const std::string key = index_of("nodes", i);
      const Json& node = object(ns[i], key);
      if (node.contains("children")) {
        const Json& c = node["children"];
        if (!c.is_array()) fail(key + ".children", "expected an array of node indices, got " + dumped(c));
        for (size_t k = 0; k < c.size(); ++k) children_[i].push_back(index(c[k], key + ".children", "nodes", n));
      }
      if (node.contains("mesh")) index(node["mesh"], key + ".mesh", "meshes", meshes);
      numbers(node, "translation", 3, key);
      numbers(node, "rotation", 4, key);
      numbers(node, "scale", 3, key);
      numbers(node, "matrix", 16, key);
    }
    // A cycle, found by a walk along the children without recursion.
    std::vector<int> state(n, 0);  // 0 unseen, 1 on the walk, 2 done
    for (size_t start = 0; start < n; ++start) {
      if (state[start]) continue;
      std::vector<std::pair<size_t, size_t>> walk = {{start, 0}};
      state[start] = 1;
      while (!walk.empty()) {
        auto& [at, next] = walk.back();
        if (next == children_[at].size()) {
          state[at] = 2;
          walk.pop_back();
          continue;
        }
        const size_t child = static_cast<size_t>(children_[at][next++]);
        if (state[child] == 1)
          fail(index_of("nodes", child), "a cycle in the node tree: it is a child of " +
                                             (child == at ? std::string("itself") : index_of("nodes", at)) +
                                             ", a node below it");
        if (state[child] == 0) {
          state[child] = 1;
          walk.push_back({child, 0});
        }
      }
    }
    parent_.assign(n, -1);
    for (size_t i = 0; i < n; ++i)
      for (const uint64_t c : children_[i]) {
        if (parent_[c] >= 0)
          fail(index_of("nodes", c), "a child of both " + index_of("nodes", static_cast<uint64_t>(parent_[c])) +
                                         " and " + index_of("nodes", i) +
                                         "; a glTF node has one parent (assimp would read it twice)");
        parent_[c] = static_cast<int64_t>(i);
      }
    // Levels, from the roots down, without recursion.
    std::vector<size_t> level;
    for (size_t i = 0; i < n; ++i)
      if (parent_[i] < 0) level.push_back(i);
    for (int depth = 1; !level.empty(); ++depth) {
      if (depth > kMaxGltfNodeDepth)
        fail(index_of("nodes", level.front()),
             "at level " + std::to_string(depth) + " of the node tree; radmesh reads node trees of at most " +
                 std::to_string(kMaxGltfNodeDepth) + " levels (assimp's importer recurses once a level)");
      std::vector<size_t> below;
      for (const size_t i : level)
        for (const uint64_t c : children_[i]) below.push_back(static_cast<size_t>(c));
      level.swap(below);
    }
  }

  void scenes() {
    const Json& ss = array("scenes");
    const size_t n = children_.size();
    std::vector<size_t> seen_in(n, SIZE_MAX);  // the last scene that listed each node
    for (size_t s = 0; s < ss.size(); ++s) {
      const std::string key = index_of("scenes", s);
      const Json& scene = object(ss[s], key);
      if (!scene.contains("nodes")) continue;
      const Json& roots = scene["nodes"];
      if (!roots.is_array()) fail(key + ".nodes", "expected an array of node indices, got " + dumped(roots));
      for (const Json& r : roots) {
        const uint64_t i = index(r, key + ".nodes", "nodes", n);
        if (parent_[i] >= 0)
          fail(key + ".nodes", index_of("nodes", i) + " is a child of " +
                                   index_of("nodes", static_cast<uint64_t>(parent_[i])) +
                                   ", not a root (assimp would read it twice)");
        if (seen_in[i] == s) fail(key + ".nodes", index_of("nodes", i) + " is listed twice");
        seen_in[i] = s;
      }
    }
    if (g_.contains("scene")) scene_ = index(g_["scene"], "scene", "scenes", ss.size());
  }

  // ---------------------------------------------------------------- data

  void buffers() {
    const Json& bs = array("buffers");
    const fs::path dir = fs::path(path_).parent_path();
    buffers_.resize(bs.size());
    for (size_t i = 0; i < bs.size(); ++i) {
      const std::string key = index_of("buffers", i);
      const Json& b = object(bs[i], key);
      Buffer& buffer = buffers_[i];
      buffer.length = required(b, "byteLength", key);
      if (buffer.length == 0) fail(key + ".byteLength", "0: a buffer holds at least one byte");
      if (!b.contains("uri")) {
        if (!file_.binary || i != 0) fail(key, "no \"uri\": the buffer has no data");
        if (!file_.has_bin) fail(key, "no \"uri\", and the .glb has no BIN chunk");
        if (file_.bin.size() < buffer.length)
          fail(key, "byteLength " + std::to_string(buffer.length) + ", but the .glb's BIN chunk holds " +
                        std::to_string(file_.bin.size()) + " bytes");
        if (file_.bin.size() > buffer.length + 3)
          fail(key, "byteLength " + std::to_string(buffer.length) + ", but the .glb's BIN chunk holds " +
                        std::to_string(file_.bin.size()) + " bytes (at most 3 of padding may follow)");
        buffer.held = &file_.bin;
        continue;
      }
      if (!b["uri"].is_string()) fail(key + ".uri", "expected a string, got " + dumped(b["uri"]));
      const std::string uri = b["uri"].get<std::string>();
      if (uri.rfind("data:", 0) == 0) {
        const size_t comma = uri.find(',');
        if (comma == std::string::npos || comma < 12 || comma > 100 || uri.compare(comma - 7, 7, ";base64") != 0)
          fail(key + ".uri", "a data URI '" + shown(uri.substr(0, std::min(comma, size_t{60}))) +
                                 "...' that is not 'data:<media type>;base64,...'; radmesh reads base64 data URIs");
        const auto data = base64_decode(std::string_view(uri).substr(comma + 1));
        if (!data) fail(key + ".uri", "its base64 data is not valid base64");
        if (data->size() != buffer.length)
          fail(key, "byteLength " + std::to_string(buffer.length) + ", but its data URI holds " +
                        std::to_string(data->size()) + " bytes");
        buffer.decoded = std::move(*data);
        buffer.held = &buffer.decoded;
        continue;
      }
      const fs::path file = dir / uri;
      std::error_code ec;
      if (!fs::is_regular_file(file, ec))
        fail(key + ".uri", "'" + shown(uri) + "' is not a file radmesh can read (looked for " + file.string() + ")");
      const auto size = fs::file_size(file, ec);
      if (ec || size < buffer.length)
        fail(key, "byteLength " + std::to_string(buffer.length) + ", but its file '" + shown(uri) + "' has " +
                      std::to_string(ec ? 0 : size) + " bytes");
      buffer.file = file.string();
    }
  }

  void views() {
    const Json& vs = array("bufferViews");
    for (size_t i = 0; i < vs.size(); ++i) {
      const std::string key = index_of("bufferViews", i);
      const Json& v = object(vs[i], key);
      if (!v.contains("buffer")) fail(key, "missing \"buffer\"");
      View view;
      view.buffer = index(v["buffer"], key + ".buffer", "buffers", buffers_.size());
      view.offset = whole(v, "byteOffset", key).value_or(0);
      view.length = required(v, "byteLength", key);
      view.stride = whole(v, "byteStride", key).value_or(0);  // 0: elements packed (as absent, to assimp)
      const uint64_t end = view.offset + view.length, have = buffers_[view.buffer].length;
      if (view.length == 0 || end < view.offset || end > have)
        fail(key, "byteOffset " + std::to_string(view.offset) + " and byteLength " + std::to_string(view.length) +
                      " reach byte " + std::to_string(end) + " of " + index_of("buffers", view.buffer) +
                      ", which has " + std::to_string(have));
      views_.push_back(view);
    }
  }

  void accessors() {
    static const std::map<uint64_t, uint64_t> component_bytes = {{5120, 1}, {5121, 1}, {5122, 2},
                                                                   {5123, 2}, {5125, 4}, {5126, 4}};
    static const std::map<std::string, uint64_t> components = {{"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4},
                                                               {"MAT2", 4},   {"MAT3", 9}, {"MAT4", 16}};
    const Json& as = array("accessors");
    for (size_t i = 0; i < as.size(); ++i) {
      const std::string key = index_of("accessors", i);
      const Json& a = object(as[i], key);
      Accessor acc;
      acc.count = required(a, "count", key);
      if (acc.count == 0) fail(key + ".count", "0: an accessor holds at least one element");
      if (!a.contains("bufferView"))
        fail(key, std::to_string(acc.count) +
                      " elements without a bufferView (zeros, or a sparse accessor): radmesh reads accessors whose "
                      "elements a bufferView holds, not sparse ones (assimp allocates what the count says)");
      if (a.contains("sparse")) fail(key + ".sparse", "radmesh does not read sparse accessors");
      acc.component = required(a, "componentType", key);
      const auto bytes = component_bytes.find(acc.component);
      if (bytes == component_bytes.end()) fail(key + ".componentType", std::to_string(acc.component) + " is not a glTF component type");
      if (!a.contains("type") || !a["type"].is_string() || !components.count(a["type"].get<std::string>()))
        fail(key + ".type", "expected SCALAR, VEC2, VEC3, VEC4, MAT2, MAT3 or MAT4, got " +
                                dumped(a.value("type", Json())));
      acc.type = a["type"].get<std::string>();
      acc.element = bytes->second * components.at(acc.type);
      const uint64_t v = index(a["bufferView"], key + ".bufferView", "bufferViews", views_.size());
      const View& view = views_[v];
      const uint64_t offset = whole(a, "byteOffset", key).value_or(0);
      if (view.stride != 0 && view.stride < acc.element)
        fail(index_of("bufferViews", v), "byteStride " + std::to_string(view.stride) + " is shorter than the " +
                                             std::to_string(acc.element) + "-byte elements of " + key + " (" +
                                             acc.type + " of componentType " + std::to_string(acc.component) +
                                             "): they would overlap");
      acc.stride = view.stride ? view.stride : acc.element;
      // The last element's end, in doubles: a count near 2^64 must not wrap.
      const double end = static_cast<double>(offset) + static_cast<double>(acc.stride) * static_cast<double>(acc.count - 1) +
                         static_cast<double>(acc.element);
      // assimp reads count * stride bytes from the view's start.
      const double read = static_cast<double>(acc.count) * static_cast<double>(acc.stride);
      if (end > static_cast<double>(view.length) || read > static_cast<double>(view.length))
        fail(key, "byteOffset " + std::to_string(offset) + " and " + count_of(acc.count, "element", "elements") +
                      " of " + std::to_string(acc.element) + " bytes (stride " + std::to_string(acc.stride) +
                      ") reach byte " + format_number(std::max(end, read)) + " of " + index_of("bufferViews", v) +
                      ", which has " + std::to_string(view.length));
      acc.offset = view.offset + offset;
      acc.buffer = view.buffer;
      accessors_.push_back(acc);
    }
  }

  // ---------------------------------------------------------------- meshes

  void meshes() {
    const Json& ms = array("meshes");
    const size_t materials = array("materials").size();
    triangles_.assign(ms.size(), 0.0);
    for (size_t m = 0; m < ms.size(); ++m) {
      const std::string mkey = index_of("meshes", m);
      const Json& mesh = object(ms[m], mkey);
      if (!mesh.contains("primitives") || !mesh["primitives"].is_array() || mesh["primitives"].empty())
        fail(mkey + ".primitives", "expected a non-empty array of primitives");
      const Json& ps = mesh["primitives"];
      for (size_t p = 0; p < ps.size(); ++p) {
        const std::string key = mkey + ".primitives[" + std::to_string(p) + "]";
        const Json& prim = object(ps[p], key);
        const uint64_t mode = whole(prim, "mode", key).value_or(4);
        if (mode < 4 || mode > 6)
          fail(key + ".mode", std::to_string(mode) + (mode < 4 ? " (points or lines)" : "") +
                                  ": radmesh reads surfaces: triangles (4), a strip (5) or a fan (6)");
        if (prim.contains("material")) index(prim["material"], key + ".material", "materials", materials);
        if (!prim.contains("attributes") || !prim["attributes"].is_object() || !prim["attributes"].contains("POSITION"))
          fail(key + ".attributes", "no POSITION: the primitive has no vertices");
        for (auto it = prim["attributes"].begin(); it != prim["attributes"].end(); ++it)
          index(it.value(), key + ".attributes." + it.key(), "accessors", accessors_.size());
        const uint64_t pa = prim["attributes"]["POSITION"].get<uint64_t>();
        const Accessor& pos = accessors_[pa];
        if (pos.type != "VEC3" || pos.component != 5126)
          fail(index_of("accessors", pa), "the POSITION of " + key + " is " + pos.type + " of componentType " +
                                              std::to_string(pos.component) +
                                              "; radmesh reads positions as VEC3 of float (5126)");
        uint64_t count = pos.count;
        std::string counted = index_of("accessors", pa);
        if (prim.contains("indices")) {
          const uint64_t ia = index(prim["indices"], key + ".indices", "accessors", accessors_.size());
          indices(ia, key, pos.count);
          count = accessors_[ia].count;
          counted = index_of("accessors", ia);
        }
        if (mode == 4 && count % 3 != 0)
          fail(counted, (prim.contains("indices") ? count_of(count, "index", "indices")
                                                  : count_of(count, "vertex", "vertices") + " without indices") +
                            " for the triangles of " + key + ", not a multiple of 3 (assimp would drop the last " +
                            std::to_string(count % 3) + ")");
        if (count < 3) fail(counted, count_of(count, "vertex", "vertices") + " for the triangles of " + key);
        triangles_[m] += mode == 4 ? static_cast<double>(count / 3) : static_cast<double>(count - 2);
      }
    }
  }

  // The index accessor `ia` of primitive `key`, of `vertices` vertices:
  // unsigned whole scalars, each a vertex (assimp drops a triangle with
  // one out of range).
  void indices(uint64_t ia, const std::string& key, uint64_t vertices) {
    const std::string akey = index_of("accessors", ia);
    const Accessor& acc = accessors_[ia];
    if (acc.type != "SCALAR" || (acc.component != 5121 && acc.component != 5123 && acc.component != 5125))
      fail(akey, "the indices of " + key + " are " + acc.type + " of componentType " + std::to_string(acc.component) +
                     "; indices are SCALAR of unsigned byte, short or int (5121, 5123, 5125)");
    if (checked_.count({ia, vertices})) return;
    checked_.insert({ia, vertices});
    const uint64_t size = acc.element;
    const std::string bytes = buffers_[acc.buffer].at(acc.offset, acc.stride * (acc.count - 1) + size);
    for (uint64_t k = 0; k < acc.count; ++k) {
      uint64_t v = 0;
      std::memcpy(&v, bytes.data() + k * acc.stride, size);  // little-endian, as glTF
      if (v >= vertices)
        fail(akey, "index " + std::to_string(v) + " (at " + std::to_string(k) + ") is out of range: " + key +
                       " has " + count_of(vertices, "vertex", "vertices") + " (assimp would drop its triangle)");
    }
  }

  // The triangles of the default scene, every instance counted.
  void triangles() const {
    const Json& ss = array("scenes");
    if (ss.empty() || scene_ >= ss.size() || !ss[scene_].contains("nodes")) return;
    const Json& ns = array("nodes");
    double total = 0.0;
    std::vector<size_t> todo;
    for (const Json& r : ss[scene_]["nodes"]) todo.push_back(r.get<size_t>());
    while (!todo.empty()) {
      const size_t i = todo.back();
      todo.pop_back();
      if (ns[i].contains("mesh")) total += triangles_[ns[i]["mesh"].get<size_t>()];
      for (const uint64_t c : children_[i]) todo.push_back(static_cast<size_t>(c));
    }
    if (total > kMaxGltfTriangles)
      fail(index_of("scenes", scene_), format_number(total) + " triangles, every instance of a mesh counted; " +
                                           "radmesh reads at most " + format_number(kMaxGltfTriangles));
  }

  struct View {
    uint64_t buffer = 0, offset = 0, length = 0, stride = 0;
  };

  const std::string& path_;
  const GltfFile& file_;
  const Json& g_;
  std::vector<std::vector<uint64_t>> children_;
  std::vector<int64_t> parent_;
  size_t scene_ = 0;
  std::vector<Buffer> buffers_;
  std::vector<View> views_;
  std::vector<Accessor> accessors_;
  std::vector<double> triangles_;  // per mesh
  std::set<std::pair<uint64_t, uint64_t>> checked_;
};

uint32_t word(const std::string& bytes, size_t at) {
  uint32_t w = 0;
  std::memcpy(&w, bytes.data() + at, 4);
  return w;
}

}  // namespace

GltfFile read_gltf_file(const std::string& path, bool binary) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open for reading");
  GltfFile out;
  out.binary = binary;
  std::string text;
  if (binary) {
    std::error_code ec;
    const auto size = static_cast<double>(fs::file_size(path, ec));
    char header[20];
    if (!in.read(header, 20)) throw InputError(path + ": too short for a .glb file");
    uint32_t magic, version, length, json_length, type;
    std::memcpy(&magic, header, 4);
    std::memcpy(&version, header + 4, 4);
    std::memcpy(&length, header + 8, 4);
    std::memcpy(&json_length, header + 12, 4);
    std::memcpy(&type, header + 16, 4);
    if (magic != 0x46546C67u || type != 0x4E4F534Au)
      throw InputError(path + ": not a binary glTF file (no 'glTF' header and JSON chunk)");
    if (version != 2) throw InputError(path + ": binary glTF version " + std::to_string(version) + "; radmesh reads 2");
    if (ec || 20.0 + json_length > size)  // not an allocation the header alone decides
      throw InputError(path + ": JSON chunk of a stated " + std::to_string(json_length) +
                       " bytes, longer than the file");
    if (length > size)
      throw InputError(path + ": its header declares " + std::to_string(length) + " bytes, the file has " +
                       format_number(size) + " (truncated)");
    if (length < size)
      throw InputError(path + ": " + format_number(size - length) + " bytes after the " + std::to_string(length) +
                       " bytes its header declares");
    text.resize(json_length);
    if (!in.read(text.data(), static_cast<std::streamsize>(json_length)))
      throw InputError(path + ": JSON chunk shorter than its stated " + std::to_string(json_length) + " bytes");
    // The chunks after the JSON, as assimp finds them (after the JSON's
    // padding to 4 bytes): the first must be the BIN chunk, and each lies
    // within the declared length.
    double at = 20.0 + static_cast<double>((json_length + 3u) & ~3u);
    for (int chunk = 1; at < length; ++chunk) {
      if (at + 8.0 > length)
        throw InputError(path + ": " + format_number(length - at) + " bytes after the JSON chunk, too few for a chunk");
      std::string head = std::string(8, '\0');
      in.seekg(static_cast<std::streamoff>(at));
      in.read(head.data(), 8);
      const uint32_t chunk_length = word(head, 0), chunk_type = word(head, 4);
      if (at + 8.0 + chunk_length > length)
        throw InputError(path + ": chunk " + std::to_string(chunk) + " of a stated " +
                         std::to_string(chunk_length) + " bytes reaches past the file's " + std::to_string(length));
      if (chunk == 1) {
        if (chunk_type != 0x004E4942u)
          throw InputError(path + ": the chunk after the JSON is not a BIN chunk (assimp reads no other)");
        out.has_bin = true;
        out.bin.resize(chunk_length);
        in.read(out.bin.data(), static_cast<std::streamsize>(chunk_length));
      }
      at += 8.0 + chunk_length;
    }
  } else {
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  try {
    // A key written twice: assimp's JSON parser takes the first, nlohmann's the last.
    out.json = parse_json_bounded(text, path, /*unique_keys=*/true);
  } catch (const nlohmann::json::exception& e) {
    std::string m = e.what();
    const size_t close = m.find("] ");
    throw InputError(path + ": " + (close == std::string::npos ? m : m.substr(close + 2)));
  }
  return out;
}

void check_gltf(const std::string& path, const GltfFile& file) { Checker(path, file).run(); }

}  // namespace radmesh::internal
