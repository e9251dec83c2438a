// libFuzzer target: glTF node trees. The input describes a node graph (a
// chain as deep as 600 levels, a fan of up to 1000 nodes or past the node
// bound, a k-ary tree, or explicit edges: cycles, a child of two parents, a
// child index out of range or written 1.0, roots that are children, a
// default scene out of range), written as a glTF whose nodes may place one
// mesh, a square of 2 triangles. The reader must refuse the file with a
// radmesh error exactly when the graph is not a forest within the bounds
// (gltf_check.h), and otherwise read 2 faces per instance of the mesh in
// the default scene: a tree refused, a broken one read, or a wrong face
// count is a defect.

#include "fuzz/fuzz_util.h"
#include "io/readers/gltf_check.h"
#include "io/readers/scene_sources.h"

#include <algorithm>
#include <string>
#include <vector>

namespace {

struct Graph {
  size_t nodes = 0;
  std::vector<std::vector<size_t>> children;  // an index >= nodes is out of range
  std::vector<bool> mesh;
  std::vector<size_t> roots;
  size_t scene = 0;          // the default scene (1: out of range)
  bool fraction = false;     // one child written 1.0
};

class Bytes {
public:
  Bytes(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  unsigned next() { return at_ < size_ ? data_[at_++] : 0u; }
  bool more() const { return at_ < size_; }

private:
  const uint8_t* data_;
  size_t size_, at_ = 0;
};

Graph graph_of(Bytes& in) {
  Graph g;
  const unsigned shape = in.next() % 4;
  if (shape == 0) {  // explicit edges: (parent, child, flags) triples
    g.nodes = 1 + in.next() % 40;
    g.children.assign(g.nodes, {});
    g.mesh.assign(g.nodes, false);
    while (in.more()) {
      const size_t parent = in.next() % g.nodes, child = in.next() % (g.nodes + 1);
      const unsigned flags = in.next();
      if (flags & 1) g.mesh[parent] = true;
      if (flags & 2) g.roots.push_back(child);
      if (flags & 4) g.children[parent].push_back(child);
      if (flags & 8) g.mesh[child % g.nodes] = true;
      if ((flags & 0xF0) == 0xF0) g.fraction = true;
      if ((flags & 0xF0) == 0xE0) g.scene = 1;
    }
    if (g.roots.empty()) g.roots.push_back(0);
    return g;
  }
  if (shape == 1) {  // a chain, the last node placing the mesh, maybe closed into a cycle
    const unsigned a = in.next(), b = in.next(), c = in.next();
    g.nodes = 1 + (a | b << 8) % 600;
    g.children.assign(g.nodes, {});
    g.mesh.assign(g.nodes, false);
    for (size_t i = 0; i + 1 < g.nodes; ++i) g.children[i].push_back(i + 1);
    g.mesh[g.nodes - 1] = true;
    if (c & 1) g.children[g.nodes - 1].push_back(in.next() % g.nodes);
    g.roots = {0};
    return g;
  }
  if (shape == 2) {  // a fan under node 0: small, or (rarely: it takes 0.7 s) past the node bound
    const unsigned a = in.next(), b = in.next(), c = in.next();
    g.nodes = c == 0xFF ? radmesh::internal::kMaxGltfNodes + 1 + a : 1 + (a | b << 8) % 1000;
    g.children.assign(g.nodes, {});
    g.mesh.assign(g.nodes, false);
    for (size_t i = 1; i < g.nodes; ++i) g.children[0].push_back(i);
    for (size_t i = 0; i < g.nodes; i += 1 + c % 7) g.mesh[i] = true;
    g.roots = {0};
    return g;
  }
  // A k-ary tree of some depth, capped at 1000 nodes; its leaves place the mesh.
  const size_t k = 1 + in.next() % 6, depth = 1 + in.next() % 12;
  g.children.push_back({});
  std::vector<size_t> level = {0};
  for (size_t d = 1; d < depth && g.children.size() < 1000; ++d) {
    std::vector<size_t> below;
    for (const size_t p : level)
      for (size_t j = 0; j < k && g.children.size() < 1000; ++j) {
        g.children[p].push_back(g.children.size());
        below.push_back(g.children.size());
        g.children.push_back({});
      }
    level.swap(below);
  }
  g.nodes = g.children.size();
  g.mesh.assign(g.nodes, false);
  for (size_t i = 0; i < g.nodes; ++i) g.mesh[i] = g.children[i].empty();
  g.roots = {0};
  return g;
}

// The faces the reader must give (2 per mesh instance in the default
// scene), or -1 when it must refuse the file.
long expected_faces(const Graph& g) {
  if (g.nodes > radmesh::internal::kMaxGltfNodes || g.fraction || g.scene != 0) return -1;
  std::vector<long> parent(g.nodes, -1);
  for (size_t p = 0; p < g.nodes; ++p)
    for (const size_t c : g.children[p]) {
      if (c >= g.nodes || parent[c] >= 0) return -1;  // out of range, or a second parent
      parent[c] = static_cast<long>(p);
    }
  // With one parent each, a cycle is a node whose parents never reach a root.
  std::vector<int> depth(g.nodes, 0);
  for (size_t i = 0; i < g.nodes; ++i) {
    int d = 1;
    for (long at = parent[i]; at >= 0; at = parent[static_cast<size_t>(at)])
      if (static_cast<size_t>(++d) > g.nodes) return -1;
    depth[i] = d;
  }
  if (*std::max_element(depth.begin(), depth.end()) > radmesh::internal::kMaxGltfNodeDepth) return -1;
  std::vector<bool> root(g.nodes, false);
  for (const size_t r : g.roots) {
    if (r >= g.nodes || parent[r] >= 0 || root[r]) return -1;
    root[r] = true;
  }
  long faces = 0;
  std::vector<size_t> todo(g.roots.begin(), g.roots.end());
  while (!todo.empty()) {
    const size_t i = todo.back();
    todo.pop_back();
    if (g.mesh[i]) faces += 2;
    todo.insert(todo.end(), g.children[i].begin(), g.children[i].end());
  }
  return faces == 0 ? -1 : faces;  // no faces: refused
}

std::string gltf_of(const Graph& g) {
  std::string nodes;
  for (size_t i = 0; i < g.nodes; ++i) {
    std::string node;
    if (g.mesh[i]) node = "\"mesh\": 0";
    if (!g.children[i].empty()) {
      node += std::string(node.empty() ? "" : ", ") + "\"children\": [";
      for (size_t k = 0; k < g.children[i].size(); ++k)
        node += (k ? ", " : "") + std::to_string(g.children[i][k]) + (g.fraction && i == 0 && k == 0 ? ".0" : "");
      node += "]";
    }
    nodes += (i ? ",\n" : "") + ("{" + node + "}");
  }
  if (g.fraction && (g.children.empty() || g.children[0].empty())) nodes += ", {\"children\": [0.0]}";
  std::string roots;
  for (size_t k = 0; k < g.roots.size(); ++k) roots += (k ? ", " : "") + std::to_string(g.roots[k]);
  return "{\"asset\": {\"version\": \"2.0\"}, \"scene\": " + std::to_string(g.scene) +
         ", \"scenes\": [{\"nodes\": [" + roots + "]}],\n"
         "\"buffers\": [{\"byteLength\": 72, \"uri\": \"data:application/octet-stream;base64,"
         "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAACAPwAAgD8AAAAAAAAAAAEAAAACAAAAAQAAAAMAAAACAAAA\"}],\n"
         "\"bufferViews\": [{\"buffer\": 0, \"byteLength\": 48}, {\"buffer\": 0, \"byteOffset\": 48, "
         "\"byteLength\": 24}],\n"
         "\"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC3\"}, "
         "{\"bufferView\": 1, \"componentType\": 5125, \"count\": 6, \"type\": \"SCALAR\"}],\n"
         "\"materials\": [{\"name\": \"grey\", \"pbrMetallicRoughness\": {\"baseColorFactor\": [0.5, 0.5, 0.5, 1]}}],\n"
         "\"meshes\": [{\"name\": \"square\", \"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1, "
         "\"material\": 0}]}],\n\"nodes\": [" + nodes + "]}\n";
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace radmesh;
  Bytes in(data, size);
  const Graph g = graph_of(in);
  const long want = expected_faces(g);
  const std::string path = fuzz::write_file("nodes.gltf", gltf_of(g));
  long got = -1;
  std::string refusal;
  try {
    got = static_cast<long>(internal::read_assimp_source(path, true).faces.size());
  } catch (const Error& e) {
    refusal = e.what();
  }
  if (want < 0 && got >= 0) fuzz::defect("a node graph that is not a forest within the bounds was read: " +
                                         std::to_string(got) + " faces");
  if (want >= 0 && got != want)
    fuzz::defect("a valid node tree gave " + (got < 0 ? "an error: " + refusal : std::to_string(got) + " faces") +
                 "; expected " + std::to_string(want) + " faces");
  return 0;
}
