// Small geometric vocabulary shared by every module: plain GLM double vectors.
#pragma once

#include <glm/vec3.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <vector>

namespace radmesh {

using Vec3 = glm::dvec3;
// RGB triple (reflectance, emission, radiosity).
using Rgb = glm::dvec3;

// The largest of an RGB triple's channels.
inline double max3(const Rgb& c) { return std::max({c.x, c.y, c.z}); }

// Newell normal (not normalized): its length is twice the polygon's vector area.
Vec3 newell_normal(const std::vector<Vec3>& loop);

// Length of a closed polygon's boundary.
double loop_length(const std::vector<Vec3>& loop);

// Area of a triangle.
double triangle_area(const Vec3& a, const Vec3& b, const Vec3& c);

// Distance from p to the segment (a, b) (to a when a == b).
double point_segment_distance(const Vec3& p, const Vec3& a, const Vec3& b);

}  // namespace radmesh
