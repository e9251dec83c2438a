// Lines where radiosity is discontinuous, known from the geometry alone:
// contacts (D0), where a patch touches or passes through another, and the
// shadow boundaries an emitter polygon casts past an occluder (D1/D2).
#pragma once

#include "radmesh/geometry.h"
#include "radmesh/scene.h"

#include <string>
#include <vector>

namespace radmesh {

enum class DiscontinuityMode { off, contacts, full };

// "off" | "contacts" | "full"; throws InputError naming the value otherwise.
DiscontinuityMode parse_discontinuity_mode(const std::string& text);
const char* to_string(DiscontinuityMode mode);

// How a shadow line is made (the critical surface that cuts the receiver).
enum class VisualEvent {
  contact = 0,          // D0: not a visual event, the patches meet
  emitter_vertex = 1,   // EV: plane through an emitter vertex and an occluder edge
  occluder_vertex = 2,  // VE: plane through an occluder vertex and an emitter edge
};

struct DiscontinuitySegment {
  int patch = -1;    // the patch the segment lies on (it becomes a constraint there)
  int other = -1;    // the patch that causes it: the touching patch (D0) or the occluder
  int emitter = -1;  // the emitter patch (D1/D2); -1 for contacts
  // Order of the discontinuity in the radiosity across the line:
  // 0 = the value jumps (contact); 1 = the first derivative jumps (the
  // critical plane holds an emitter edge and an occluder edge, e.g. parallel
  // edges); 2 = the second derivative jumps (every other EV/VE event).
  int kind = 0;
  VisualEvent event = VisualEvent::contact;
  Vec3 a{0.0}, b{0.0};
};

// Contact segments: for every pair of non-coplanar patches, the part of one
// patch that lies in or crosses the other's plane, clipped to the other's
// polygon (holes respected), minus what runs along that polygon's boundary
// (such lines are mesh edges already). Crossing points are constructed with
// exact arithmetic (CGAL Epeck) and rounded to double once; points within
// 1e-9 of the scene diagonal of a plane count as on it.
std::vector<DiscontinuitySegment> contact_segments(const Scene& scene);

// Overhang outlines: where every vertex of a patch q lies in front of patch
// p, nearer than `max_gap` to its plane, and q is within about 25 degrees of
// parallel to p (|cos| >= 0.9: a lamp hung just under a ceiling, a
// rug laid just above a floor, a picture on a wall), q's loops projected
// onto p's plane and clipped to p, as contact segments of p (other = q). At
// a mesh's resolution such a gap is a contact: p is dark under q and lit
// beside it, and an element straddling the outline would send what its lit
// part gathered into q's back. mesh_scene uses max_gap = the separation
// floor (min_separation_fraction x max_edge).
std::vector<DiscontinuitySegment> overhang_segments(const Scene& scene, double max_gap);

// Shadow boundaries (D1/D2) cast by every emitter polygon.
//
// For each emitter e, each receiver r facing it and each occluder o in the
// e-r shaft, the critical planes through (emitter vertex, occluder edge) and
// (occluder vertex, emitter edge) are cut with r's plane (exact: CGAL Epeck
// plane-plane intersection and ray-plane points, rounded once). The line is
// kept where the plane is a real critical surface: beyond the occluder
// element as seen from the emitter element (the wedge), on the receiver
// polygon, and where the generator line from the receiver point through the
// occluder element to the emitter element is not blocked by anything else
// (tested at points along the segment; pieces that fail are dropped).
// Occluder edges whose two faces lie on both sides of the critical plane are
// not silhouette edges and make no line. Events formed by three edges (EEE)
// are left out.
struct ShadowOptions {
  // Emitters whose power (largest channel exitance x area) is below this
  // fraction of the strongest emitter's are skipped.
  double weak_emitter = 1e-3;
  // Shadow segments kept per receiver patch; more are dropped with a warning.
  int max_lines_per_receiver = 400;
  // Visibility checks per segment: it is cut into at most this many pieces.
  int visibility_pieces = 16;
  // A segment lying within this distance of a line already kept (at both
  // ends and its middle) is dropped: two lines that close would force the
  // mesher into slivers or a flood of tiny triangles, while the light
  // between them barely changes. 0 keeps everything. mesh_scene sets it to
  // min_separation_fraction x the maximum edge length.
  double min_separation = 0.0;
};

struct ShadowReport {
  int emitters = 0;
  int weak_emitters_skipped = 0;       // emitters below ShadowOptions::weak_emitter
  int pairs = 0;                       // emitter-receiver pairs considered
  int back_facing_pairs_skipped = 0;   // receiver behind the emitter or facing away from it
  int no_occluder_pairs_skipped = 0;   // nothing in the emitter-receiver shaft
  int non_silhouette_skipped = 0;      // occluder edges/vertices the critical plane cuts through
  int hidden_pieces_dropped = 0;       // pieces whose generator line is blocked
  int near_duplicates_dropped = 0;     // segments within min_separation of a kept line
  int budget_receivers = 0;            // receivers that reached max_lines_per_receiver
  int lines_dropped_by_budget = 0;
  int d1 = 0, d2 = 0;                  // segments returned
  std::vector<std::string> warnings;
};

// `contacts` are the scene's contact lines (contact_segments(scene)): a
// shadow line loses the parts that run along one of them.
std::vector<DiscontinuitySegment> shadow_segments(const Scene& scene,
                                                  const std::vector<DiscontinuitySegment>& contacts,
                                                  const ShadowOptions& options, ShadowReport* report = nullptr);

}  // namespace radmesh
