#include "regions/surface_spheres.h"

#include <cmath>

#include "drape/bake/mesh_reference.h"
#include "drape/runtime/math.h"

namespace drape::bake {

std::vector<JointSphereData> BuildSurfaceJointSpheres(const Regions& regions,
                                                      const MeshReference& body, float delta,
                                                      float min_radius,
                                                      std::vector<SphereLeftOut>* left_out) {
  std::vector<JointSphereData> spheres;
  for (const JointRegion& region : regions.joints) {
    const double q[3] = {region.center.x, region.center.y, region.center.z};
    const auto leave = [&](const char* reason) {
      if (left_out != nullptr) left_out->push_back({region.child, region.parent, reason});
    };
    if (!body.Inside(q)) {
      leave("its centre is outside the body");
      continue;
    }
    // Distance to the surface: the largest ball at the centre with no surface point inside.
    const double distance = body.Distance(q);
    if (!(distance >= min_radius)) {
      leave("its centre is nearer the surface than spheres.min_radius");
      continue;
    }
    Mat34 rest_to_bind;
    if (!InverseAffine(regions.rest_skinning[region.child], &rest_to_bind)) {
      leave("its bone's rest matrix is not invertible");
      continue;
    }
    JointSphereData sphere;
    sphere.joint = region.child;
    sphere.parent_joint = region.parent;
    sphere.center = TransformPoint(rest_to_bind, region.center);
    sphere.radius = static_cast<float>(distance) + delta;
    spheres.push_back(sphere);
  }
  return spheres;
}

}  // namespace drape::bake
