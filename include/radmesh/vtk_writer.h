// ParaView output: the solved mesh as a VTK XML unstructured grid (.vtu),
// binary and LZ4-compressed.
#pragma once

#include "radmesh/discontinuity.h"
#include "radmesh/mesh.h"
#include "radmesh/scene.h"
#include "radmesh/method.h"
#include "radmesh/run.h"
#include "radmesh/solution.h"

#include <array>
#include <string>
#include <utility>
#include <vector>

namespace radmesh {

// Writes the display mesh (points NodalField::points, triangles
// NodalField::corners, which must have one entry per Mesh triangle) with
//   point data: radiosity (RGB, NodalField::radiosity)
//   cell data:  radiosity (RGB, Solution::element), patch_id, reflectance (RGB),
//               emission (RGB) of the patch's material, area, min_angle, aspect_ratio
// The file is written to `path + ".tmp"` and renamed, so a failure leaves no
// half-written file and an existing file at `path` untouched. Throws IoError
// naming `path` when writing fails or the inputs disagree in size or indices.
void write_vtu(const std::string& path, const Scene& scene, const Mesh& mesh,
               const TriangleQuality& quality, const Solution& solution,
               const std::vector<std::pair<std::string, std::vector<int>>>& int_cell_fields = {});

// The result of radmesh::solve, as the radmesh program writes it.
void write_vtu(const std::string& path, const Result& result);

// A ParaView collection (.pvd) of `files` (names relative to the .pvd), one
// time step each (0, 1, ...), so ParaView steps through them. Atomic; throws IoError.
void write_pvd(const std::string& path, const std::vector<std::string>& files);

// The discontinuity lines as a line dataset (VTK_LINE cells) with cell data
// kind (0 = D0 contact, 1 = D1, 2 = D2), event (0 = contact, 1 = emitter
// vertex - occluder edge, 2 = occluder vertex - emitter edge), emitter (-1
// for contacts), patch_id (the patch the line lies on) and other_patch (the
// patch that causes it: the touching patch or the occluder).
void write_discontinuities_vtu(const std::string& path, const std::vector<DiscontinuitySegment>& segments);

// Line segments with per-segment integer and real fields (cell data, see
// LineSet in radmesh/method.h), as VTK_LINE cells: links of hierarchical
// radiosity. Every field must have one value per segment; real values must be
// finite. Atomic; throws IoError.
void write_lines_vtu(const std::string& path, const LineSet& lines);

// Reads back a mesh written by write_mesh_vtu or write_vtu (points, triangles,
// cell array patch_id) for `radmesh quality MESH.vtu`. Throws IoError naming
// the file and the bad cell when it is not such a mesh.
Mesh read_mesh_vtu(const std::string& path);

// Reads back a line dataset written by write_discontinuities_vtu.
std::vector<DiscontinuitySegment> read_discontinuities_vtu(const std::string& path);

// Mesh only (radmesh mesh): points Mesh::positions, triangles Mesh::triangles,
// cell data patch_id, area, min_angle, aspect_ratio, reflectance, emission.
// Same temporary-file behaviour and errors as write_vtu.
void write_mesh_vtu(const std::string& path, const Scene& scene, const Mesh& mesh,
                    const TriangleQuality& quality);

}  // namespace radmesh
