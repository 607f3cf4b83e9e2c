#pragma once
// Joint spheres sized by the body around the joint (spheres.cover = surface): centred on the
// joint, as large as the body allows there. Paper B's sphere reaches every blended vertex of the
// joint, which on a smoothly weighted rig is half a limb away (0.25 m at the hips of a 1.8 m
// human, 0.8 m on a 3 m creature); a sphere that large bulges far out of the body.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "drape/bake/regions.h"
#include "drape/formats/hull_collider_data.h"

namespace drape::bake {

class MeshReference;

struct SphereLeftOut {
  int32_t joint = -1, parent_joint = -1;  // the region's bones
  std::string reason;
};

// One sphere per joint region whose centre lies inside the rest-pose body (`body`: the rest
// positions of `regions` and the mesh's triangles): radius = the centre's distance to the body
// surface plus delta (metres), so the sphere stays within delta of the body. A centre outside the
// body, or nearer than min_radius (metres) to its surface, gets no sphere: it is listed in
// *left_out with the reason.
std::vector<JointSphereData> BuildSurfaceJointSpheres(const Regions& regions,
                                                      const MeshReference& body, float delta,
                                                      float min_radius,
                                                      std::vector<SphereLeftOut>* left_out);

}  // namespace drape::bake
