#pragma once
// drape-sim's simulation of one scene through the runtime alone: the skeleton posed from the
// clip at the start and end of every frame, the colliders the scene uses (hulls and joint spheres
// posed by the skinning matrices, the body-map pose picked for the frame's end time), one
// ClothSolver per garment, and per-frame figures measured after the step with the colliders' own
// queries.

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "drape/bake/scene.h"
#include "drape/formats/character_asset.h"
#include "drape/formats/status.h"
#include "drape/runtime/body_map_collider.h"
#include "drape/runtime/cloth.h"
#include "drape/runtime/cloth_solver.h"
#include "drape/runtime/hull_collider.h"
#include "drape/runtime/skeleton_pose.h"

namespace drape::sim {

struct FrameStats {
  int64_t frame = 0;               // output frame index; settle frames are negative
  float time = 0.f;                // scene time at the end of the frame, seconds
  double step_ms = 0.0;            // wall time of the solver steps of all garments
  uint32_t contacts = 0;           // particles in contact in the last substep, all garments
  uint32_t hull_contacts = 0;      // hulls and spheres, summed over substeps
  uint32_t body_map_contacts = 0;  // summed over substeps
  // After the step, at the frame's end pose: particles inside a collider the scene uses and the
  // deepest of them (metres), from HullColliderSet::Query and BodyMapCollider::Query of the
  // particle's position (a point query).
  uint32_t inside_particles = 0;
  float max_penetration = 0.f;
  float max_stretch = 0.f;  // max over stretch springs of L / R - 1
  bool finite = true;       // every position and velocity finite
};

class SceneSimulation {
 public:
  // `scene` (clip resolved, frame_count set) and `asset` must outlive the simulation. Builds the
  // colliders the scene's methods name, resolves and places the garments at the start pose.
  Status Init(const bake::Scene& scene, const CharacterAsset& asset, int32_t clip);

  // Frames held at the start pose before frame 0: round(settle / dt).
  int64_t settle_frames() const { return settle_frames_; }
  // Advances frame `frame` (negative: a settle frame). Fills stats even on failure.
  Status Step(int64_t frame, FrameStats* stats);

  // Drawing and output: the body skinned at the end of the last frame, the garments.
  void SkinBody(std::vector<Float3>* positions) const;
  size_t garment_count() const { return garments_.size(); }
  std::span<const Float3> garment_positions(size_t g) const {
    return garments_[g]->state.positions;
  }
  std::span<const uint32_t> garment_triangles(size_t g) const {
    return garments_[g]->cloth.triangles();
  }
  // Positions of the garment at the start pose (before settling), for framing the camera.
  std::span<const Float3> garment_start_positions(size_t g) const {
    return garments_[g]->start_positions;
  }
  uint32_t particle_count() const;
  // The colliders in use, posed for the last frame (null when no hull or sphere is used).
  const HullColliderSet* hulls() const { return has_hull_set_ ? &hulls_ : nullptr; }
  // Indices into asset.hulls / asset.joint_spheres of the hull set's colliders.
  const std::vector<uint32_t>& hull_indices() const { return hull_indices_; }
  const std::vector<uint32_t>& sphere_indices() const { return sphere_indices_; }
  // The skinning matrices at the end of the last frame.
  std::span<const Mat34> skinning() const { return skin_end_; }
  uint32_t substeps(size_t g) const { return garments_[g]->solver.settings().substeps; }

  // Scene time at the start of frame `frame` (settle frames: the start time).
  float FrameStartTime(int64_t frame) const;

 private:
  struct Garment {
    bake::ResolvedGarment resolved;
    Cloth cloth;
    ClothSolver solver;
    ClothState state;
    std::vector<Float3> start_positions;
  };

  Status Pose(float time, std::vector<Mat34>* skinning);
  void Measure(const BodyMapCollider* body_map, FrameStats* stats);

  const bake::Scene* scene_ = nullptr;
  const CharacterAsset* asset_ = nullptr;
  int32_t clip_ = -1;
  int64_t settle_frames_ = 0;
  SkeletonPose pose_;
  std::vector<Mat34> skin_start_, skin_end_;
  HullColliderSet hulls_;
  bool has_hull_set_ = false;
  std::vector<uint32_t> hull_indices_, sphere_indices_;
  BodyMapSequence maps_;
  BodyMapCollider map_scratch_;
  bool has_maps_ = false;
  std::vector<std::unique_ptr<Garment>> garments_;
};

// The clip time a scene time plays (wrapped when looping, clamped to the clip).
float ClipTimeOf(const ClipData& clip, float time, bool loop);

}  // namespace drape::sim
