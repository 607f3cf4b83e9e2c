// Private to the runtime: BodyMapCollider's lanes (short motions, walks), written once for any
// width in the lane operations of common/lanes/ and instantiated for each pack: ScalarLanes and
// Sse2Lanes in lanes_baseline.cpp, EightLanes in lanes_avx2.cpp (inside its AVX2 target region).
// Every instantiation answers each particle bit for bit as CollideOne does.
//
// These files include nothing: everything they use must be declared before this file is
// included. In the AVX2 file that keeps the headers (and every inline function they define)
// outside the AVX2 region, so that no function the baseline code also uses is ever compiled for
// AVX2.

#include "body_map/lanes/lane_helpers.inl"

#include "body_map/lanes/gap_lanes.inl"

#include "body_map/lanes/short_motion_lanes.inl"

#include "body_map/lanes/walk_lanes.inl"
