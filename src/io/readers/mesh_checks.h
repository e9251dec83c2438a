// Internal to radmesh_io: the checks a PLY, OFF or STL file passes before
// assimp reads it. assimp's readers allocate what a count declares before
// reading the body, drop what follows the declared data, skip what they do
// not know, and read numbers their own way (a run of 24 digits as 0, "1,5"
// as 1.5); so radmesh reads each file once itself, in the syntax of
// text_syntax.h, and refuses it, naming the line or element and the value,
// unless assimp will read exactly what it holds.
#pragma once

#include <string>

namespace radmesh::internal {

// Each throws InputError naming `path`; none allocates more than the file
// holds.
void check_ply(const std::string& path);
void check_off(const std::string& path);
void check_stl(const std::string& path);

}  // namespace radmesh::internal
