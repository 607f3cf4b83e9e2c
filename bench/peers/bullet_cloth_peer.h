#pragma once
// Bullet's soft-body cloth as the simulation peer of drape's ClothSolver (issues #5, #6): a
// btSoftBody built from the garment's triangle mesh (one link per triangle edge plus Bullet's
// distance-2 bending links), in a btSoftRigidDynamicsWorld, against kinematic convex hulls
// (btConvexHullShape) and spheres (btSphereShape) that the caller poses every frame.
//
// How it maps onto Bullet (single-threaded, deterministic: no random seeds, no threads):
// - Solver: Bullet's position-based soft body solver (eSolverPresets::Positions: per iteration
//   anchors, rigid contacts, soft contacts, then links), `iterations` passes (piterations) per
//   step, velocity damping kDP, gravity through btSoftBodyWorldInfo.
// - Attached particles (inverse mass 0): Bullet node mass 0, moved kinematically. Before each
//   substep the node's velocity is set to (target - position) / h, so Bullet's own integration
//   carries it exactly to its target and the links see its motion; after the step the position
//   is snapped to the target (removing the rounding of x + v h). Anchors (appendAnchor) are the
//   alternative, but they pull with a hardness kAHR < 1 and need one rigid body per joint.
// - Colliders: one kinematic btRigidBody per hull or sphere (CF_KINEMATIC_OBJECT,
//   DISABLE_DEACTIVATION, a btDefaultMotionState updated each substep), so Bullet derives their
//   linear and angular velocity from the previous transform (used for friction). Colliders do not
//   collide with one another (collision filter groups), as in drape.
// - Collision: see BulletClothCollision. SDF_RS (node against a signed distance field of each
//   shape) is the default because it is the one that holds the cloth: on a 0.6 m sheet dropped
//   onto a 0.2 m box (BulletClothPeer.SheetOnBoxIsHeld) SDF_RS keeps it on the box with nodes at most 2.1 cm
//   inside, while CL_RS (one cluster per triangle against the shape by GJK) lets the whole sheet
//   fall through within 40 frames; k-means clusters would be worse still for cloth wrapped round
//   a limb (a cluster's convex hull spans the limb). Both are discrete: a particle that crosses a
//   thin limb in one step is not caught.
// - Where Bullet's cloth ends up inside: contacts are found once per step at the predicted node
//   positions, each iteration solves them before the links (so the last link pass can pull nodes
//   back in), and a contact only corrects a node still moving inwards. Solving contacts after
//   the links instead was worse (the sheet slid off the box).
// - Tuned away from Bullet's defaults, which are for other scales: the soft body margin (default
//   0.25 m) is `collision_margin`; the hull margin (default 0.04 m) is 0, so the hull is the
//   hull; the SDF voxel (default 0.25 m, bigger than a shin) is `sdf_voxel_size`, with 65521
//   hash buckets and a cap of 2^20 cells (defaults 2383 and 2^18, too few for 5 mm voxels); the
//   kinematic contact hardness kKHR (default 0.1: a tenth of the penetration removed per pass,
//   with which the sheet sinks through the box) is `kinematic_contact_hardness`.
// Benchmark-side code: Build allocates (generateBendingConstraints builds an n x n int adjacency
// matrix: 400 MB for the 10 100-particle skirt, freed before Build returns); Step allocates only
// inside Bullet (contact arrays grow to their high-water mark, SDF cells are built on first
// touch, CL_RS allocates a joint per contact).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "drape/formats/status.h"
#include "drape/formats/types.h"

namespace drape::peers {

enum class BulletClothCollision : uint8_t {
  // fCollision::SDF_RS (Bullet's default): each node against a signed distance field of each
  // convex shape, sampled lazily on a sparse voxel grid in the shape's frame (btSparseSdf) and
  // trilinearly interpolated; contacts are found once per step at the predicted positions and
  // solved in every iteration.
  kSdfRigidSoft = 0,
  // fCollision::CL_RS: every triangle is a cluster (a small rigid body), tested against each
  // shape with GJK/EPA and resolved by impulses on the cluster (citerations passes).
  kClusterRigidSoft = 1,
};

struct BulletClothSetup {
  std::vector<Float3> positions;      // rest positions, metres (link rest lengths come from them)
  std::vector<uint32_t> triangles;    // 3 indices per triangle, every particle in one triangle
  std::vector<float> inverse_masses;  // 1/kg per particle; 0 = attached: driven to a target
  float gravity_y = -9.81f;           // m/s^2
  // Bullet kDP in [0, 1): the velocity fraction lost per substep (the skirt benchmark converts
  // drape's 0.2 1/s to 1 - exp(-0.2 h) for substeps of h seconds).
  float damping = 0.2f;
  float friction = 0.3f;            // Bullet kDF in [0, 1] (the colliders' own friction is 1)
  uint32_t iterations = 5;          // position solver passes per substep (piterations), >= 1
  uint32_t substeps = 1;            // Bullet steps per Step, >= 1
  float collision_margin = 0.002f;  // metres, > 0: the soft body's collision margin
  // Further tuning (defaults are the skirt benchmark's values; see the file comment):
  float stretch_stiffness = 1.f;           // kLST of the edge links in (0, 1]: 1 = full correction
  float bend_stiffness = 0.2f;             // kLST of the distance-2 bending links in (0, 1]
  float kinematic_contact_hardness = 1.f;  // kKHR in (0, 1]: penetration fraction removed per pass
  float sdf_voxel_size = 0.005f;           // metres, > 0 (SDF_RS only)
  BulletClothCollision collision = BulletClothCollision::kSdfRigidSoft;
};

// A convex collider: the vertices of its hull in the shape's local frame (metres). Bullet takes
// the hull of these points (btConvexHullShape), margin 0.
struct BulletHullShape {
  std::vector<Float3> local_vertices;
};

class BulletClothPeer {
 public:
  BulletClothPeer();
  ~BulletClothPeer();
  BulletClothPeer(const BulletClothPeer&) = delete;
  BulletClothPeer& operator=(const BulletClothPeer&) = delete;

  // Builds the world (replacing any previous one). kInvalidArgument naming the field for: no
  // particles or more than 46340 (see generateBendingConstraints above), a triangle count not a
  // multiple of 3, an index out of range, a particle in no triangle, inverse masses of the wrong
  // count or negative or non-finite, a value out of its range above, a hull with fewer than 4
  // vertices, a sphere radius not finite and > 0. Hulls start at the identity transform and spheres
  // at the origin (see SetInitialPose).
  Status Build(const BulletClothSetup& setup, std::span<const BulletHullShape> hulls,
               std::span<const float> sphere_radii);

  // Places the colliders without velocity (the pose before the first Step). Without it the
  // first Step moves them from the identity / the origin, which Bullet reads as a fast motion.
  Status SetInitialPose(std::span<const Mat34> hull_world, std::span<const Float3> sphere_centres);

  // One frame of dt seconds (> 0): the hulls' world transforms (rigid: rotation + translation),
  // the sphere centres and the attached particles' targets (one per particle with inverse mass
  // 0, in index order), all at the END of the frame. Within the frame, substep s of n sees the
  // colliders and targets interpolated at (s + 1) / n between the previous frame's values and
  // these (rotations by quaternion slerp), so Bullet derives their velocities. kInvalidArgument
  // when a count does not match Build or dt is not finite and > 0, kInvalidState before Build.
  Status Step(std::span<const Mat34> hull_world, std::span<const Float3> sphere_centres,
              std::span<const Float3> attached_targets, float dt);

  // Particle positions (metres) in input order, the first min(out.size(), particle_count()).
  void CopyPositions(std::span<Float3> out) const;
  size_t particle_count() const;
  size_t attached_count() const;
  size_t link_count() const;  // stretch + bending links
  // Node-vs-shape contacts Bullet generated in the last substep (SDF_RS; always 0 for CL_RS,
  // whose contact joints are freed within the step).
  size_t last_contact_count() const;
  // Cells of Bullet's sparse SDF built so far (SDF_RS): each costs 64 GJK distance queries.
  size_t sdf_cell_count() const;

 private:
  struct World;
  std::unique_ptr<World> world_;
};

}  // namespace drape::peers
