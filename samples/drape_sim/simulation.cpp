#include "simulation.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "drape/runtime/capsule_colliders.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skinning.h"
#include "tasks/parallel_for.h"

namespace drape::sim {
namespace {

bool Finite(Float3 p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

// Reads a small /proc file into `buffer` (NUL-terminated, truncated to fit) without allocating;
// the length read, 0 on failure.
size_t ReadProcFile(const char* path, char* buffer, size_t capacity) {
  const int fd = ::open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return 0;
  size_t length = 0;
  while (length + 1 < capacity) {
    const ssize_t n = ::read(fd, buffer + length, capacity - 1 - length);
    if (n <= 0) break;
    length += static_cast<size_t>(n);
  }
  ::close(fd);
  buffer[length] = '\0';
  return length;
}

// The unsigned decimal after optional spaces at `text`; false when there is none.
bool ParseCount(const char* text, const char* end, uint64_t* value) {
  while (text < end && (*text == ' ' || *text == '\t')) ++text;
  return std::from_chars(text, end, *value).ec == std::errc();
}

}  // namespace

uint64_t ResidentSetBytes() {
  // statm: "size resident shared text lib data dt", in pages.
  char buffer[256];
  const size_t length = ReadProcFile("/proc/self/statm", buffer, sizeof(buffer));
  const char* const end = buffer + length;
  uint64_t size_pages = 0, resident_pages = 0;
  const char* cursor = buffer;
  if (!ParseCount(cursor, end, &size_pages)) return 0;
  cursor = std::strchr(cursor, ' ');
  if (cursor == nullptr || !ParseCount(cursor, end, &resident_pages)) return 0;
  const long page_bytes = ::sysconf(_SC_PAGESIZE);
  return page_bytes > 0 ? resident_pages * static_cast<uint64_t>(page_bytes) : 0;
}

uint64_t PeakResidentSetBytes() {
  // status: one "Key:\tvalue" line each; "VmHWM:     123456 kB".
  char buffer[8192];
  const size_t length = ReadProcFile("/proc/self/status", buffer, sizeof(buffer));
  const char* const line = std::strstr(buffer, "VmHWM:");
  if (length == 0 || line == nullptr) return 0;
  uint64_t kib = 0;
  if (!ParseCount(line + 6, buffer + length, &kib)) return 0;
  return kib * 1024;
}

RunSummary SummarizeRun(std::span<const FrameStats> frames) {
  RunSummary summary;
  const size_t n = frames.size();
  summary.frames = static_cast<int64_t>(n);
  if (n == 0) return summary;
  std::vector<double> step_ms(n);
  double total = 0.0;
  for (size_t k = 0; k < n; ++k) {
    const FrameStats& f = frames[k];
    step_ms[k] = f.step_ms;
    total += f.step_ms;
    summary.measure_ms_mean += f.measure_ms / static_cast<double>(n);
    summary.maps_render_ms_mean += f.maps_render_ms / static_cast<double>(n);
    if (!f.finite) ++summary.nan_frames;
    if (f.inside_particles > 0) ++summary.frames_with_inside;
    summary.inside_particles_max = std::max(summary.inside_particles_max, f.inside_particles);
    summary.held_inside_particles_max =
        std::max(summary.held_inside_particles_max, f.held_inside_particles);
    summary.held_max_penetration = std::max(summary.held_max_penetration, f.held_max_penetration);
    if (f.max_penetration > summary.max_penetration) {
      summary.max_penetration = f.max_penetration;
      summary.max_penetration_frame = f.frame;
    }
  }
  for (size_t tenth = 0; tenth < 10; ++tenth) {
    const size_t begin = tenth * n / 10, end = (tenth + 1) * n / 10;
    if (begin == end) continue;
    double sum = 0.0;
    for (size_t k = begin; k < end; ++k) sum += step_ms[k];
    summary.step_ms_tenths.push_back(sum / static_cast<double>(end - begin));
  }
  summary.step_ms_mean = total / static_cast<double>(n);
  std::sort(step_ms.begin(), step_ms.end());
  // Nearest rank: the smallest value with at least p n values at or below it.
  const auto rank = [&](double p) {
    const auto r = static_cast<size_t>(std::ceil(p * static_cast<double>(n)));
    return step_ms[std::clamp<size_t>(r, 1, n) - 1];
  };
  summary.step_ms_median = rank(0.5);
  summary.step_ms_p99 = rank(0.99);
  summary.step_ms_max = step_ms.back();
  summary.rss_after_100_frames = frames[std::min<size_t>(100, n) - 1].rss_bytes;
  summary.rss_end = frames.back().rss_bytes;
  summary.rss_growth =
      static_cast<int64_t>(summary.rss_end) - static_cast<int64_t>(summary.rss_after_100_frames);
  return summary;
}

float ClipTimeOf(const ClipData& clip, float time, bool loop) {
  if (loop && clip.duration > 0.f) {
    time = std::fmod(time, clip.duration);
    if (time < 0.f) time += clip.duration;
  }
  return std::fmin(std::fmax(time, 0.f), clip.duration);
}

Status SceneSimulation::Init(const bake::Scene& scene, const CharacterAsset& asset, int32_t clip) {
  scene_ = &scene;
  asset_ = &asset;
  clip_ = clip;
  settle_frames_ = static_cast<int64_t>(std::lround(scene.animation.settle / scene.dt));
  const std::string where = scene.source + ": ";
  if (Status s = pose_.Init(asset.skeleton); !s.ok()) return Status(s.code(), where + s.message());
  if (Status s = poser_.Init(scene, asset, clip); !s.ok()) return s;

  // Hulls and joint spheres: one set holding the kinds the scene uses.
  std::vector<HullColliderData> hulls;
  std::vector<JointSphereData> spheres;
  if (scene.use_hulls) {
    hulls = asset.hulls;
    for (uint32_t h = 0; h < asset.hulls.size(); ++h) hull_indices_.push_back(h);
  }
  if (scene.use_spheres) {
    spheres = asset.joint_spheres;
    for (uint32_t s = 0; s < asset.joint_spheres.size(); ++s) sphere_indices_.push_back(s);
  }
  if (!hulls.empty() || !spheres.empty()) {
    if (Status s = hulls_.Build(hulls, spheres, asset.skeleton.joint_count(), scene.hull_options);
        !s.ok()) {
      return Status(s.code(), where + "the asset's hulls and spheres: " + s.message());
    }
    has_hull_set_ = true;
  }
  if (scene.use_maps && scene.maps_source == bake::MapSource::kRendered) {
    if (Status s = InitRenderedMaps(asset); !s.ok()) return s;
  } else if (scene.use_maps) {
    std::vector<BodyMapPose> poses;
    for (const BodyMapPose& p : asset.body_maps.poses)
      if (p.clip == clip) poses.push_back(p);
    if (poses.empty()) {
      return Status(
          StatusCode::kInvalidArgument,
          where + "/collision/methods: uses maps, but the asset holds no body-map pose " +
              (clip < 0 ? std::string("of the static pose")
                        : "of clip '" + asset.clips[static_cast<size_t>(clip)].name + "'"));
    }
    std::stable_sort(poses.begin(), poses.end(),
                     [](const BodyMapPose& a, const BodyMapPose& b) { return a.time < b.time; });
    if (Status s = maps_.Build(poses, scene.maps_sampling, scene.maps_blend); !s.ok())
      return Status(s.code(), where + "the asset's body maps: " + s.message());
    has_maps_ = true;
  }

  // The engine shapes, placed from the rest pose, and the baked capsules.
  {
    SkeletonPose rest;
    if (Status s = rest.Init(asset.skeleton); !s.ok()) return s;
    rest.SetRest();
    if (Status s = scene_shapes_.Init(scene, asset.skeleton, rest.skinning()); !s.ok()) return s;
    const size_t capsules = scene.use_capsules ? asset.capsules.size() : 0;
    shapes_.Reserve(scene_shapes_.size() + static_cast<uint32_t>(capsules), 0);
  }

  // Garments, placed at the start pose.
  if (Status s = Pose(scene.animation.start, &skin_start_); !s.ok()) return s;
  skin_end_ = skin_start_;
  ClothSolverSettings settings = scene.solver;
  // `relative` is linear inertia 0; any inertia below 1 is relative to the root joint.
  if (scene.relative) settings.linear_inertia = 0.f;
  if (settings.linear_inertia < 1.f || settings.angular_inertia < 1.f) {
    settings.root_joint = 0;
    Mat34 root;
    if (!asset.skeleton.inverse_bind.empty() &&
        InverseAffine(asset.skeleton.inverse_bind[0], &root))
      settings.root_bind_position = {root.m[3], root.m[7], root.m[11]};
  }
  for (size_t g = 0; g < scene.garments.size(); ++g) {
    auto garment = std::make_unique<Garment>();
    if (Status s = bake::ResolveGarment(scene, g, asset.skeleton, &garment->resolved); !s.ok())
      return s;
    if (Status s = bake::SkinGarment(scene, g, asset.skeleton, asset.mesh, &garment->resolved);
        !s.ok())
      return s;
    const std::string at = where + scene.garments[g].path + ": ";
    if (Status s = BuildCloth(garment->resolved.description, &garment->cloth); !s.ok())
      return Status(s.code(), at + s.message());
    ClothSolverSettings garment_settings = settings;
    if (scene.auto_substeps) {
      garment_settings.substeps = std::clamp(
          RecommendedEulerSubsteps(garment->cloth, scene.dt, settings.damping), 1u, 256u);
    }
    if (Status s = garment->solver.Init(garment->cloth, garment_settings); !s.ok())
      return Status(s.code(), at + s.message());
    garment->state.Reset(garment->cloth);
    if (garment->cloth.skinned()) {  // at its skinned positions
      if (Status s = garment->solver.Reset(&garment->state, {}, skin_start_); !s.ok())
        return Status(s.code(), at + s.message());
      garment->start_positions = garment->state.positions;
    } else {
      bake::PlaceGarment(garment->resolved, skin_start_, &garment->start_positions);
      garment->state.positions = garment->start_positions;
      garment->state.previous_positions = garment->start_positions;
    }
    garments_.push_back(std::move(garment));
  }
  return Status::Ok();
}

uint32_t SceneSimulation::particle_count() const {
  uint32_t n = 0;
  for (const auto& g : garments_) n += g->cloth.particle_count();
  return n;
}

float SceneSimulation::FrameStartTime(int64_t frame) const {
  return scene_->animation.start + (frame < 0 ? 0.f : static_cast<float>(frame) * scene_->dt);
}

Status SceneSimulation::Pose(float time, std::vector<Mat34>* skinning) {
  if (Status s = poser_.Pose(time, &pose_); !s.ok())
    return Status(s.code(), scene_->source + ": " + s.message());
  skinning->assign(pose_.skinning().begin(), pose_.skinning().end());
  return Status::Ok();
}

Status SceneSimulation::Step(int64_t frame, FrameStats* stats) {
  *stats = FrameStats{};
  stats->frame = frame;
  const float t0 = FrameStartTime(frame);
  const float t1 = frame < 0 ? t0 : t0 + scene_->dt;
  stats->time = t1;
  if (Status s = Pose(t0, &skin_start_); !s.ok()) return s;
  if (Status s = Pose(t1, &skin_end_); !s.ok()) return s;

  ClothColliders colliders;
  colliders.response = scene_->response;
  colliders.hulls = has_hull_set_ ? &hulls_ : nullptr;
  if (renders_maps_) {
    const auto render_start = std::chrono::steady_clock::now();
    if (Status s = RenderMaps(frame); !s.ok()) return s;
    stats->maps_render_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - render_start)
            .count();
    // Nothing of the body within the garments' reach this frame: no maps to collide with.
    colliders.body_map = rendered_maps_.empty() ? nullptr : &rendered_maps_;
  } else if (has_maps_) {
    const float map_time = clip_ >= 0 ? ClipTimeOf(asset_->clips[static_cast<size_t>(clip_)], t1,
                                                   scene_->animation.loop)
                                      : 0.f;
    colliders.body_map = &maps_.At(map_time, &map_scratch_);
  }
  if (!scene_shapes_.empty() || scene_->use_capsules) {
    if (Status s = scene_shapes_.Pose(skin_start_, skin_end_, &shapes_); !s.ok())
      return Status(s.code(), scene_->source + ": " + s.message());
    if (scene_->use_capsules) {
      if (Status s = AddCapsuleColliders(asset_->capsules, skin_start_, skin_end_, &shapes_);
          !s.ok())
        return Status(s.code(), scene_->source + ": " + s.message());
    }
    colliders.shapes = &shapes_;
  }
  ClothFrame cloth_frame;
  cloth_frame.dt = scene_->dt;
  cloth_frame.skinning_start = skin_start_;
  cloth_frame.skinning_end = skin_end_;

  Status result = Status::Ok();
  for (size_t g = 0; g < garments_.size() && result.ok(); ++g) {
    Garment& garment = *garments_[g];
    ClothStepStats step;
    const auto start = std::chrono::steady_clock::now();
    result = garment.solver.Step(&garment.state, colliders, cloth_frame, &step);
    stats->step_ms +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    stats->contacts += step.contacts;
    stats->hull_contacts += step.hull_contacts;
    stats->body_map_contacts += step.body_map_contacts;
    stats->shape_contacts += step.shape_contacts;
    stats->max_stretch = std::max(stats->max_stretch, step.max_stretch);
    stats->overstretched_springs += step.overstretched_springs;
    if (!result.ok()) {
      result = Status(result.code(), scene_->source + ": frame " + std::to_string(frame) + ", " +
                                         scene_->garments[g].path + ": " + result.message());
    }
  }
  const auto measure_start = std::chrono::steady_clock::now();
  Measure(colliders.body_map, stats);
  stats->measure_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - measure_start)
          .count();
  stats->rss_bytes = ResidentSetBytes();
  return result;
}

// The rest pose's maps give the texel size, epsilon and grid; the mesh is the asset's.
Status SceneSimulation::InitRenderedMaps(const CharacterAsset& asset) {
  const std::string where = scene_->source + ": ";
  if (asset.body_maps.poses.empty()) {
    return Status(StatusCode::kInvalidArgument,
                  where +
                      "/collision/methods: uses maps, but the asset holds no body-map pose "
                      "(rendered maps take the texel size of its rest pose's)");
  }
  const BodyMapPose& rest = asset.body_maps.poses.front();
  BodyMapRenderOptions options;
  options.texel_size = rest.texel_size;
  options.epsilon = asset.body_maps.epsilon;
  options.grid_x = rest.origin_x;
  options.grid_y = rest.origin_y;
  options.view_axis = rest.view_axis;
  options.sampling = scene_->maps_sampling;
  if (Status s = renderer_.Init(RenderMeshOf(asset), options); !s.ok())
    return Status(s.code(), where + "rendered maps: " + s.message());
  renders_maps_ = true;
  return Status::Ok();
}

// The end pose's maps over the box the garments can reach this frame: their particles' box,
// padded by twice the fastest particle's motion in a frame and the scene's reach margin.
Status SceneSimulation::RenderMaps(int64_t frame) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  RenderRegion region;
  region.min = {kInf, kInf, kInf};
  region.max = {-kInf, -kInf, -kInf};
  float fastest = 0.f;  // metres per second
  for (const auto& g : garments_) {
    for (size_t i = 0; i < g->state.positions.size(); ++i) {
      const Float3 p = g->state.positions[i];
      if (!Finite(p)) continue;
      region.min = {std::min(region.min.x, p.x), std::min(region.min.y, p.y),
                    std::min(region.min.z, p.z)};
      region.max = {std::max(region.max.x, p.x), std::max(region.max.y, p.y),
                    std::max(region.max.z, p.z)};
      if (Finite(g->state.velocities[i])) {
        fastest = std::max(fastest, Length(g->state.velocities[i]));
      }
    }
  }
  const float pad = scene_->reach_margin + 2.f * std::min(fastest, 100.f) * scene_->dt;
  const bool any = region.min.x <= region.max.x;
  region.min = any ? region.min - Float3{pad, pad, pad} : Float3{-kInf, -kInf, -kInf};
  region.max = any ? region.max + Float3{pad, pad, pad} : Float3{kInf, kInf, kInf};
  if (Status s = renderer_.Render(skin_end_, &rendered_maps_, &region); !s.ok()) {
    return Status(s.code(), scene_->source + ": frame " + std::to_string(frame) +
                                ", rendered maps: " + s.message());
  }
  return Status::Ok();
}

void SceneSimulation::Measure(const BodyMapCollider* body_map, FrameStats* stats) {
  // Point queries at the end pose: the hull set at exactly s = 1 (Step leaves its last substep
  // selected; the next Step poses it afresh).
  if (has_hull_set_) (void)hulls_.SelectSubstep(1.f, 1.f);
  const HullColliderSet* hulls = has_hull_set_ ? &hulls_ : nullptr;
  // The queries are const and thread-safe; they run in chunks of 1024 particles on the
  // runtime's task system (tasks/parallel_for.h), each chunk's figures in its own slot, combined
  // in chunk order.
  struct ChunkFigures {
    uint32_t inside = 0, held_inside = 0;
    float deepest = 0.f, held_deepest = 0.f;
    bool finite = true;
  };
  constexpr int64_t kChunk = 1024;
  std::vector<ChunkFigures> chunks;
  for (const auto& g : garments_) {
    const ClothState& state = g->state;
    const std::span<const float> inverse_masses = g->cloth.inverse_masses();
    const auto n = static_cast<int64_t>(state.positions.size());
    chunks.assign(static_cast<size_t>((n + kChunk - 1) / kChunk), ChunkFigures{});
    detail::ParallelRanges(n, kChunk, [&](int64_t begin, int64_t end) {
      ChunkFigures& figures = chunks[static_cast<size_t>(begin / kChunk)];
      for (int64_t i = begin; i < end; ++i) {
        const Float3 p = state.positions[static_cast<size_t>(i)];
        if (!Finite(p) || !Finite(state.velocities[static_cast<size_t>(i)])) {
          figures.finite = false;
          continue;
        }
        float depth = -1.f;  // < 0: outside every collider
        if (hulls != nullptr) {
          const ContactQuery q = hulls->Query(p, p);
          if (q.inside_end) depth = std::max(depth, q.depth);
        }
        if (body_map != nullptr) {
          const ContactQuery q = body_map->Query(p, p);
          if (q.inside_end) depth = std::max(depth, q.depth);
        }
        if (depth < 0.f) continue;
        if (inverse_masses[static_cast<size_t>(i)] == 0.f) {  // held: kinematic
          ++figures.held_inside;
          figures.held_deepest = std::max(figures.held_deepest, depth);
        } else {
          ++figures.inside;
          figures.deepest = std::max(figures.deepest, depth);
        }
      }
    });
    for (const ChunkFigures& figures : chunks) {
      stats->inside_particles += figures.inside;
      stats->max_penetration = std::max(stats->max_penetration, figures.deepest);
      stats->held_inside_particles += figures.held_inside;
      stats->held_max_penetration = std::max(stats->held_max_penetration, figures.held_deepest);
      stats->finite = stats->finite && figures.finite;
    }
  }
}

void SceneSimulation::SkinBody(std::vector<Float3>* positions) const {
  positions->resize(asset_->mesh.vertex_count());
  (void)SkinMesh(asset_->mesh, skin_end_, *positions);
}

}  // namespace drape::sim
