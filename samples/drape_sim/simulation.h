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
#include "drape/runtime/body_map_renderer.h"
#include "drape/runtime/body_map_sequence.h"
#include "drape/runtime/cloth.h"
#include "drape/runtime/cloth_solver.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/shape_collider_set.h"
#include "drape/runtime/skeleton_pose.h"
#include "scene_shapes.h"

namespace drape::sim {

struct FrameStats {
  int64_t frame = 0;               // output frame index; settle frames are negative
  float time = 0.f;                // scene time at the end of the frame, seconds
  double step_ms = 0.0;            // wall time of the solver steps of all garments
  uint32_t contacts = 0;           // particles in contact in the last substep, all garments
  uint32_t hull_contacts = 0;      // hulls and spheres, summed over substeps
  uint32_t body_map_contacts = 0;  // summed over substeps
  uint32_t shape_contacts = 0;     // the scene's engine shapes, summed over substeps
  // After the step, at the frame's end pose: simulated particles inside a collider the scene uses
  // and the deepest of them (metres), from HullColliderSet::Query and BodyMapCollider::Query of
  // the particle's position (a point query).
  uint32_t inside_particles = 0;
  float max_penetration = 0.f;
  // The same for the held particles (attached, pinned, skinned with max distance 0): the scene
  // puts them where they are (a waistband drawn inside the hips) and no collider moves them, so
  // they are counted apart from what the solver answers for.
  uint32_t held_inside_particles = 0;
  float held_max_penetration = 0.f;
  float max_stretch = 0.f;  // max over stretch springs of L / R - 1
  // Stretch springs beyond their garment's strain limit (ClothStepStats), all garments.
  uint32_t overstretched_springs = 0;
  bool finite = true;           // every position and velocity finite
  uint64_t rss_bytes = 0;       // the process's resident set size after the frame (0: unknown)
  double measure_ms = 0.0;      // wall time of the point queries above (not part of step_ms)
  double maps_render_ms = 0.0;  // wall time of rendering the frame's maps (not part of step_ms)
};

// The process's memory, for long runs (Linux /proc; 0 when the file cannot be read or parsed).
// Neither allocates, so reading them every frame does not disturb what they measure.
// The resident set size now, bytes: resident pages of /proc/self/statm times the page size.
uint64_t ResidentSetBytes();
// The peak resident set size so far, bytes: VmHWM of /proc/self/status.
uint64_t PeakResidentSetBytes();

// Figures over the frames of a run (settle frames excluded), for stats.json's totals and the
// soak command's checks.
struct RunSummary {
  int64_t frames = 0;
  // Step time, ms: mean per tenth of the run (frames [i n / 10, (i + 1) n / 10); an empty tenth,
  // only when n < 10, is left out), overall mean, median and p99 (nearest rank), max.
  std::vector<double> step_ms_tenths;
  double step_ms_mean = 0.0, step_ms_median = 0.0, step_ms_p99 = 0.0, step_ms_max = 0.0;
  double measure_ms_mean = 0.0;            // the per-frame point queries, ms
  double maps_render_ms_mean = 0.0;        // rendering each frame's maps (rendered maps only), ms
  uint32_t nan_frames = 0;                 // frames with a non-finite position or velocity
  uint32_t frames_with_inside = 0;         // frames ending with a simulated particle inside
  uint32_t inside_particles_max = 0;       // most particles inside at the end of one frame
  float max_penetration = 0.f;             // metres, deepest over the run
  int64_t max_penetration_frame = -1;      // the first frame reaching it (-1: none inside)
  uint32_t held_inside_particles_max = 0;  // held particles: most inside at the end of one frame
  float held_max_penetration = 0.f;        // held particles: metres, deepest over the run
  // Resident set size, bytes (0: unknown): after the first 100 frames (frame 99, or the last
  // frame of a shorter run), after the last frame, and the growth between them (may be < 0).
  uint64_t rss_after_100_frames = 0, rss_end = 0;
  int64_t rss_growth = 0;
};
RunSummary SummarizeRun(std::span<const FrameStats> frames);

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
  // Garment g as the scene resolved it (mesh, holds, skin, max distance and backstop).
  const bake::ResolvedGarment& resolved_garment(size_t g) const { return garments_[g]->resolved; }
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
  bake::ScenePoser poser_;
  std::vector<Mat34> skin_start_, skin_end_;
  HullColliderSet hulls_;
  bool has_hull_set_ = false;
  std::vector<uint32_t> hull_indices_, sphere_indices_;
  BodyMapSequence maps_;
  BodyMapCollider map_scratch_;
  bool has_maps_ = false;
  // Rendered maps (MapSource::kRendered): each frame's end pose over the garments' reach.
  Status InitRenderedMaps(const CharacterAsset& asset);
  Status RenderMaps(int64_t frame);
  BodyMapRenderer renderer_;
  BodyMapCollider rendered_maps_;
  bool renders_maps_ = false;
  std::vector<std::unique_ptr<Garment>> garments_;
  SceneShapes scene_shapes_;  // the scene's engine colliders, posed per frame into shapes_
  ShapeColliderSet shapes_;
};

// The clip time a scene time plays (wrapped when looping, clamped to the clip).
float ClipTimeOf(const ClipData& clip, float time, bool loop);

}  // namespace drape::sim
