#pragma once
// Colliders a game engine hands the cloth every frame: spheres, tapered capsules, planes, boxes
// and convexes, each with its rigid transform at the start and at the end of the frame. Particle
// motion segments are tested continuously against every shape in the shape's own frame, and a
// contact gets a Coulomb response relative to the shape's moving surface. How it works:
// docs/ALGORITHMS.md §14.
//
//   ShapeColliderSet shapes;
//   shapes.Reserve(32, 256);                                // once: allocates
//   // every frame:
//   shapes.Clear();                                         // keeps the capacity
//   shapes.AddSphere(head_at_frame_start, head_at_frame_end, 0.11f);
//   shapes.AddPlane(floor, floor);
//   // every substep [s0, s1] of the frame, h seconds long:
//   shapes.CollideBatch(previous, positions, velocities, flags, params, s0, s1, h);
//
// Transforms are shape frame -> world, rotation and translation only (no scale or shear: the
// columns of the 3x3 part orthonormal within 1e-3, determinant +1). Within the frame a shape's
// translation moves linearly and its rotation by nlerp, from `start` at fraction 0 to `end` at 1.

#include <cstdint>
#include <span>
#include <vector>

#include "drape/formats/hull_collider_data.h"
#include "drape/formats/status.h"
#include "drape/formats/types.h"
#include "drape/runtime/collision_types.h"

namespace drape {

enum class ShapeKind : uint8_t { kSphere = 0, kCapsule = 1, kPlane = 2, kBox = 3, kConvex = 4 };

// The shapes of one frame. Add* validate and copy; CollideBatch and Query are const,
// allocation-free and thread-safe.
class ShapeColliderSet {
 public:
  // A convex has 4 to kMaxConvexPlanes planes and lies within kMaxConvexExtent metres of its
  // local origin (anything larger is reported as unbounded).
  static constexpr uint32_t kMaxConvexPlanes = 256;
  static constexpr double kMaxConvexExtent = 1e4;  // metres
  // Columns of a transform's 3x3 part are unit and orthogonal within this (dot products).
  static constexpr double kRigidTolerance = 1e-3;
  // After the Gauss-Seidel pass over the shapes, a particle in contact that ended more than this
  // deep inside a shape (metres) is resolved against it once more.
  static constexpr double kSecondPassDepth = 1e-5;

  // Setup (allocates): room for `shapes` shapes and `planes` convex planes in total.
  void Reserve(uint32_t shapes, uint32_t planes);
  // Removes every shape and keeps the capacity: re-adding as many shapes and planes as before
  // allocates nothing.
  void Clear();

  // start, end: shape frame -> world at the start and the end of the frame (rigid, finite). Each
  // Add validates and returns kInvalidArgument naming the shape (the index it would get) and the
  // field; nothing is added on error. Beyond the reserved capacity an Add allocates.
  //
  // A sphere centred on the local origin. radius: metres, finite, > 0.
  Status AddSphere(const Mat34& start, const Mat34& end, float radius);
  // A tapered capsule (round cone: the convex hull of two spheres) along local x: a sphere of
  // radius0 centred at x = -half_length and one of radius1 at x = +half_length. half_length:
  // metres, finite, >= 0; radius0, radius1: metres, finite, > 0. When one sphere holds the
  // other, the shape is that sphere.
  Status AddCapsule(const Mat34& start, const Mat34& end, float half_length, float radius0,
                    float radius1);
  // The solid half-space local y <= 0 (local +y is the outward normal), e.g. a floor.
  Status AddPlane(const Mat34& start, const Mat34& end);
  // A box centred on the local origin, its faces normal to the local axes. half_extents:
  // metres, each finite and > 0.
  Status AddBox(const Mat34& start, const Mat34& end, Float3 half_extents);
  // A convex polytope: inside where normal . x <= offset for every local plane. 4 to
  // kMaxConvexPlanes planes, unit normals (within 1e-3; renormalised), finite offsets in metres,
  // enclosing a non-empty region within kMaxConvexExtent of the local origin. A convex of no
  // volume (all its points on one plane) collides with nothing.
  Status AddConvex(const Mat34& start, const Mat34& end, std::span<const Plane> planes);

  uint32_t size() const { return static_cast<uint32_t>(shapes_.size()); }
  bool empty() const { return shapes_.empty(); }
  ShapeKind kind(uint32_t shape) const { return shapes_[shape].kind; }
  uint32_t plane_count() const { return static_cast<uint32_t>(planes_.size()); }  // all convexes
  uint32_t shape_capacity() const { return static_cast<uint32_t>(shapes_.capacity()); }
  uint32_t plane_capacity() const { return static_cast<uint32_t>(planes_.capacity()); }
  // Shape frame -> world at fraction s of the frame, in [0, 1].
  Mat34 WorldTransform(uint32_t shape, float s) const;

  // One substep: the fractions [s0, s1] of the frame (0 <= s0 <= s1 <= 1), substep_seconds long
  // (finite, > 0). Particle i moves x_start[i] -> x_end[i] while each shape moves from its pose
  // at s0 to its pose at s1. Shapes are tested continuously in index order, each seeing where the
  // previous one left the particle; a particle in contact that ends more than kSecondPassDepth
  // inside a shape meets that shape once more. A contact puts x_end[i] params.separation outside
  // the surface, its motion along the surface relative to the shape cut by friction
  // (params.friction_model), and gives velocities[i] (m/s) the response of collision_types.h
  // relative to the surface's velocity. flags[i] is always overwritten (CollisionFlags); a
  // non-finite input is flagged kCollisionInvalidInput and left untouched. Bound: one shape moves
  // a particle at most its motion relative to the shape + its depth in it + params.separation.
  // Spans of one size; params pass ValidResponse. No allocation; the same bits at any thread
  // count. contact_count: the particles with kCollisionContact.
  Status CollideBatch(std::span<const Float3> x_start, std::span<Float3> x_end,
                      std::span<Float3> velocities, std::span<uint8_t> flags,
                      const ResponseParams& params, float s0, float s1, float substep_seconds,
                      uint32_t* contact_count = nullptr) const;

  // The first contact (lowest t; the lower shape index on ties) of one segment p0 -> p1 over the
  // fractions [s0, s1], without response; point and normal in the world at s1. inside_end: p1 is
  // inside some shape, depth the deepest. A non-finite point or fractions outside
  // 0 <= s0 <= s1 <= 1 give flags kCollisionInvalidInput and no contact.
  ContactQuery Query(Float3 p0, Float3 p1, float s0, float s1) const;

 private:
  struct Shape {                              // 160 bytes
    double rotation_start[4] = {0, 0, 0, 1};  // unit quaternion (x, y, z, w)
    double rotation_end[4] = {0, 0, 0, 1};    // on the same hemisphere as rotation_start
    double translation_start[3] = {0, 0, 0};  // metres
    double translation_end[3] = {0, 0, 0};
    double bound_radius = 0.0;  // metres: a sphere about the local origin holding the shape
    float radius0 = 0.f;        // sphere: its radius; capsule: the sphere at -half_length
    float radius1 = 0.f;        // capsule: the sphere at +half_length
    float half_length = 0.f;    // capsule
    Float3 half_extents;        // box
    uint32_t plane_begin = 0, plane_count = 0;  // convex: its range of planes_
    ShapeKind kind = ShapeKind::kSphere;
  };
  struct Frames;  // shapes/shape_collider_set.cpp: a chunk of shapes posed over a substep

  // The checks every Add shares; on success fills the motion of *shape.
  Status ValidateMotion(const char* function, const Mat34& start, const Mat34& end,
                        Shape* shape) const;
  // Particles [first, last) of a batch against every shape, Gauss-Seidel then the second pass;
  // *frames: the calling thread's posed shapes. Returns the particles in contact.
  uint32_t CollideBlock(Frames* frames, size_t first, size_t last, std::span<const Float3> x_start,
                        std::span<Float3> x_end, std::span<Float3> velocities,
                        std::span<uint8_t> flags, const ResponseParams& params, float s0, float s1,
                        double substep_seconds) const;

  std::vector<Shape> shapes_;
  std::vector<Plane> planes_;  // convexes' local planes, unit normals
};

}  // namespace drape
