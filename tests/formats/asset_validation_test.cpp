// ValidateAsset names the field of every out-of-range index and inconsistent value (a cyclic
// hierarchy, a skeleton out of order, a skewed rotation, a degenerate box, a duplicate name), and
// the writer refuses what it refuses.

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "asset_fixtures.h"
#include "drape/formats/asset_file.h"

namespace drape {
namespace {

using test::SmallAsset;

TEST(AssetFile, OutOfRangeIndicesAreRefusedWithTheField) {
  CharacterAsset a = SmallAsset();
  a.hulls[0].triangles[4] = 99;
  std::vector<uint8_t> invalid;
  EXPECT_FALSE(EncodeAsset(a, &invalid).ok()) << "the writer must refuse an invalid asset";
  const Status v = ValidateAsset(a);
  EXPECT_NE(v.message().find("hulls[0].triangles[4] = 99 is out of range [0, 4)"),
            std::string::npos)
      << v.message();

  CharacterAsset cyclic = SmallAsset();
  cyclic.hulls[0].upper.children[0] = 1;  // a node that is its own child: a walk would not end
  EXPECT_NE(ValidateAsset(cyclic).message().find("hulls[0].upper.children[0]"), std::string::npos);
  CharacterAsset parents = SmallAsset();
  parents.skeleton.parents[1] = 2;
  EXPECT_NE(ValidateAsset(parents).message().find("skeleton.parents[1] = 2"), std::string::npos);
  CharacterAsset skewed = SmallAsset();
  skewed.skeleton.rest_local[1].rotation = {0.f, 0.f, 0.f, 2.f};
  EXPECT_NE(ValidateAsset(skewed).message().find("not a finite unit quaternion"),
            std::string::npos);
  CharacterAsset tiny = SmallAsset();
  tiny.body_maps.poses[0].texel_size = 1e-30f;  // 1 / texel_size would be infinite
  EXPECT_NE(ValidateAsset(tiny).message().find("texel_size is not in"), std::string::npos);
  CharacterAsset flat = SmallAsset();
  flat.hulls[0].obb.axes[1] = {1, 0, 0};
  EXPECT_NE(ValidateAsset(flat).message().find("obb.axes are not orthonormal"), std::string::npos);
  CharacterAsset cut = SmallAsset();
  cut.hulls[0].plane_internal.pop_back();  // a flag per plane, or none
  EXPECT_NE(ValidateAsset(cut).message().find("hulls[0].plane_internal is neither empty"),
            std::string::npos);
  cut.hulls[0].plane_internal = {0, 2, 0, 0};
  EXPECT_NE(ValidateAsset(cut).message().find("hulls[0].plane_internal[1] is not 0 or 1"),
            std::string::npos);
  CharacterAsset dup = SmallAsset();
  dup.skeleton.joint_names[2] = "root";
  EXPECT_NE(ValidateAsset(dup).message().find("'root' is a duplicate"), std::string::npos);
}

}  // namespace
}  // namespace drape
