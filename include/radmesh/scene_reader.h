// Reads a scene from any supported file, chosen by its extension (case-insensitive).
#pragma once

#include "radmesh/scene.h"

#include <string>

namespace radmesh {

// .obj (+ .mtl)  OBJ with its MTL libraries: read_obj_scene (obj_reader.h).
// .ply .stl .off  meshes without materials (through assimp): they need a JSON
//                 scene that names one; read directly they give an InputError
//                 saying so.
// .gltf .glb      glTF 2.0 (through assimp): baseColorFactor (rgb) is the
//                 reflectance, emissiveFactor times KHR_materials_emissive_strength
//                 the emission; node transforms applied.
// .mgf            MGF 2.0 (Greg Ward's Materials and Geometry Format): rd and
//                 ed (lux, divided by 179 lm/W) with their colours as RGB in
//                 Radiance's primaries; includes, transforms and arrays
//                 applied; curved primitives cut into planar faces within
//                 options.curve_tolerance (docs/scenes.md, "MGF").
// .json           a scene file placing meshes and assigning materials:
//   {"materials": {"white": {"reflectance": [0.5, 0.5, 0.5]},
//                  "lamp":  {"reflectance": [0, 0, 0], "emission": [10, 10, 10]}},
//    "objects": [{"file": "room.obj"},
//                {"file": "bunny.ply", "material": "white",
//                 "transform": {"scale": 0.5, "rotate_deg": [0, 90, 0],
//                               "translate": [0.5, 0, 0.5]}}]}
//   Paths are relative to the JSON file. `scale` is a number or [sx, sy, sz];
//   points are scaled, rotated about x, then y, then z (degrees, right-handed),
//   then translated; a transform that mirrors (odd number of negative scales)
//   reverses each face's vertex order so that faces keep facing the same side
//   of the surface. An object with `material` uses it for every face; one
//   without keeps the materials its file carries, and a file that carries none
//   (PLY, STL, OFF, an OBJ face without usemtl, a glTF mesh without material)
//   must be given one. Materials are merged by name; one name with different
//   values is an error.
// Every face of the input is one patch, validated, welded and split as
// build_scene (scene.h) describes. Errors name the file and the line,
// key or element: InputError for bad content, IoError for missing files.
Scene read_scene(const std::string& path, const SceneOptions& options = {});

}  // namespace radmesh
