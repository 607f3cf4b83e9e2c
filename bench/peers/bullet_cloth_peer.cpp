#include "bullet_cloth_peer.h"

#include <BulletCollision/BroadphaseCollision/btDbvtBroadphase.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <BulletCollision/CollisionShapes/btSphereShape.h>
#include <BulletDynamics/ConstraintSolver/btSequentialImpulseConstraintSolver.h>
#include <BulletDynamics/Dynamics/btRigidBody.h>
#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <LinearMath/btDefaultMotionState.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace drape::peers {
namespace {

// Collision filter groups: the cloth collides with the colliders, the colliders not with each
// other (drape never tests a collider against a collider either).
constexpr int kClothGroup = 1 << 6;
constexpr int kColliderGroup = 1 << 7;

// The sparse SDF's cell hash table and cell cap. Bullet's defaults (2383 buckets, 256 Ki cells,
// all cells dropped when the cap is passed) suit its 0.25 m voxel. With 5 mm voxels the skirt
// benchmark's 20 colliders build about 250 000 cells (each 4^3 samples, ~300 bytes: ~75 MB) over
// the first seconds: the default chains grew long enough to take 60% of a frame (50 ms against
// 18.5 ms with these buckets), and the default cap would wipe and rebuild the whole field.
constexpr int kSdfHashBuckets = 65521;
constexpr int kSdfMaxCells = 1 << 20;

btVector3 ToBullet(Float3 p) { return btVector3(p.x, p.y, p.z); }

btTransform ToBullet(const Mat34& m) {
  const btMatrix3x3 basis(m.m[0], m.m[1], m.m[2], m.m[4], m.m[5], m.m[6], m.m[8], m.m[9], m.m[10]);
  return btTransform(basis, btVector3(m.m[3], m.m[7], m.m[11]));
}

// Rigid interpolation: translation linearly, rotation by slerp (the shorter arc).
btTransform Interpolate(const btTransform& a, const btTransform& b, btScalar t) {
  btQuaternion qa = a.getRotation(), qb = b.getRotation();
  if (qa.dot(qb) < 0) qb = -qb;
  return btTransform(qa.slerp(qb, t), a.getOrigin().lerp(b.getOrigin(), t));
}

bool Finite(float v) { return std::isfinite(v); }

Status Invalid(std::string message) {
  return Status(StatusCode::kInvalidArgument, "BulletClothPeer: " + message);
}

}  // namespace

// Owns the Bullet world and everything in it. Members are declared in construction order; the
// destructor takes the objects out of the world before the world goes (btCollisionWorld's
// destructor still touches the objects it holds).
struct BulletClothPeer::World {
  btSoftBodyRigidBodyCollisionConfiguration collision_configuration;
  btCollisionDispatcher dispatcher{&collision_configuration};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;  // rigid-body solver: idle (no dynamic bodies)
  std::unique_ptr<btSoftRigidDynamicsWorld> world;
  std::unique_ptr<btSoftBody> cloth;
  std::vector<std::unique_ptr<btCollisionShape>> shapes;  // hulls, then spheres
  std::vector<std::unique_ptr<btDefaultMotionState>> motion_states;
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  size_t hull_count = 0, sphere_count = 0;
  std::vector<int> attached;  // particles with inverse mass 0, ascending
  // The colliders' and targets' values at the end of the previous frame (the start of this one).
  std::vector<btTransform> previous_pose;   // per body
  std::vector<btVector3> previous_targets;  // per attached particle
  std::vector<btTransform> end_pose;        // per body: Step's scratch
  uint32_t substeps = 1;

  ~World() {
    if (world) {
      for (auto& body : bodies) world->removeRigidBody(body.get());
      if (cloth) world->removeSoftBody(cloth.get());
      world.reset();
    }
  }

  // Kinematic pose for the next Bullet step: the motion state is what saveKinematicState reads
  // (it then derives the body's velocity from its previous transform).
  void SetBodyPose(size_t body, const btTransform& pose) {
    motion_states[body]->setWorldTransform(pose);
  }
};

BulletClothPeer::BulletClothPeer() = default;
BulletClothPeer::~BulletClothPeer() = default;

Status BulletClothPeer::Build(const BulletClothSetup& setup, std::span<const BulletHullShape> hulls,
                              std::span<const float> sphere_radii) {
  world_.reset();
  const size_t n = setup.positions.size();
  if (n == 0) return Invalid("positions: no particles");
  // generateBendingConstraints indexes an n x n matrix with int (and allocates it: 4 n^2 bytes).
  if (n > 46340)
    return Invalid("positions: " + std::to_string(n) + " particles, more than the 46340 Bullet's " +
                   "bending-link generator can index");
  for (size_t i = 0; i < n; ++i) {
    const Float3 p = setup.positions[i];
    if (!Finite(p.x) || !Finite(p.y) || !Finite(p.z))
      return Invalid("positions[" + std::to_string(i) + "] is not finite");
  }
  if (setup.triangles.empty() || setup.triangles.size() % 3 != 0)
    return Invalid("triangles: count " + std::to_string(setup.triangles.size()) +
                   " is not a positive multiple of 3");
  std::vector<bool> used(n, false);
  for (size_t t = 0; t < setup.triangles.size(); ++t) {
    if (setup.triangles[t] >= n)
      return Invalid("triangles[" + std::to_string(t) +
                     "] = " + std::to_string(setup.triangles[t]) + " is out of range (" +
                     std::to_string(n) + " particles)");
    used[setup.triangles[t]] = true;
  }
  for (size_t i = 0; i < n; ++i)
    if (!used[i]) return Invalid("particle " + std::to_string(i) + " is in no triangle");
  if (setup.inverse_masses.size() != n)
    return Invalid("inverse_masses: " + std::to_string(setup.inverse_masses.size()) +
                   " values for " + std::to_string(n) + " particles");
  for (size_t i = 0; i < n; ++i)
    if (!Finite(setup.inverse_masses[i]) || setup.inverse_masses[i] < 0.f)
      return Invalid("inverse_masses[" + std::to_string(i) + "] is not finite and >= 0");
  if (!Finite(setup.gravity_y)) return Invalid("gravity_y is not finite");
  if (!(setup.damping >= 0.f && setup.damping < 1.f)) return Invalid("damping is not in [0, 1)");
  if (!(setup.friction >= 0.f && setup.friction <= 1.f))
    return Invalid("friction is not in [0, 1]");
  if (setup.iterations < 1 || setup.iterations > 1024)
    return Invalid("iterations is not in [1, 1024]");
  if (setup.substeps < 1 || setup.substeps > 1024) return Invalid("substeps is not in [1, 1024]");
  if (!(setup.collision_margin > 0.f && Finite(setup.collision_margin)))
    return Invalid("collision_margin is not finite and > 0");
  if (!(setup.stretch_stiffness > 0.f && setup.stretch_stiffness <= 1.f))
    return Invalid("stretch_stiffness is not in (0, 1]");
  if (!(setup.bend_stiffness > 0.f && setup.bend_stiffness <= 1.f))
    return Invalid("bend_stiffness is not in (0, 1]");
  if (!(setup.kinematic_contact_hardness > 0.f && setup.kinematic_contact_hardness <= 1.f))
    return Invalid("kinematic_contact_hardness is not in (0, 1]");
  if (!(setup.sdf_voxel_size > 0.f && Finite(setup.sdf_voxel_size)))
    return Invalid("sdf_voxel_size is not finite and > 0");
  for (size_t h = 0; h < hulls.size(); ++h) {
    if (hulls[h].local_vertices.size() < 4)
      return Invalid("hulls[" + std::to_string(h) + "] has fewer than 4 vertices");
    for (const Float3& v : hulls[h].local_vertices)
      if (!Finite(v.x) || !Finite(v.y) || !Finite(v.z))
        return Invalid("hulls[" + std::to_string(h) + "] has a non-finite vertex");
  }
  for (size_t s = 0; s < sphere_radii.size(); ++s)
    if (!(sphere_radii[s] > 0.f && Finite(sphere_radii[s])))
      return Invalid("sphere_radii[" + std::to_string(s) + "] is not finite and > 0");

  auto w = std::make_unique<World>();
  w->world = std::make_unique<btSoftRigidDynamicsWorld>(&w->dispatcher, &w->broadphase, &w->solver,
                                                        &w->collision_configuration);
  w->world->setGravity(btVector3(0, setup.gravity_y, 0));
  btSoftBodyWorldInfo& info = w->world->getWorldInfo();
  info.m_gravity.setValue(0, setup.gravity_y, 0);
  info.air_density = 0;  // no aerodynamics (kLF = kDG = 0 anyway)
  info.m_sparsesdf.Initialize(kSdfHashBuckets, kSdfMaxCells);
  info.m_sparsesdf.setDefaultVoxelsz(setup.sdf_voxel_size);
  info.m_sparsesdf.Reset();

  // The cloth: nodes in input order (CreateFromTriMesh makes node i from vertex i, up to the
  // largest index used, which is n - 1 since every particle is in a triangle), one link per
  // distinct triangle edge, the faces.
  std::vector<btScalar> xyz(3 * n);
  for (size_t i = 0; i < n; ++i) {
    xyz[3 * i] = setup.positions[i].x;
    xyz[3 * i + 1] = setup.positions[i].y;
    xyz[3 * i + 2] = setup.positions[i].z;
  }
  const std::vector<int> triangles(setup.triangles.begin(), setup.triangles.end());
  w->cloth.reset(btSoftBodyHelpers::CreateFromTriMesh(info, xyz.data(), triangles.data(),
                                                      static_cast<int>(triangles.size() / 3),
                                                      /*randomizeConstraints=*/false));
  btSoftBody& cloth = *w->cloth;
  if (static_cast<size_t>(cloth.m_nodes.size()) != n)
    return Invalid("Bullet made " + std::to_string(cloth.m_nodes.size()) + " nodes for " +
                   std::to_string(n) + " particles");
  cloth.m_materials[0]->m_kLST = setup.stretch_stiffness;
  btSoftBody::Material* bend = cloth.appendMaterial();
  bend->m_kLST = setup.bend_stiffness;
  cloth.generateBendingConstraints(2, bend);
  // Bullet's own deterministic shuffle of the link order (a fixed linear congruential sequence),
  // which its demos apply to reduce the bias of the sequential link solve.
  cloth.randomizeConstraints();
  for (size_t i = 0; i < n; ++i) {
    const float inverse_mass = setup.inverse_masses[i];
    cloth.setMass(static_cast<int>(i), inverse_mass > 0.f ? 1.f / inverse_mass : 0.f);
    if (inverse_mass == 0.f) w->attached.push_back(static_cast<int>(i));
  }
  cloth.getCollisionShape()->setMargin(setup.collision_margin);
  cloth.m_cfg.piterations = static_cast<int>(setup.iterations);
  cloth.m_cfg.kDP = setup.damping;
  cloth.m_cfg.kDF = setup.friction;
  cloth.m_cfg.kKHR = setup.kinematic_contact_hardness;
  cloth.m_cfg.kCHR = setup.kinematic_contact_hardness;
  if (setup.collision == BulletClothCollision::kClusterRigidSoft) {
    cloth.generateClusters(0);  // one cluster per triangle
    cloth.m_cfg.collisions = btSoftBody::fCollision::CL_RS;
  } else {
    cloth.m_cfg.collisions = btSoftBody::fCollision::SDF_RS;
  }
  w->world->addSoftBody(&cloth, kClothGroup, kColliderGroup);

  // The colliders: kinematic bodies (mass 0) with friction 1, so the contact friction is kDF.
  const auto add_body = [&](std::unique_ptr<btCollisionShape> shape) {
    auto motion_state = std::make_unique<btDefaultMotionState>(btTransform::getIdentity());
    btRigidBody::btRigidBodyConstructionInfo body_info(0, motion_state.get(), shape.get());
    body_info.m_friction = 1;
    auto body = std::make_unique<btRigidBody>(body_info);
    body->setCollisionFlags(body->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
    body->setActivationState(DISABLE_DEACTIVATION);
    w->world->addRigidBody(body.get(), kColliderGroup, kClothGroup);
    w->shapes.push_back(std::move(shape));
    w->motion_states.push_back(std::move(motion_state));
    w->bodies.push_back(std::move(body));
    w->previous_pose.push_back(btTransform::getIdentity());
  };
  for (const BulletHullShape& hull : hulls) {
    auto shape = std::make_unique<btConvexHullShape>();
    for (const Float3& v : hull.local_vertices) shape->addPoint(ToBullet(v), false);
    shape->recalcLocalAabb();
    shape->setMargin(0);  // the hull itself, not a rounded copy 0.04 m larger
    add_body(std::move(shape));
  }
  for (const float radius : sphere_radii) add_body(std::make_unique<btSphereShape>(radius));
  w->hull_count = hulls.size();
  w->sphere_count = sphere_radii.size();
  w->previous_targets.resize(w->attached.size());
  for (size_t a = 0; a < w->attached.size(); ++a)
    w->previous_targets[a] = cloth.m_nodes[w->attached[a]].m_x;
  w->substeps = setup.substeps;
  world_ = std::move(w);
  return Status::Ok();
}

Status BulletClothPeer::SetInitialPose(std::span<const Mat34> hull_world,
                                       std::span<const Float3> sphere_centres) {
  if (!world_) return Status(StatusCode::kInvalidState, "BulletClothPeer: not built");
  World& w = *world_;
  if (hull_world.size() != w.hull_count || sphere_centres.size() != w.sphere_count)
    return Invalid("SetInitialPose: " + std::to_string(hull_world.size()) + " hulls and " +
                   std::to_string(sphere_centres.size()) + " spheres for " +
                   std::to_string(w.hull_count) + " and " + std::to_string(w.sphere_count));
  for (size_t b = 0; b < w.bodies.size(); ++b) {
    const btTransform pose =
        b < w.hull_count
            ? ToBullet(hull_world[b])
            : btTransform(btQuaternion::getIdentity(), ToBullet(sphere_centres[b - w.hull_count]));
    btRigidBody& body = *w.bodies[b];
    w.SetBodyPose(b, pose);
    body.setWorldTransform(pose);
    body.setInterpolationWorldTransform(pose);  // the "previous" transform of the next step
    body.setLinearVelocity(btVector3(0, 0, 0));
    body.setAngularVelocity(btVector3(0, 0, 0));
    w.previous_pose[b] = pose;
  }
  return Status::Ok();
}

Status BulletClothPeer::Step(std::span<const Mat34> hull_world,
                             std::span<const Float3> sphere_centres,
                             std::span<const Float3> attached_targets, float dt) {
  if (!world_) return Status(StatusCode::kInvalidState, "BulletClothPeer: not built");
  World& w = *world_;
  if (hull_world.size() != w.hull_count || sphere_centres.size() != w.sphere_count ||
      attached_targets.size() != w.attached.size())
    return Invalid("Step: " + std::to_string(hull_world.size()) + " hulls, " +
                   std::to_string(sphere_centres.size()) + " spheres, " +
                   std::to_string(attached_targets.size()) + " targets for " +
                   std::to_string(w.hull_count) + ", " + std::to_string(w.sphere_count) + ", " +
                   std::to_string(w.attached.size()));
  if (!(dt > 0.f && Finite(dt))) return Invalid("Step: dt is not finite and > 0");
  btSoftBody& cloth = *w.cloth;
  const btScalar h = dt / static_cast<btScalar>(w.substeps);
  std::vector<btTransform>& end_pose = w.end_pose;
  end_pose.resize(w.bodies.size());
  for (size_t b = 0; b < w.bodies.size(); ++b)
    end_pose[b] = b < w.hull_count ? ToBullet(hull_world[b])
                                   : btTransform(btQuaternion::getIdentity(),
                                                 ToBullet(sphere_centres[b - w.hull_count]));
  for (uint32_t s = 0; s < w.substeps; ++s) {
    const btScalar t = static_cast<btScalar>(s + 1) / static_cast<btScalar>(w.substeps);
    for (size_t b = 0; b < w.bodies.size(); ++b)
      w.SetBodyPose(b, Interpolate(w.previous_pose[b], end_pose[b], t));
    // Attached nodes: mass 0, carried to their target by their velocity in Bullet's integration.
    for (size_t a = 0; a < w.attached.size(); ++a) {
      btSoftBody::Node& node = cloth.m_nodes[w.attached[a]];
      const btVector3 target = w.previous_targets[a].lerp(ToBullet(attached_targets[a]), t);
      node.m_v = (target - node.m_x) / h;
    }
    // maxSubSteps 0: exactly one Bullet step of h (no fixed-step accumulator, no interpolation).
    w.world->stepSimulation(h, 0);
    for (size_t a = 0; a < w.attached.size(); ++a) {
      btSoftBody::Node& node = cloth.m_nodes[w.attached[a]];
      node.m_x = w.previous_targets[a].lerp(ToBullet(attached_targets[a]), t);
    }
  }
  w.previous_pose.swap(end_pose);
  for (size_t a = 0; a < w.attached.size(); ++a)
    w.previous_targets[a] = ToBullet(attached_targets[a]);
  return Status::Ok();
}

void BulletClothPeer::CopyPositions(std::span<Float3> out) const {
  if (!world_) return;
  const btSoftBody& cloth = *world_->cloth;
  const size_t n = std::min(out.size(), static_cast<size_t>(cloth.m_nodes.size()));
  for (size_t i = 0; i < n; ++i) {
    const btVector3& x = cloth.m_nodes[static_cast<int>(i)].m_x;
    out[i] = {static_cast<float>(x.x()), static_cast<float>(x.y()), static_cast<float>(x.z())};
  }
}

size_t BulletClothPeer::particle_count() const {
  return world_ ? static_cast<size_t>(world_->cloth->m_nodes.size()) : 0;
}

size_t BulletClothPeer::attached_count() const { return world_ ? world_->attached.size() : 0; }

size_t BulletClothPeer::link_count() const {
  return world_ ? static_cast<size_t>(world_->cloth->m_links.size()) : 0;
}

size_t BulletClothPeer::last_contact_count() const {
  if (!world_) return 0;
  return static_cast<size_t>(world_->cloth->m_rcontacts.size());
}

size_t BulletClothPeer::sdf_cell_count() const {
  return world_ ? static_cast<size_t>(world_->world->getWorldInfo().m_sparsesdf.ncells) : 0;
}

}  // namespace drape::peers
