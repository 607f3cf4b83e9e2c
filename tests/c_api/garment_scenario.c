/* The C API driven from C: see garment_scenario.h. */
#include "garment_scenario.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "drape/drape.h"

void scenario_skirt_mesh(const float top[3], float radius, float length, float* positions,
                         uint32_t* triangles) {
  const float kTwoPi = 6.2831853f;
  for (int ring = 0; ring <= kScenarioRings; ++ring) {
    const float down = length * (float)ring / (float)kScenarioRings;
    const float r = radius + 0.35f * down; /* flares towards the hem */
    for (int s = 0; s < kScenarioSegments; ++s) {
      const float angle = kTwoPi * (float)s / (float)kScenarioSegments;
      float* p = positions + 3 * (ring * kScenarioSegments + s);
      p[0] = top[0] + r * cosf(angle);
      p[1] = top[1] - down;
      p[2] = top[2] + r * sinf(angle);
    }
  }
  uint32_t* t = triangles;
  for (int ring = 0; ring < kScenarioRings; ++ring) {
    for (int s = 0; s < kScenarioSegments; ++s) {
      const uint32_t a = (uint32_t)(ring * kScenarioSegments + s);
      const uint32_t b = (uint32_t)(ring * kScenarioSegments + (s + 1) % kScenarioSegments);
      const uint32_t c = a + kScenarioSegments, d = b + kScenarioSegments;
      t[0] = a, t[1] = c, t[2] = b;
      t[3] = b, t[4] = c, t[5] = d;
      t += 6;
    }
  }
}

void scenario_staff(const float root[12], int frame, float out[12]) {
  static const float kIdentity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  memcpy(out, kIdentity, sizeof(kIdentity));
  out[3] = root[3] + 0.4f * sinf(0.05f * (float)frame);
  out[7] = root[7] * 0.5f;
  out[11] = root[11] + 0.25f;
}

/* Everything the scenario creates, destroyed in one place. */
typedef struct Scenario {
  drape_asset* asset;
  drape_pose* pose;
  drape_colliders* colliders;
  drape_shapes* shapes;
  drape_cloth* cloth;
} Scenario;

static void destroy(Scenario* s) {
  drape_cloth_destroy(s->cloth);
  drape_shapes_destroy(s->shapes);
  drape_colliders_destroy(s->colliders);
  drape_pose_destroy(s->pose);
  drape_asset_destroy(s->asset);
}

static drape_status create_cloth(Scenario* s, const float root[12]) {
  static float positions[3 * kScenarioParticles];
  static uint32_t triangles[3 * kScenarioTriangles];
  static uint32_t joints[4 * kScenarioParticles];
  static float weights[4 * kScenarioParticles];
  static float max_distance[kScenarioParticles];
  const float top[3] = {root[3], root[7] + 0.03f, root[11]};
  scenario_skirt_mesh(top, 0.19f, 0.6f, positions, triangles);
  for (int i = 0; i < kScenarioParticles; ++i) {
    joints[4 * i] = joints[4 * i + 1] = joints[4 * i + 2] = joints[4 * i + 3] = 0;
    weights[4 * i] = 1.f;
    weights[4 * i + 1] = weights[4 * i + 2] = weights[4 * i + 3] = 0.f;
    max_distance[i] = i < kScenarioSegments ? 0.f : 0.15f; /* the waistband follows the skin */
  }
  drape_cloth_desc desc;
  drape_cloth_desc_default(&desc);
  desc.positions = positions;
  desc.particle_count = kScenarioParticles;
  desc.triangles = triangles;
  desc.triangle_count = kScenarioTriangles;
  desc.skin_joints = joints;
  desc.skin_weights = weights;
  desc.max_distance = max_distance;
  drape_solver_settings settings;
  drape_solver_settings_default(&settings);
  settings.substeps = 2;
  settings.friction = 0.3f;
  return drape_cloth_create(&desc, &settings, &s->cloth);
}

int scenario_run(const char* asset_path, int frames, float* out_positions, uint32_t* out_contacts,
                 uint32_t* out_overstretched) {
  Scenario s = {NULL, NULL, NULL, NULL, NULL};
  drape_status status = drape_asset_load(asset_path, &s.asset);
  if (status == DRAPE_OK) status = drape_pose_create(s.asset, &s.pose);
  if (status == DRAPE_OK) status = drape_colliders_create(s.asset, &s.colliders);
  if (status == DRAPE_OK)
    status = drape_shapes_create(2 + drape_asset_capsule_count(s.asset), &s.shapes);
  float root[12];
  if (status == DRAPE_OK) status = drape_asset_bind_matrix(s.asset, 0, root);
  if (status == DRAPE_OK) status = create_cloth(&s, root);
  if (status != DRAPE_OK) {
    destroy(&s);
    return (int)status;
  }
  const uint32_t joints = drape_asset_joint_count(s.asset);
  enum { kMaxJoints = 256 };
  static float start[12 * kMaxJoints], end[12 * kMaxJoints];
  if (joints > kMaxJoints) {
    destroy(&s);
    return (int)DRAPE_INVALID_ARGUMENT;
  }
  const float floor[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  const float dt = 1.f / 60.f;
  drape_step_stats stats;
  memset(&stats, 0, sizeof(stats));
  for (int frame = 0; frame <= frames && status == DRAPE_OK; ++frame) {
    status = drape_pose_sample_clip(s.pose, 0, (float)frame * dt, 1);
    if (status != DRAPE_OK) break;
    memcpy(end, drape_pose_skinning(s.pose), sizeof(float) * 12 * joints);
    if (frame == 0) {
      memcpy(start, end, sizeof(float) * 12 * joints);
      status = drape_cloth_reset(s.cloth, end, joints, NULL, NULL);
      continue;
    }
    float staff_start[12], staff_end[12];
    scenario_staff(root, frame - 1, staff_start);
    scenario_staff(root, frame, staff_end);
    drape_shapes_clear(s.shapes);
    status = drape_shapes_add_plane(s.shapes, floor, floor);
    if (status == DRAPE_OK)
      status = drape_shapes_add_capsule(s.shapes, staff_start, staff_end, 0.3f, 0.03f, 0.03f);
    if (status == DRAPE_OK) status = drape_shapes_add_asset_capsules(s.shapes, s.asset, start, end);
    if (status == DRAPE_OK)
      status = drape_cloth_step(s.cloth, dt, start, end, joints, s.colliders, s.shapes, &stats);
    memcpy(start, end, sizeof(float) * 12 * joints);
  }
  if (status == DRAPE_OK) {
    memcpy(out_positions, drape_cloth_positions(s.cloth), sizeof(float) * 3 * kScenarioParticles);
    *out_contacts = stats.contacts;
    *out_overstretched = stats.overstretched_springs;
  }
  destroy(&s);
  return (int)status;
}
