#include "hull/hull_mesh.h"

#include <tuple>

namespace drape::bake::detail {

void SortUnique(std::vector<Vec3>* points) {
  std::sort(points->begin(), points->end(), [](const Vec3& a, const Vec3& b) {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  });
  points->erase(std::unique(points->begin(), points->end(),
                            [](const Vec3& a, const Vec3& b) {
                              return a.x == b.x && a.y == b.y && a.z == b.z;
                            }),
                points->end());
}

}  // namespace drape::bake::detail
