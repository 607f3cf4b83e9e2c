#!/usr/bin/env bash
# Rewrites the golden files from the current build. Only for a deliberate change of the bake's
# output: say why in the commit, and keep the old files while the loader still reads them
# (mannequin_colliders_v1.drape, format 1, stays as the backward-reading test of the loader).
# The files below keep their _v2 names (the tests and the engine sample use them) but are written
# in the current format version (3 since BodyMapPose got depth layers; one layer with this
# config). The per-format files mannequin_v<N>.drape are never regenerated (see README.md).
set -euo pipefail
cd "$(dirname "$0")/../.."
build/bin/drape-bake samples/mannequin/mannequin.gltf -o tests/golden/mannequin_colliders_v2.drape \
  --config tests/golden/mannequin_colliders.json
# A shared character's bake beside our own (../shared must be present; the character itself is
# never copied here, only our bake of it).
build/bin/drape-bake ../shared/assets/characters/CesiumMan/CesiumMan.glb \
  -o tests/golden/CesiumMan_colliders_v2.drape --config tests/golden/mannequin_colliders.json
