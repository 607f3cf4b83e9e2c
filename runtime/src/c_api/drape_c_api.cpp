// The C API (drape/drape.h): thin wrappers over the C++ runtime. Each entry point validates its
// pointers and counts, converts the plain arrays to the runtime's types without copying where
// the layouts agree (Float3 and Mat34 are plain floats), and turns a Status or an allocation
// failure into a drape_status plus the thread's last error message.
#include "drape/drape.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <new>
#include <span>
#include <string>
#include <vector>

#include "drape/formats/asset_file.h"
#include "drape/runtime/capsule_colliders.h"
#include "drape/runtime/cloth.h"
#include "drape/runtime/cloth_solver.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/math.h"
#include "drape/runtime/shape_collider_set.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/task_system.h"

static_assert(sizeof(drape::Float3) == 3 * sizeof(float), "positions are 3 floats");
static_assert(sizeof(drape::Mat34) == 12 * sizeof(float), "matrices are 12 floats");
static_assert(static_cast<int>(drape::StatusCode::kInvalidState) == DRAPE_INVALID_STATE);

struct drape_asset {
  drape::CharacterAsset asset;
};
struct drape_pose {
  const drape::CharacterAsset* asset = nullptr;
  drape::SkeletonPose pose;
};
struct drape_colliders {
  drape::HullColliderSet hulls;
};
struct drape_shapes {
  drape::ShapeColliderSet shapes;
};
struct drape_cloth {
  drape::Cloth cloth;
  drape::ClothSolver solver;
  drape::ClothState state;
  drape::ResponseParams response;
};

namespace {

thread_local std::string g_last_error;

drape_status Fail(drape_status code, const std::string& message) {
  g_last_error = message;
  return code;
}

drape_status FromStatus(const drape::Status& s) {
  if (s.ok()) return DRAPE_OK;
  return Fail(static_cast<drape_status>(s.code()), s.message());
}

drape_status Null(const char* function, const char* argument) {
  return Fail(DRAPE_INVALID_ARGUMENT, std::string(function) + ": " + argument + " is NULL");
}

// Runs a setup step that allocates: an allocation failure becomes DRAPE_OUT_OF_MEMORY.
template <class Fn>
drape_status Guarded(const char* function, Fn&& fn) {
  try {
    return fn();
  } catch (const std::bad_alloc&) {
    return Fail(DRAPE_OUT_OF_MEMORY, std::string(function) + ": out of memory");
  }
}

const drape::Mat34& AsMatrix(const float* m) { return *reinterpret_cast<const drape::Mat34*>(m); }
std::span<const drape::Mat34> AsMatrices(const float* m, uint32_t count) {
  return {reinterpret_cast<const drape::Mat34*>(m), count};
}

// The engine's parallel-for behind the runtime's TaskSystem interface.
class CallbackTaskSystem final : public drape::TaskSystem {
 public:
  void Set(drape_parallel_for_fn parallel_for, uint32_t workers, void* user) {
    parallel_for_ = parallel_for;
    workers_ = workers < 1 ? 1 : workers;
    user_ = user;
  }
  void ParallelFor(uint32_t chunk_count, drape::TaskFunction run, void* context) override {
    parallel_for_(chunk_count, run, context, user_);
  }
  uint32_t WorkerCount() const override { return workers_; }

 private:
  drape_parallel_for_fn parallel_for_ = nullptr;
  uint32_t workers_ = 1;
  void* user_ = nullptr;
};

CallbackTaskSystem g_callback_tasks;

drape::ClothDescription Describe(const drape_cloth_desc& d) {
  drape::ClothDescription c;
  const auto* xyz = reinterpret_cast<const drape::Float3*>(d.positions);
  c.positions.assign(xyz, xyz + d.particle_count);
  c.triangles.assign(d.triangles, d.triangles + size_t{3} * d.triangle_count);
  if (d.pinned != nullptr) c.pinned.assign(d.pinned, d.pinned + d.pinned_count);
  c.density = d.density;
  c.stretch.stiffness = d.stretch_stiffness;
  c.stretch.damping = d.stretch_damping;
  c.bend.stiffness = d.bend_stiffness;
  c.bend.damping = d.bend_damping;
  c.tethers = d.tethers != 0;
  c.tether_stretch = d.tether_stretch;
  if (d.skin_joints != nullptr && d.skin_weights != nullptr) {
    c.skin.resize(d.particle_count);
    for (uint32_t i = 0; i < d.particle_count; ++i) {
      for (int k = 0; k < 4; ++k) {
        c.skin[i].joints[k] = d.skin_joints[4 * i + k];
        c.skin[i].weights[k] = d.skin_weights[4 * i + k];
      }
    }
  }
  if (d.max_distance != nullptr)
    c.max_distance.assign(d.max_distance, d.max_distance + d.particle_count);
  if (d.backstop != nullptr) c.backstop.assign(d.backstop, d.backstop + d.particle_count);
  return c;
}

drape::ClothSolverSettings SolverSettings(const drape_solver_settings& s) {
  drape::ClothSolverSettings c;
  c.substeps = s.substeps;
  c.iterations = s.iterations;
  c.gravity = {s.gravity[0], s.gravity[1], s.gravity[2]};
  c.damping = s.damping;
  c.max_stretch = s.max_stretch < 0.f ? std::numeric_limits<float>::infinity() : s.max_stretch;
  c.tethers = s.tethers != 0;
  c.root_joint = s.root_joint;
  c.root_bind_position = {s.root_bind_position[0], s.root_bind_position[1],
                          s.root_bind_position[2]};
  c.linear_inertia = s.linear_inertia;
  c.angular_inertia = s.angular_inertia;
  c.centrifugal_inertia = s.centrifugal_inertia;
  c.measure_stretch = s.measure_stretch != 0;
  c.guard_blowups = s.guard_blowups != 0;
  return c;
}

drape::ResponseParams Response(const drape_solver_settings& s) {
  drape::ResponseParams r;
  r.friction = s.friction;
  r.static_friction = s.static_friction;
  r.restitution = s.restitution;
  r.separation = s.separation;
  return r;
}

}  // namespace

extern "C" {

const char* drape_last_error(void) { return g_last_error.c_str(); }

void drape_set_task_system(drape_parallel_for_fn parallel_for, uint32_t worker_count, void* user) {
  if (parallel_for == nullptr) {
    drape::SetTaskSystem(nullptr);
    return;
  }
  g_callback_tasks.Set(parallel_for, worker_count, user);
  drape::SetTaskSystem(&g_callback_tasks);
}

// ---- Asset ----------------------------------------------------------------------------------

drape_status drape_asset_load(const char* path, drape_asset** out_asset) {
  if (path == nullptr) return Null("drape_asset_load", "path");
  if (out_asset == nullptr) return Null("drape_asset_load", "out_asset");
  return Guarded("drape_asset_load", [&] {
    auto* a = new drape_asset;
    if (drape_status s = FromStatus(drape::ReadAssetFile(path, &a->asset)); s != DRAPE_OK) {
      delete a;
      return s;
    }
    *out_asset = a;
    return DRAPE_OK;
  });
}

void drape_asset_destroy(drape_asset* asset) { delete asset; }

uint32_t drape_asset_joint_count(const drape_asset* asset) {
  return asset != nullptr ? asset->asset.skeleton.joint_count() : 0;
}

int32_t drape_asset_find_joint(const drape_asset* asset, const char* name) {
  if (asset == nullptr || name == nullptr) return -1;
  const std::vector<std::string>& names = asset->asset.skeleton.joint_names;
  for (size_t j = 0; j < names.size(); ++j)
    if (names[j] == name) return static_cast<int32_t>(j);
  return -1;
}

uint32_t drape_asset_clip_count(const drape_asset* asset) {
  return asset != nullptr ? static_cast<uint32_t>(asset->asset.clips.size()) : 0;
}

float drape_asset_clip_duration(const drape_asset* asset, uint32_t clip) {
  if (asset == nullptr || clip >= asset->asset.clips.size()) return 0.f;
  return asset->asset.clips[clip].duration;
}

drape_status drape_asset_bind_matrix(const drape_asset* asset, uint32_t joint, float out[12]) {
  if (asset == nullptr) return Null("drape_asset_bind_matrix", "asset");
  if (out == nullptr) return Null("drape_asset_bind_matrix", "out");
  const drape::SkeletonData& skeleton = asset->asset.skeleton;
  if (joint >= skeleton.joint_count())
    return Fail(DRAPE_INVALID_ARGUMENT, "drape_asset_bind_matrix: joint " + std::to_string(joint) +
                                            " of a skeleton of " +
                                            std::to_string(skeleton.joint_count()) + " joints");
  drape::Mat34 bind;
  if (!drape::InverseAffine(skeleton.inverse_bind[joint], &bind))
    return Fail(DRAPE_CORRUPT, "drape_asset_bind_matrix: the inverse bind matrix of joint " +
                                   std::to_string(joint) + " is singular");
  std::memcpy(out, bind.m, sizeof(bind.m));
  return DRAPE_OK;
}

// ---- Pose -----------------------------------------------------------------------------------

drape_status drape_pose_create(const drape_asset* asset, drape_pose** out_pose) {
  if (asset == nullptr) return Null("drape_pose_create", "asset");
  if (out_pose == nullptr) return Null("drape_pose_create", "out_pose");
  return Guarded("drape_pose_create", [&] {
    auto* p = new drape_pose;
    p->asset = &asset->asset;
    if (drape_status s = FromStatus(p->pose.Init(asset->asset.skeleton)); s != DRAPE_OK) {
      delete p;
      return s;
    }
    *out_pose = p;
    return DRAPE_OK;
  });
}

void drape_pose_destroy(drape_pose* pose) { delete pose; }

drape_status drape_pose_set_world_matrices(drape_pose* pose, const float* world,
                                           uint32_t joint_count) {
  if (pose == nullptr) return Null("drape_pose_set_world_matrices", "pose");
  if (world == nullptr) return Null("drape_pose_set_world_matrices", "world");
  return FromStatus(pose->pose.SetJointWorldMatrices(AsMatrices(world, joint_count)));
}

drape_status drape_pose_sample_clip(drape_pose* pose, uint32_t clip, float time, int loop) {
  if (pose == nullptr) return Null("drape_pose_sample_clip", "pose");
  if (clip >= pose->asset->clips.size())
    return Fail(DRAPE_INVALID_ARGUMENT, "drape_pose_sample_clip: clip " + std::to_string(clip) +
                                            " of " + std::to_string(pose->asset->clips.size()));
  return FromStatus(pose->pose.SampleClip(pose->asset->clips[clip], time, loop != 0));
}

const float* drape_pose_skinning(const drape_pose* pose) {
  return pose != nullptr ? pose->pose.skinning().data()->m : nullptr;
}

const float* drape_pose_world(const drape_pose* pose) {
  return pose != nullptr ? pose->pose.world().data()->m : nullptr;
}

// ---- Colliders --------------------------------------------------------------------------------

drape_status drape_colliders_create(const drape_asset* asset, drape_colliders** out_colliders) {
  if (asset == nullptr) return Null("drape_colliders_create", "asset");
  if (out_colliders == nullptr) return Null("drape_colliders_create", "out_colliders");
  return Guarded("drape_colliders_create", [&] {
    auto* c = new drape_colliders;
    const drape::CharacterAsset& a = asset->asset;
    if (drape_status s =
            FromStatus(c->hulls.Build(a.hulls, a.joint_spheres, a.skeleton.joint_count()));
        s != DRAPE_OK) {
      delete c;
      return s;
    }
    *out_colliders = c;
    return DRAPE_OK;
  });
}

void drape_colliders_destroy(drape_colliders* colliders) { delete colliders; }

drape_status drape_shapes_create(uint32_t shape_capacity, drape_shapes** out_shapes) {
  if (out_shapes == nullptr) return Null("drape_shapes_create", "out_shapes");
  return Guarded("drape_shapes_create", [&] {
    auto* s = new drape_shapes;
    s->shapes.Reserve(shape_capacity, 0);
    *out_shapes = s;
    return DRAPE_OK;
  });
}

void drape_shapes_destroy(drape_shapes* shapes) { delete shapes; }

void drape_shapes_clear(drape_shapes* shapes) {
  if (shapes != nullptr) shapes->shapes.Clear();
}

drape_status drape_shapes_add_sphere(drape_shapes* shapes, const float start[12],
                                     const float end[12], float radius) {
  if (shapes == nullptr || start == nullptr || end == nullptr)
    return Null("drape_shapes_add_sphere", "shapes, start or end");
  return Guarded("drape_shapes_add_sphere", [&] {
    return FromStatus(shapes->shapes.AddSphere(AsMatrix(start), AsMatrix(end), radius));
  });
}

drape_status drape_shapes_add_capsule(drape_shapes* shapes, const float start[12],
                                      const float end[12], float half_length, float radius0,
                                      float radius1) {
  if (shapes == nullptr || start == nullptr || end == nullptr)
    return Null("drape_shapes_add_capsule", "shapes, start or end");
  return Guarded("drape_shapes_add_capsule", [&] {
    return FromStatus(
        shapes->shapes.AddCapsule(AsMatrix(start), AsMatrix(end), half_length, radius0, radius1));
  });
}

uint32_t drape_asset_capsule_count(const drape_asset* asset) {
  return asset == nullptr ? 0 : static_cast<uint32_t>(asset->asset.capsules.size());
}

drape_status drape_shapes_add_asset_capsules(drape_shapes* shapes, const drape_asset* asset,
                                             const float* skinning_start,
                                             const float* skinning_end) {
  if (shapes == nullptr || asset == nullptr || skinning_start == nullptr || skinning_end == nullptr)
    return Null("drape_shapes_add_asset_capsules", "shapes, asset, skinning_start or skinning_end");
  const uint32_t joints = asset->asset.skeleton.joint_count();
  return Guarded("drape_shapes_add_asset_capsules", [&] {
    return FromStatus(
        drape::AddCapsuleColliders(asset->asset.capsules, AsMatrices(skinning_start, joints),
                                   AsMatrices(skinning_end, joints), &shapes->shapes));
  });
}

drape_status drape_shapes_add_plane(drape_shapes* shapes, const float start[12],
                                    const float end[12]) {
  if (shapes == nullptr || start == nullptr || end == nullptr)
    return Null("drape_shapes_add_plane", "shapes, start or end");
  return Guarded("drape_shapes_add_plane", [&] {
    return FromStatus(shapes->shapes.AddPlane(AsMatrix(start), AsMatrix(end)));
  });
}

drape_status drape_shapes_add_box(drape_shapes* shapes, const float start[12], const float end[12],
                                  const float half_extents[3]) {
  if (shapes == nullptr || start == nullptr || end == nullptr || half_extents == nullptr)
    return Null("drape_shapes_add_box", "shapes, start, end or half_extents");
  return Guarded("drape_shapes_add_box", [&] {
    return FromStatus(shapes->shapes.AddBox(AsMatrix(start), AsMatrix(end),
                                            {half_extents[0], half_extents[1], half_extents[2]}));
  });
}

// ---- Cloth ------------------------------------------------------------------------------------

void drape_cloth_desc_default(drape_cloth_desc* desc) {
  if (desc == nullptr) return;
  const drape::ClothDescription d;
  *desc = drape_cloth_desc{};
  desc->density = d.density;
  desc->stretch_stiffness = d.stretch.stiffness;
  desc->stretch_damping = d.stretch.damping;
  desc->bend_stiffness = d.bend.stiffness;
  desc->bend_damping = d.bend.damping;
  desc->tethers = d.tethers ? 1 : 0;
  desc->tether_stretch = d.tether_stretch;
}

void drape_solver_settings_default(drape_solver_settings* settings) {
  if (settings == nullptr) return;
  const drape::ClothSolverSettings s;
  const drape::ResponseParams r;
  *settings = drape_solver_settings{};
  settings->substeps = s.substeps;
  settings->iterations = s.iterations;
  settings->gravity[0] = s.gravity.x;
  settings->gravity[1] = s.gravity.y;
  settings->gravity[2] = s.gravity.z;
  settings->damping = s.damping;
  settings->max_stretch = std::isinf(s.max_stretch) ? -1.f : s.max_stretch;
  settings->tethers = s.tethers ? 1 : 0;
  settings->root_joint = s.root_joint;
  settings->linear_inertia = s.linear_inertia;
  settings->angular_inertia = s.angular_inertia;
  settings->centrifugal_inertia = s.centrifugal_inertia;
  settings->friction = r.friction;
  settings->static_friction = r.static_friction;
  settings->restitution = r.restitution;
  settings->separation = r.separation;
  settings->measure_stretch = s.measure_stretch ? 1 : 0;
  settings->guard_blowups = s.guard_blowups ? 1 : 0;
}

drape_status drape_cloth_create(const drape_cloth_desc* desc, const drape_solver_settings* settings,
                                drape_cloth** out_cloth) {
  constexpr const char* kName = "drape_cloth_create";
  if (desc == nullptr) return Null(kName, "desc");
  if (settings == nullptr) return Null(kName, "settings");
  if (out_cloth == nullptr) return Null(kName, "out_cloth");
  if (desc->positions == nullptr && desc->particle_count > 0) return Null(kName, "desc->positions");
  if (desc->triangles == nullptr && desc->triangle_count > 0) return Null(kName, "desc->triangles");
  if (desc->pinned == nullptr && desc->pinned_count > 0) return Null(kName, "desc->pinned");
  if ((desc->skin_joints == nullptr) != (desc->skin_weights == nullptr))
    return Fail(DRAPE_INVALID_ARGUMENT,
                "drape_cloth_create: desc->skin_joints and desc->skin_weights go together");
  return Guarded(kName, [&] {
    auto* c = new drape_cloth;
    c->response = Response(*settings);
    drape_status s = FromStatus(drape::BuildCloth(Describe(*desc), &c->cloth));
    if (s == DRAPE_OK) s = FromStatus(c->solver.Init(c->cloth, SolverSettings(*settings)));
    if (s == DRAPE_OK && !drape::ValidResponse(c->response))
      s = Fail(DRAPE_INVALID_ARGUMENT,
               "drape_cloth_create: friction in [0, 1], static_friction in [0, 4], restitution "
               "in [0, 1], separation finite and >= 0");
    if (s != DRAPE_OK) {
      delete c;
      return s;
    }
    c->state.Reset(c->cloth);
    *out_cloth = c;
    return DRAPE_OK;
  });
}

void drape_cloth_destroy(drape_cloth* cloth) { delete cloth; }

uint32_t drape_cloth_particle_count(const drape_cloth* cloth) {
  return cloth != nullptr ? cloth->cloth.particle_count() : 0;
}

const float* drape_cloth_positions(const drape_cloth* cloth) {
  return cloth != nullptr ? &cloth->state.positions.data()->x : nullptr;
}

const float* drape_cloth_velocities(const drape_cloth* cloth) {
  return cloth != nullptr ? &cloth->state.velocities.data()->x : nullptr;
}

drape_status drape_cloth_reset(drape_cloth* cloth, const float* skinning, uint32_t joint_count,
                               drape_colliders* colliders, const drape_shapes* shapes) {
  if (cloth == nullptr) return Null("drape_cloth_reset", "cloth");
  if (skinning == nullptr && joint_count > 0) return Null("drape_cloth_reset", "skinning");
  drape::ClothColliders hit;
  hit.hulls = colliders != nullptr ? &colliders->hulls : nullptr;
  hit.shapes = shapes != nullptr ? &shapes->shapes : nullptr;
  hit.response = cloth->response;
  return FromStatus(cloth->solver.Reset(&cloth->state, hit, AsMatrices(skinning, joint_count)));
}

drape_status drape_cloth_step(drape_cloth* cloth, float dt, const float* skinning_start,
                              const float* skinning_end, uint32_t joint_count,
                              drape_colliders* colliders, const drape_shapes* shapes,
                              drape_step_stats* stats) {
  if (cloth == nullptr) return Null("drape_cloth_step", "cloth");
  if ((skinning_start == nullptr || skinning_end == nullptr) && joint_count > 0)
    return Null("drape_cloth_step", "skinning_start or skinning_end");
  drape::ClothColliders hit;
  hit.hulls = colliders != nullptr ? &colliders->hulls : nullptr;
  hit.shapes = shapes != nullptr ? &shapes->shapes : nullptr;
  hit.response = cloth->response;
  drape::ClothFrame frame;
  frame.dt = dt;
  frame.skinning_start = AsMatrices(skinning_start, joint_count);
  frame.skinning_end = AsMatrices(skinning_end, joint_count);
  drape::ClothStepStats st;
  const drape_status s = FromStatus(cloth->solver.Step(&cloth->state, hit, frame, &st));
  if (stats != nullptr) {
    stats->substeps = st.substeps;
    stats->contacts = st.contacts;
    stats->hull_contacts = st.hull_contacts;
    stats->shape_contacts = st.shape_contacts;
    stats->max_stretch = st.max_stretch;
    stats->overstretched_springs = st.overstretched_springs;
  }
  return s;
}

drape_status drape_cloth_teleport(drape_cloth* cloth, const float transform[12]) {
  if (cloth == nullptr) return Null("drape_cloth_teleport", "cloth");
  if (transform == nullptr) return Null("drape_cloth_teleport", "transform");
  return FromStatus(cloth->solver.Teleport(&cloth->state, AsMatrix(transform)));
}

}  // extern "C"
