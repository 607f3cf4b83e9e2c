#pragma once
// A mass-spring cloth built from any triangle mesh (paper A §1, paper B §1.1): the editable
// ClothDescription, the validating BuildCloth, the immutable Cloth it fills (springs coloured
// for the solver, masses, pins and attachments), and the ClothState the caller owns and the
// solver advances. Every triangle edge is a stretch spring; an edge shared by two triangles
// also gives a bend spring between the opposite vertices. Pinned and attached particles have
// inverse mass 0; an attached particle follows its joint (its target at a pose with skinning
// matrix S is S * bind_position). Details: docs/ALGORITHMS.md §10.

#include <cstdint>
#include <span>
#include <vector>

#include "drape/formats/status.h"
#include "drape/formats/types.h"

namespace drape {

enum class SpringKind : uint8_t {
  kStretch = 0,  // a triangle edge (paper B: tension-shear spring)
  kBend = 1,     // across a shared edge, between the two opposite vertices
};

// How one kind of spring responds. The explicit Euler integrator uses stiffness and damping
// (forces); the Verlet integrator uses correction (paper B's iterative length correction).
struct SpringMaterial {
  float stiffness = 200.f;  // N/m per spring, finite, >= 0: force per metre of length error
  float damping = 0.05f;    // N*s/m per spring, finite, >= 0: force per m/s of length change
  float correction = 1.f;   // in [0, 1]: fraction of the length error one iteration removes
                            // (1 = paper B's full correction)
};

// Up to four joints that carry a particle by linear blend skinning (a skinned garment). Unused
// slots have weight 0; the weights sum to 1 (BuildCloth renormalises them).
struct ClothSkinWeights {             // 32 bytes
  uint32_t joints[4] = {0, 0, 0, 0};  // indices into the skinning matrices
  float weights[4] = {0.f, 0.f, 0.f, 0.f};
};

// A long-range attachment (NvCloth's tether, Jolt's LRA): `particle` may not get farther from
// `anchor` (a pinned, attached or max-distance-0 particle) than `length` (the geodesic distance
// over the rest mesh's edges) times (1 + the particle's tether stretch).
struct ClothTether {  // 12 bytes
  uint32_t particle = 0, anchor = 0;
  float length = 0.f;  // metres, > 0, already scaled by (1 + stretch)
};

// A particle that moves rigidly with a joint (paper B §3.2).
struct ClothAttachment {
  uint32_t particle = 0;
  int32_t joint = -1;    // index into the skinning matrices, >= 0
  Float3 bind_position;  // metres, bind-pose asset frame; target = skinning(joint) * this
};

// Editable input of BuildCloth.
struct ClothDescription {
  std::vector<Float3> positions;    // metres, finite: the rest shape (rest lengths come from it)
  std::vector<uint32_t> triangles;  // 3 vertex indices per triangle (winding is not used)
  // kg per particle, each finite and > 0; empty: masses from area (density, total_mass).
  std::vector<float> masses;
  float density = 0.15f;         // kg/m^2 areal density, finite, >= 0 (used when masses is empty)
  float total_mass = 0.f;        // kg, finite, >= 0; > 0 rescales area masses to this total
  std::vector<uint32_t> pinned;  // particles that only the caller moves (inverse mass 0)
  std::vector<ClothAttachment> attachments;  // at most one per particle (inverse mass 0)
  SpringMaterial stretch;                    // 200 N/m, 0.05 N*s/m, full correction
  // Bending resists much less than stretching: 20 N/m, 0.01 N*s/m, a fifth of the length error
  // per Verlet iteration.
  SpringMaterial bend{20.f, 0.01f, 0.2f};
  bool bend_springs = true;  // false: stretch springs only

  // Long-range attachments: every dynamic particle connected to the kinematic set through the
  // mesh gets one tether to its geodesically nearest kinematic particle. What keeps a long
  // garment from stretching under its own weight at few iterations.
  bool tethers = true;
  float tether_stretch = 0.02f;  // >= 0, finite: allowed stretch beyond the geodesic length
  std::vector<float> tether_stretch_per_particle;  // empty, or one value per particle (>= 0)

  // A skinned garment: per particle its joints and weights (empty: not skinned), and where it
  // sits in the bind pose (asset frame; empty: `positions`, the garment authored in the bind
  // pose). Its skinned position at a pose is sum_k weight_k * skinning[joint_k] * bind position.
  std::vector<ClothSkinWeights> skin;
  std::vector<Float3> skin_bind_positions;
  // metres per particle (empty: unlimited): how far a particle may move from its skinned
  // position; 0 makes it kinematic (placed at its skinned position, like an attachment).
  std::vector<float> max_distance;
  // metres per particle (empty: none; +inf: none): the particle stays on the outside of the
  // plane this far behind its skinned position, along the garment's skinned normal (the side
  // the triangles' counter-clockwise winding faces). Keeps a garment from sinking into the body
  // it is skinned to, whatever the colliders miss.
  std::vector<float> backstop;
};

// What BuildCloth did with input it tolerates.
struct ClothBuildReport {
  uint32_t dropped_triangles = 0;    // a repeated vertex index: no springs, no mass
  uint32_t zero_area_triangles = 0;  // area < 1e-12 m^2: springs kept, no mass
  uint32_t dropped_springs = 0;      // rest length < 1e-7 m, or both ends have inverse mass 0
  uint32_t non_manifold_edges = 0;   // edges of more than two triangles: no bend spring
  uint32_t stretch_colours = 0;
  uint32_t bend_colours = 0;
  uint32_t tethers = 0;
  uint32_t untethered_particles = 0;  // dynamic particles with no mesh path to a kinematic one
};

// One spring in solver form. weight_a + weight_b = 1 (or both 0): the share of a length
// correction each end takes, inverse_mass / (inverse_mass_a + inverse_mass_b) (paper B eq. 3).
struct ClothSpring {
  uint32_t a = 0, b = 0;
  float rest_length = 0.f;  // metres, > 0
  float weight_a = 0.f, weight_b = 0.f;
};  // 20 bytes

// A range of springs of one kind in which no two springs share a particle.
struct SpringColour {
  uint32_t begin = 0, end = 0;  // into Cloth::springs()
  SpringKind kind = SpringKind::kStretch;
};

class Cloth;

// Validates `description` and fills `cloth` (allocates). Rejected with kInvalidArgument and a
// message naming the field and index: no particles or more than 2^30, a non-finite position, a
// triangle count not a multiple of 3, a vertex index out of range, masses of the wrong count or
// not finite and > 0, density or total_mass not finite and >= 0, a pinned index or attachment
// particle out of range, two attachments of one particle, a negative joint, a non-finite
// attachment position, a material value out of range, a particle that gets no mass (in no
// triangle with area, masses empty) and is neither pinned nor attached, a tether stretch not
// finite and >= 0, skin weights of the wrong count, negative, not finite or summing to 0, max
// distances or backstops of the wrong count, negative or NaN, or given without skin weights.
// Tolerated and counted in the report: see ClothBuildReport. On error `cloth` is left empty.
Status BuildCloth(const ClothDescription& description, Cloth* cloth);

// The immutable topology of one cloth. Only BuildCloth fills it.
class Cloth {
 public:
  uint32_t particle_count() const { return static_cast<uint32_t>(rest_positions_.size()); }
  bool empty() const { return rest_positions_.empty(); }

  std::span<const Float3> rest_positions() const { return rest_positions_; }
  // kg as described (explicit, or from area; pinned and attached particles keep theirs).
  std::span<const float> masses() const { return masses_; }
  // 1/kg; 0 for pinned and attached particles.
  std::span<const float> inverse_masses() const { return inverse_masses_; }
  std::span<const float> areas() const {
    return areas_;
  }  // m^2 per particle (a third of each
     // adjacent triangle): fluid drag
  std::span<const uint32_t> triangles() const { return triangles_; }  // kept triangles
  // Stretch springs first (spring_count(kStretch) of them), then bend springs; by colour.
  std::span<const ClothSpring> springs() const { return springs_; }
  std::span<const SpringColour> colours() const { return colours_; }
  // Particles with inverse mass 0 (pinned or attached), ascending.
  std::span<const uint32_t> kinematic_particles() const { return kinematic_; }
  std::span<const ClothAttachment> attachments() const { return attachments_; }  // by particle
  std::span<const ClothTether> tethers() const { return tethers_; }              // by particle
  // Skinned garments: weights per particle (empty when not skinned), unit rest normals (area
  // weighted, the triangles' winding), max distances and backstops (+inf where unlimited).
  bool skinned() const { return !skin_.empty(); }
  std::span<const ClothSkinWeights> skin() const { return skin_; }
  // Bind positions of the skin: the description's, or the rest positions when it gave none.
  std::span<const Float3> skin_bind_positions() const {
    return skin_bind_.empty() && !skin_.empty() ? rest_positions() : skin_bind_;
  }
  std::span<const Float3> rest_normals() const { return rest_normals_; }
  std::span<const float> max_distances() const { return max_distance_; }
  std::span<const float> backstops() const { return backstop_; }
  // Dynamic particles with a finite max distance or backstop, ascending.
  std::span<const uint32_t> constrained_particles() const { return constrained_; }
  const SpringMaterial& material(SpringKind kind) const {
    return kind == SpringKind::kStretch ? stretch_ : bend_;
  }
  uint32_t spring_count(SpringKind kind) const {
    return kind == SpringKind::kStretch ? stretch_count_ : bend_count_;
  }
  // Skinning matrices Step needs for the attachments: max joint + 1 (0 without attachments).
  uint32_t required_joint_count() const { return required_joints_; }
  float total_mass() const { return total_mass_; }  // kg over the dynamic particles
  const ClothBuildReport& build_report() const { return report_; }

  // The largest explicit Euler step (seconds) for which the undamped-plus-damped spring system is
  // stable, from a Gershgorin bound on the eigenvalues of M^-1 K and M^-1 C: with
  // w2 = max_i 2 sum_j k_ij / m_i and g = max_i 2 sum_j c_ij / m_i + extra_damping,
  // h = (sqrt(g^2 + 4 w2) - g) / w2 (semi-implicit Euler is stable for h^2 w2 + 2 h g < 4).
  // Conservative: the bound is attained only by the worst mode. +inf without springs.
  // extra_damping: 1/s, the solver's global velocity damping.
  float MaxStableEulerStep(float extra_damping = 0.f) const;

  size_t memory_bytes() const;

 private:
  friend Status BuildCloth(const ClothDescription& description, Cloth* cloth);
  struct Builder;  // BuildCloth's stages (cloth/cloth.cpp)
  void Clear();

  float euler_stiffness_rate_ = 0.f;  // 1/s^2: max_i 2 sum_j k_ij / m_i over dynamic particles
  float euler_damping_rate_ = 0.f;    // 1/s: max_i 2 sum_j c_ij / m_i
  std::vector<Float3> rest_positions_;
  std::vector<float> masses_, inverse_masses_, areas_;
  std::vector<uint32_t> triangles_;
  std::vector<ClothSpring> springs_;
  std::vector<SpringColour> colours_;
  std::vector<uint32_t> kinematic_;
  std::vector<ClothAttachment> attachments_;
  std::vector<ClothTether> tethers_;
  std::vector<ClothSkinWeights> skin_;
  std::vector<Float3> skin_bind_;  // empty when the skin binds the rest positions
  std::vector<Float3> rest_normals_;
  std::vector<float> max_distance_, backstop_;
  std::vector<uint32_t> constrained_;
  SpringMaterial stretch_, bend_;
  uint32_t stretch_count_ = 0, bend_count_ = 0;
  uint32_t required_joints_ = 0;
  float total_mass_ = 0.f;
  ClothBuildReport report_;
};

// The per-particle state of one cloth, owned by the caller (read it, or move particles between
// steps: pinned particles stay wherever the caller puts them). All three arrays have the
// cloth's particle count.
struct ClothState {
  std::vector<Float3> positions;           // metres, world (asset) frame
  std::vector<Float3> previous_positions;  // positions at the start of the last substep
  std::vector<Float3> velocities;          // m/s

  // Rest positions, zero velocities (allocates).
  void Reset(const Cloth& cloth);
  // Sizes match the cloth.
  bool Matches(const Cloth& cloth) const;
};

}  // namespace drape
