// Loads a .drape with the installed runtime and poses its first clip.
#include <cstdio>

#include "drape/formats/asset_file.h"
#include "drape/runtime/skeleton_pose.h"

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  drape::CharacterAsset asset;
  if (drape::Status s = drape::ReadAssetFile(argv[1], &asset); !s.ok()) {
    std::fprintf(stderr, "%s\n", s.message().c_str());
    return 1;
  }
  drape::SkeletonPose pose;
  if (!pose.Init(asset.skeleton).ok()) return 1;
  if (!asset.clips.empty() && !pose.SampleClip(asset.clips[0], 0.5f, true).ok()) return 1;
  std::printf("consumer: %u joints posed\n", pose.joint_count());
  return 0;
}
