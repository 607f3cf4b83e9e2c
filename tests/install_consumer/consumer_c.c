/* Loads a .drape through the installed runtime's C API and poses its first clip. */
#include <stdio.h>

#include "drape/drape.h"

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  drape_asset* asset = NULL;
  if (drape_asset_load(argv[1], &asset) != DRAPE_OK) {
    fprintf(stderr, "%s\n", drape_last_error());
    return 1;
  }
  drape_pose* pose = NULL;
  int ok = drape_pose_create(asset, &pose) == DRAPE_OK;
  if (ok && drape_asset_clip_count(asset) > 0) ok = drape_pose_sample_clip(pose, 0, 0.5f, 1) == 0;
  if (ok) printf("consumer_c: %u joints posed\n", drape_asset_joint_count(asset));
  drape_pose_destroy(pose);
  drape_asset_destroy(asset);
  return ok ? 0 : 1;
}
