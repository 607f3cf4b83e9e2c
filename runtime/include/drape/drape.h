/* drape's runtime as a C API, for engines and languages that bind C (C#, Rust, Python ctypes).
 * Opaque handles, plain arrays, status codes; the same code and the same bits as the C++ API.
 *
 *   drape_asset* asset;       drape_asset_load("hero.drape", &asset);
 *   drape_pose* pose;         drape_pose_create(asset, &pose);
 *   drape_colliders* body;    drape_colliders_create(asset, &body);   // baked hulls + spheres
 *   drape_cloth_desc desc;    drape_cloth_desc_default(&desc);  desc.positions = ...;
 *   drape_solver_settings s;  drape_solver_settings_default(&s);
 *   drape_cloth* cloth;       drape_cloth_create(&desc, &s, &cloth);
 *   // every frame (no allocation):
 *   drape_pose_set_world_matrices(pose, engine_bones, joint_count);
 *   memcpy(end, drape_pose_skinning(pose), joint_count * 12 * sizeof(float));
 *   drape_cloth_step(cloth, dt, start, end, joint_count, body, shapes, NULL);
 *   const float* xyz = drape_cloth_positions(cloth);
 *
 * Conventions. Metres, seconds, a right-handed frame with +y up (the asset's). A matrix is 12
 * floats: a 3x4 row-major affine transform, rows (r00 r01 r02 tx), (r10 r11 r12 ty),
 * (r20 r21 r22 tz). Positions are 3 floats per particle. Every function that can fail returns a
 * drape_status; DRAPE_OK is 0, and drape_last_error() then holds the message of this thread's
 * last failure, naming the input and the reason. Nothing is written on failure, except where a
 * function says so. Handles are not thread-safe: one thread at a time per handle. The runtime
 * runs its own stages in parallel through the task system (drape_set_task_system). */
#ifndef DRAPE_DRAPE_H_
#define DRAPE_DRAPE_H_

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The values of drape::StatusCode, plus DRAPE_OUT_OF_MEMORY. */
typedef enum drape_status {
  DRAPE_OK = 0,
  DRAPE_IO_ERROR = 1,            /* the file could not be opened or read */
  DRAPE_BAD_MAGIC = 2,           /* not a .drape file */
  DRAPE_UNSUPPORTED_VERSION = 3, /* a format version this build does not know */
  DRAPE_TRUNCATED = 4,
  DRAPE_TRAILING_BYTES = 5,
  DRAPE_CHECKSUM_MISMATCH = 6,
  DRAPE_CORRUPT = 7,          /* a count, index or value out of range in the file */
  DRAPE_INVALID_ARGUMENT = 8, /* a caller-supplied value out of its documented range */
  DRAPE_INVALID_STATE = 9,    /* e.g. a non-finite particle handed to the solver */
  DRAPE_OUT_OF_MEMORY = 100
} drape_status;

/* The message of the calling thread's last failed call ("" before any failure). */
const char* drape_last_error(void);

/* ---- Task system ----------------------------------------------------------------------------
 * parallel_for(chunk_count, run, context, user) must call run(context, c) exactly once for every
 * c in [0, chunk_count), on any threads in any order, and return when all calls have returned.
 * worker_count (>= 1) is a hint for stages without a natural chunk size. parallel_for NULL
 * restores the default (OpenMP's team when the runtime was built with it, else one thread). Set
 * it at start-up, while no drape call runs. */
typedef void (*drape_task_fn)(void* context, uint32_t chunk);
typedef void (*drape_parallel_for_fn)(uint32_t chunk_count, drape_task_fn run, void* context,
                                      void* user);
void drape_set_task_system(drape_parallel_for_fn parallel_for, uint32_t worker_count, void* user);

/* ---- Asset: a loaded .drape file --------------------------------------------------------------
 * The file is checked like every input: a corrupt, truncated or newer file fails with its
 * reason. The asset must outlive every handle created from it. */
typedef struct drape_asset drape_asset;
drape_status drape_asset_load(const char* path, drape_asset** out_asset);
void drape_asset_destroy(drape_asset* asset); /* NULL is ignored */
uint32_t drape_asset_joint_count(const drape_asset* asset);
/* The joint's index, or -1 when the skeleton has no joint of that name. */
int32_t drape_asset_find_joint(const drape_asset* asset, const char* name);
uint32_t drape_asset_clip_count(const drape_asset* asset);
float drape_asset_clip_duration(const drape_asset* asset, uint32_t clip); /* seconds; 0 if none */
/* The joint's world matrix in the bind pose (the inverse of its inverse bind matrix). */
drape_status drape_asset_bind_matrix(const drape_asset* asset, uint32_t joint, float out[12]);

/* ---- Pose: the skeleton's world and skinning matrices ------------------------------------------
 */
typedef struct drape_pose drape_pose;
drape_status drape_pose_create(const drape_asset* asset, drape_pose** out_pose);
void drape_pose_destroy(drape_pose* pose);
/* The engine's joint world matrices (asset frame), joint_count * 12 floats, finite. */
drape_status drape_pose_set_world_matrices(drape_pose* pose, const float* world,
                                           uint32_t joint_count);
/* Samples one of the asset's clips at `time` seconds (wrapped when loop != 0, else clamped). */
drape_status drape_pose_sample_clip(drape_pose* pose, uint32_t clip, float time, int loop);
/* joint_count * 12 floats, valid until the next call on this pose: world * inverse bind
 * (what drape_cloth_step takes), and the joints' world matrices. */
const float* drape_pose_skinning(const drape_pose* pose);
const float* drape_pose_world(const drape_pose* pose);

/* ---- Baked colliders: the asset's convex hulls and joint spheres -------------------------------
 */
typedef struct drape_colliders drape_colliders;
drape_status drape_colliders_create(const drape_asset* asset, drape_colliders** out_colliders);
void drape_colliders_destroy(drape_colliders* colliders);

/* ---- The engine's own shapes, re-posed every frame ---------------------------------------------
 * start and end: shape frame -> world at the frame's start and end, rigid (rotation and
 * translation). Room for shape_capacity shapes is allocated at creation; clear keeps it. */
typedef struct drape_shapes drape_shapes;
drape_status drape_shapes_create(uint32_t shape_capacity, drape_shapes** out_shapes);
void drape_shapes_destroy(drape_shapes* shapes);
void drape_shapes_clear(drape_shapes* shapes);
drape_status drape_shapes_add_sphere(drape_shapes* shapes, const float start[12],
                                     const float end[12], float radius);
/* A tapered capsule along local x: radius0 at x = -half_length, radius1 at +half_length. */
drape_status drape_shapes_add_capsule(drape_shapes* shapes, const float start[12],
                                      const float end[12], float half_length, float radius0,
                                      float radius1);
/* The half-space local y <= 0 (a floor when the transforms are identities). */
drape_status drape_shapes_add_plane(drape_shapes* shapes, const float start[12],
                                    const float end[12]);
drape_status drape_shapes_add_box(drape_shapes* shapes, const float start[12], const float end[12],
                                  const float half_extents[3]);
/* The asset's baked tapered capsules (one per bone that carries skin), posed by the skinning
 * matrices at the frame's start and end (joint_count * 12 floats each, e.g. drape_pose_skinning):
 * drape_asset_capsule_count() shapes more. */
uint32_t drape_asset_capsule_count(const drape_asset* asset);
drape_status drape_shapes_add_asset_capsules(drape_shapes* shapes, const drape_asset* asset,
                                             const float* skinning_start,
                                             const float* skinning_end);

/* ---- Cloth: a garment, its solver and its state ------------------------------------------------
 */
typedef struct drape_cloth_desc {
  const float* positions; /* particle_count * 3, the rest shape (metres) */
  uint32_t particle_count;
  const uint32_t* triangles; /* triangle_count * 3 particle indices */
  uint32_t triangle_count;
  const uint32_t* pinned; /* particles only the caller moves (may be NULL) */
  uint32_t pinned_count;
  /* A skinned garment (NULL: not skinned): per particle 4 joints and 4 weights (summing to
   * more than 0), placed in the bind pose at `positions`. */
  const uint32_t* skin_joints;
  const float* skin_weights;
  const float* max_distance; /* per particle, metres (0: follows the skin exactly); may be NULL */
  const float* backstop;     /* per particle, metres behind the skinned surface; may be NULL */
  float density;             /* kg/m^2 */
  float stretch_stiffness, stretch_damping, bend_stiffness, bend_damping; /* N/m, N*s/m */
  int tethers;          /* long-range tethers to the kinematic particles (0: none) */
  float tether_stretch; /* allowed stretch beyond the geodesic length, >= 0 */
} drape_cloth_desc;
void drape_cloth_desc_default(drape_cloth_desc* desc); /* no arrays, drape's default materials */

typedef struct drape_solver_settings {
  uint32_t substeps;   /* per frame, [1, 256] */
  uint32_t iterations; /* spring passes per substep, [1, 256] */
  float gravity[3];    /* m/s^2 */
  float damping;       /* 1/s */
  float max_stretch;   /* strain limit of stretch springs; a negative value: none */
  int tethers;         /* apply the cloth's tethers */
  int32_t root_joint;  /* -1: none; needed for inertia below 1 */
  float root_bind_position[3];
  float linear_inertia, angular_inertia, centrifugal_inertia; /* [0, 1] */
  /* The contact response. */
  float friction;        /* kinetic, [0, 1] */
  float static_friction; /* [0, 4] */
  float restitution;     /* [0, 1] */
  float separation;      /* metres kept off the surfaces, >= 0 */
  int measure_stretch;   /* report drape_step_stats.max_stretch (a pass over the springs) */
  int guard_blowups;     /* back up and check each substep: a blow-up stops the step */
} drape_solver_settings;
void drape_solver_settings_default(drape_solver_settings* settings);

typedef struct drape_step_stats {
  uint32_t substeps;       /* completed */
  uint32_t contacts;       /* particles in contact in the last substep */
  uint32_t hull_contacts;  /* summed over substeps */
  uint32_t shape_contacts; /* summed over substeps */
  float max_stretch;       /* after the step: max over stretch springs of L / R - 1 */
  /* After the step: stretch springs beyond the strain limit (10 % without one). */
  uint32_t overstretched_springs;
} drape_step_stats;

typedef struct drape_cloth drape_cloth;
drape_status drape_cloth_create(const drape_cloth_desc* desc, const drape_solver_settings* settings,
                                drape_cloth** out_cloth);
void drape_cloth_destroy(drape_cloth* cloth);
uint32_t drape_cloth_particle_count(const drape_cloth* cloth);
/* particle_count * 3 floats, valid until the next call on this cloth. */
const float* drape_cloth_positions(const drape_cloth* cloth);
const float* drape_cloth_velocities(const drape_cloth* cloth);
/* Places the cloth at the pose (skinned garments on their skin, attachments on their joints),
 * then pushes out of the colliders (each may be NULL) whatever lies inside. */
drape_status drape_cloth_reset(drape_cloth* cloth, const float* skinning, uint32_t joint_count,
                               drape_colliders* colliders, const drape_shapes* shapes);
/* Advances the cloth by dt seconds, the skeleton moving from skinning_start to skinning_end
 * (joint_count * 12 floats each). colliders and shapes may be NULL; stats may be NULL. On a
 * failed step the state is left at the end of the last valid substep (see the C++ Step). */
drape_status drape_cloth_step(drape_cloth* cloth, float dt, const float* skinning_start,
                              const float* skinning_end, uint32_t joint_count,
                              drape_colliders* colliders, const drape_shapes* shapes,
                              drape_step_stats* stats);
/* Moves the whole cloth rigidly with a teleporting character. */
drape_status drape_cloth_teleport(drape_cloth* cloth, const float transform[12]);

#ifdef __cplusplus
}
#endif

#endif /* DRAPE_DRAPE_H_ */
