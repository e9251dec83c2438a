// OBJ + MTL scene reader (tinyobjloader).
#pragma once

#include "radmesh/scene.h"

#include <string>

namespace radmesh {

// Reads an OBJ file and its MTL library: Kd is the reflectance, Ke the emission
// (radiant exitance). Every face is a patch named after its o/g; polygons of
// any vertex count. Throws InputError (file:line and value) or IoError.
Scene read_obj_scene(const std::string& path, const SceneOptions& options = {});

}  // namespace radmesh
