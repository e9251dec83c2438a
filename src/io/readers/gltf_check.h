// Internal to radmesh_io: a glTF 2.0 file (.gltf or .glb) read and checked
// before assimp sees it. assimp's importer recurses once per level of the
// node tree (20,000 levels overflowed the stack), keeps 2 KB a node (a
// million nodes, 12 MB of JSON, took 2 GB), reads a node with two parents twice,
// drops a triangle with an index out of range and the indices short of a
// triangle, reads a stride shorter than its element or an accessor past
// its view as other bytes, skips an index written 1.0, and allocates what
// a sparse accessor's count says. So radmesh checks the JSON's node tree,
// scenes, meshes, accessors, views and buffers itself (reading the index
// data), and refuses the file, naming the key and the value, unless assimp
// will read exactly what it holds.
#pragma once

#include <nlohmann/json.hpp>

#include <string>

namespace radmesh::internal {

// The most nodes a glTF file may hold, and the most levels its node tree
// may have (a root node is level 1).
inline constexpr size_t kMaxGltfNodes = 100000;
inline constexpr int kMaxGltfNodeDepth = 256;
// The most triangles the default scene may hold, every instance of a mesh
// counted (a node tree of 1000 nodes each placing one mesh of 10^6
// triangles would be 10^9 faces from a small file).
inline constexpr double kMaxGltfTriangles = 1e7;

struct GltfFile {
  nlohmann::json json;  // the .gltf itself, or the JSON chunk of a .glb
  bool binary = false;
  bool has_bin = false;
  std::string bin;  // the .glb's BIN chunk
};

// Reads the file: the JSON (nesting bounded, a key written twice in one
// object refused, since assimp's parser takes the first and nlohmann's
// the last), and a .glb's chunks, whose lengths must lie within the file,
// which may hold nothing past the length its header declares. Throws
// InputError (IoError when it cannot be opened).
GltfFile read_gltf_file(const std::string& path, bool binary);

// Checks the file's node tree (at most kMaxGltfNodes nodes and
// kMaxGltfNodeDepth levels, each node the child of at most one node, no
// cycle, children and scene roots indices of nodes), its scenes, meshes
// (triangles only; POSITION of float VEC3; index values within the
// primitive's vertices and a whole number of triangles), accessors (a
// bufferView each, within it, strides no shorter than an element), buffer
// views (within their buffers) and buffers (their data there: a base64
// data URI, a file, or the .glb's BIN chunk). Throws InputError naming
// `path`, the key and the value.
void check_gltf(const std::string& path, const GltfFile& file);

}  // namespace radmesh::internal
