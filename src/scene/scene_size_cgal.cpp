// The scene's size (Scene::diagonal): CGAL's smallest enclosing sphere.

#include "radmesh/scene.h"

#include <CGAL/Min_sphere_of_spheres_d.h>
#include <CGAL/Min_sphere_of_spheres_d_traits_3.h>
#include <CGAL/Simple_cartesian.h>

#include <vector>

namespace radmesh {

double Scene::diagonal() const {
  if (vertices.empty()) return 0.0;
  using Kernel = CGAL::Simple_cartesian<double>;
  using Traits = CGAL::Min_sphere_of_spheres_d_traits_3<Kernel, double, CGAL::Tag_true>;
  std::vector<Traits::Sphere> points;
  points.reserve(vertices.size());
  for (const Vec3& v : vertices) points.emplace_back(Kernel::Point_3(v.x, v.y, v.z), 0.0);
  CGAL::Min_sphere_of_spheres_d<Traits> sphere(points.begin(), points.end());  // radius() is not const
  return 2.0 * sphere.radius();
}

}  // namespace radmesh
