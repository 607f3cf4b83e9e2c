// BodyMapRenderer: the maps of a pose rendered at run time. Render is a recipe of stages:
// skin and offset the mesh, cull the triangles to the region, place the window on the texel
// lattice, rasterize both surfaces in row bands, shade the normals, and let the collider derive
// its bounds and blocks (docs/ALGORITHMS.md §7.9).
#include "drape/runtime/body_map_renderer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "drape/runtime/math.h"
#include "drape/runtime/normal_encoding.h"
#include "drape/runtime/skinning.h"

#include "body_map/raster_triangle.h"
#include "body_map/texel_normal_lanes.h"
#include "drape/runtime/task_system.h"
#include "tasks/parallel_for.h"

namespace drape {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
using detail::kNoFace;
using detail::RasterTriangle;
// Init reserves this much more than the bind pose's window in each dimension: a pose that
// spreads the limbs needs a wider window.
constexpr double kReserveGrowth = 1.5;
// Vertices or triangles per chunk of the per-vertex stages.
constexpr int64_t kVertexGrain = 4096;

Status Invalid(const std::string& message) {
  return Status(StatusCode::kInvalidArgument, "BodyMapRenderer: " + message);
}

}  // namespace

// Out of line: the per-triangle shading type is internal (raster_triangle.h).
BodyMapRenderer::BodyMapRenderer() = default;
BodyMapRenderer::~BodyMapRenderer() = default;
BodyMapRenderer::BodyMapRenderer(const BodyMapRenderer&) = default;
BodyMapRenderer::BodyMapRenderer(BodyMapRenderer&&) noexcept = default;
BodyMapRenderer& BodyMapRenderer::operator=(const BodyMapRenderer&) = default;
BodyMapRenderer& BodyMapRenderer::operator=(BodyMapRenderer&&) noexcept = default;

Status BodyMapRenderer::Init(const MeshData& mesh, const BodyMapRenderOptions& options) {
  mesh_ = nullptr;
  stats_ = {};
  const BodyMapRenderOptions& o = options;
  if (!(o.texel_size >= 1e-4f && o.texel_size <= 1.f)) {
    return Invalid("texel_size " + std::to_string(o.texel_size) + " is outside [1e-4, 1] m");
  }
  if (!(o.epsilon >= 0.f && o.epsilon <= 1.f)) {
    return Invalid("epsilon " + std::to_string(o.epsilon) + " is outside [0, 1] m");
  }
  if (o.max_side < 16 || o.max_side > 16384) {
    return Invalid("max_side " + std::to_string(o.max_side) + " is outside [16, 16384]");
  }
  if (!std::isfinite(o.grid_x) || !std::isfinite(o.grid_y)) {
    return Invalid("grid_x and grid_y must be finite");
  }
  if (o.sampling != DepthSampling::kNearest && o.sampling != DepthSampling::kBilinear) {
    return Invalid("unknown depth sampling");
  }
  constexpr uint32_t kMaxGaps = uint32_t{kMaxBodyMapLayers} - 1u;
  if (o.air_gaps > kMaxGaps) {
    return Invalid("air_gaps " + std::to_string(o.air_gaps) + " is outside [0, " +
                   std::to_string(kMaxGaps) + "]");
  }
  if (static_cast<uint8_t>(o.view_axis) > 2) {
    return Invalid("view_axis " + std::to_string(static_cast<int>(o.view_axis)) +
                   " is not 0 (z), 1 (x) or 2 (y)");
  }
  const uint32_t vertices = mesh.vertex_count();
  if (mesh.triangles.empty() || mesh.triangles.size() % 3 != 0) {
    return Invalid("the mesh has " + std::to_string(mesh.triangles.size()) +
                   " triangle indices (a positive multiple of 3 is needed)");
  }
  if (mesh.triangle_count() >= detail::kMaxRasterTriangles) {
    return Invalid("the mesh has " + std::to_string(mesh.triangle_count()) +
                   " triangles (fewer than " + std::to_string(detail::kMaxRasterTriangles) +
                   " are supported)");
  }
  for (size_t k = 0; k < mesh.triangles.size(); ++k) {
    if (mesh.triangles[k] >= vertices) {
      return Invalid("triangle index " + std::to_string(k) + " names vertex " +
                     std::to_string(mesh.triangles[k]) + " of " + std::to_string(vertices));
    }
  }
  for (uint32_t v = 0; v < vertices; ++v) {
    if (!IsFinite(mesh.positions[v])) {
      return Invalid("vertex " + std::to_string(v) + " is not finite");
    }
  }
  const bool skinned = mesh.influence_offsets.size() == size_t{vertices} + 1;
  joints_needed_ = 0;
  if (skinned) {
    if (mesh.influence_offsets.back() > mesh.influence_joints.size()) {
      return Invalid("the influence rows end past the influence arrays");
    }
    for (uint32_t k = 0; k < mesh.influence_offsets.back(); ++k) {
      joints_needed_ = std::max<uint32_t>(joints_needed_, mesh.influence_joints[k] + 1u);
    }
  }
  options_ = options;

  // The triangles around each vertex, ascending: normals are gathered per vertex in a fixed
  // order, so they do not depend on the thread count.
  const uint32_t triangles = mesh.triangle_count();
  vertex_triangle_offsets_.assign(size_t{vertices} + 1, 0u);
  for (uint32_t index : mesh.triangles) ++vertex_triangle_offsets_[index + 1];
  for (uint32_t v = 0; v < vertices; ++v) {
    vertex_triangle_offsets_[v + 1] += vertex_triangle_offsets_[v];
  }
  every_vertex_in_a_triangle_ = true;
  for (uint32_t v = 0; v < vertices; ++v) {
    if (vertex_triangle_offsets_[v + 1] == vertex_triangle_offsets_[v])
      every_vertex_in_a_triangle_ = false;
  }
  vertex_triangles_.resize(mesh.triangles.size());
  std::vector<uint32_t> fill(vertex_triangle_offsets_.begin(), vertex_triangle_offsets_.end() - 1);
  for (uint32_t t = 0; t < triangles; ++t) {
    for (int k = 0; k < 3; ++k) vertex_triangles_[fill[mesh.triangles[3 * t + k]]++] = t;
  }
  posed_.resize(vertices);
  normals_.resize(vertices);
  offset_.resize(vertices);
  face_normals_.resize(triangles);
  shading_.resize(triangles);
  drawn_.reserve(triangles);
  all_boxes_.reserve(triangles);
  placed_.reserve(vertices);
  raster_faces_.reserve(triangles);
  if (o.air_gaps > 0) gap_triangles_.reserve(triangles);
  raster_.reserve(triangles);
  raster_boxes_.reserve(triangles);

  // The bind pose's window, grown: most poses then render without allocating.
  Float3 lo{kInf, kInf, kInf}, hi{-kInf, -kInf, -kInf};
  for (const Float3& bind : mesh.positions) {
    const Float3 p = ToBodyMapView(o.view_axis, bind);
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  const double pad = 2.0 * (static_cast<double>(o.epsilon) + o.texel_size);
  const double side_x = (static_cast<double>(hi.x) - lo.x + pad) / o.texel_size + 3.0;
  const double side_y = (static_cast<double>(hi.y) - lo.y + pad) / o.texel_size + 3.0;
  const double limit = o.max_side;
  reserved_texels_ = static_cast<size_t>(std::min(kReserveGrowth * side_x, limit) *
                                         std::min(kReserveGrowth * side_y, limit));
  Reserve(reserved_texels_);
  mesh_ = &mesh;
  return Status::Ok();
}

Status BodyMapRenderer::Render(std::span<const Mat34> skinning, BodyMapCollider* maps,
                               const RenderRegion* region) {
  if (maps == nullptr) return Invalid("no collider to render into");
  maps->Clear();
  stats_.width = stats_.height = stats_.triangles_drawn = stats_.valid_texels = 0;
  stats_.gap_texels = 0;
  if (mesh_ == nullptr) return Invalid("not initialised (Init failed or was not called)");
  // A render that enlarged any buffer is counted once, whichever stages grew.
  grew_ = false;
  const size_t bytes = memory_bytes();
  RenderRegion box;  // everywhere, or the region in the view frame
  if (region != nullptr) {
    if (Status s = CheckRegion(*region); !s.ok()) return s;
    box.min = ToBodyMapView(options_.view_axis, region->min);
    box.max = ToBodyMapView(options_.view_axis, region->max);
  }
  if (Status s = SkinAndOffset(skinning); !s.ok()) return s;
  CullTriangles(box);
  Window window;
  if (Status s = PlaceWindow(box, &window); !s.ok()) return s;
  if (window.width == 0) return Status::Ok();  // nothing of the body reaches the region
  Publish(window, maps);
  Rasterize(window, maps);
  SetUpShading(window);
  if (options_.air_gaps > 0) {
    FindGaps(window, maps);
    PublishGaps(window, maps);
  }
  ShadeNormals(window, maps);
  maps->Finish(row_spans_);
  stats_.valid_texels = maps->stats().valid_texels;
  stats_.gap_texels = maps->stats().gap_texels;
  // The renderer's own buffers also grow with more gap texels or surfaces than reserved.
  if (grew_ || memory_bytes() != bytes) ++stats_.grew;
  return Status::Ok();
}

std::span<const uint32_t> BodyMapRenderer::RasterFaces() const {
  return {raster_faces_.data(), raster_count_};
}
std::span<const detail::RasterTriangle> BodyMapRenderer::RasterSetUps() const {
  return {raster_.data(), raster_count_};
}
std::span<const detail::RasterBox> BodyMapRenderer::RasterBoxes() const {
  return {raster_boxes_.data(), raster_count_};
}

detail::RasterWindow BodyMapRenderer::RasterWindowOf(const Window& window) const {
  return {window.origin_x,
          window.origin_y,
          window.width,
          window.height,
          1.0 / static_cast<double>(options_.texel_size),
          window.sub_bits};
}

Status BodyMapRenderer::CheckRegion(const RenderRegion& region) const {
  const float lo[3] = {region.min.x, region.min.y, region.min.z};
  const float hi[3] = {region.max.x, region.max.y, region.max.z};
  for (int c = 0; c < 3; ++c) {
    if (std::isnan(lo[c]) || std::isnan(hi[c]) || !(lo[c] <= hi[c]) || lo[c] == kInf ||
        hi[c] == -kInf) {
      return Invalid("the region's axis " + std::to_string(c) + " is empty or not a number ([" +
                     std::to_string(lo[c]) + ", " + std::to_string(hi[c]) + "])");
    }
  }
  return Status::Ok();
}

// Stage 1: the skinned vertices, their normals, and the surface offset by epsilon.
Status BodyMapRenderer::SkinAndOffset(std::span<const Mat34> skinning) {
  if (skinning.size() < joints_needed_) {
    return Invalid(std::to_string(skinning.size()) + " skinning matrices, the mesh's influences " +
                   "name " + std::to_string(joints_needed_) + " joints");
  }
  if (Status s = SkinMesh(*mesh_, skinning, posed_); !s.ok()) return Invalid(s.message());
  const int64_t vertices = static_cast<int64_t>(posed_.size());
  // Beyond 1e15 m the window arithmetic loses every texel: a hostile matrix, not a pose. The
  // check is cheap next to the skinning: one pass on the calling thread.
  int64_t first_bad = vertices;
  for (int64_t v = 0; v < vertices && first_bad == vertices; ++v) {
    const Float3 p = posed_[v];
    const bool sane = std::fabs(p.x) < 1e15f && std::fabs(p.y) < 1e15f && std::fabs(p.z) < 1e15f;
    if (!sane) first_bad = v;
  }
  if (first_bad < vertices) {
    return Invalid("skinned vertex " + std::to_string(first_bad) +
                   " is not finite or beyond 1e15 m (check the skinning matrices)");
  }
  ComputeNormals();
  const float epsilon = options_.epsilon;
  const BodyMapViewAxis axis = options_.view_axis;
  // The rest of the render is in the view frame: the offset surface and the normals the texels
  // take (an exact permutation; posed_ stays in the asset frame).
  detail::ParallelFor(vertices, kVertexGrain, [&](int64_t v) {
    offset_[v] = ToBodyMapView(axis, posed_[v] + normals_[v] * epsilon);
    normals_[v] = ToBodyMapView(axis, normals_[v]);
  });
  if (axis != BodyMapViewAxis::kZ) {
    const int64_t triangles = static_cast<int64_t>(face_normals_.size());
    detail::ParallelFor(triangles, kVertexGrain, [&](int64_t t) {
      face_normals_[t] = ToBodyMapView(axis, face_normals_[t]);
    });
  }
  return Status::Ok();
}

// Area-weighted vertex normals, gathered per vertex in triangle order.
void BodyMapRenderer::ComputeNormals() {
  const uint32_t* tri = mesh_->triangles.data();
  const int64_t triangles = static_cast<int64_t>(face_normals_.size());
  detail::ParallelFor(triangles, kVertexGrain, [&](int64_t t) {
    const Float3 a = posed_[tri[3 * t]], b = posed_[tri[3 * t + 1]], c = posed_[tri[3 * t + 2]];
    face_normals_[t] = Cross(b - a, c - a);
  });
  const int64_t vertices = static_cast<int64_t>(posed_.size());
  detail::ParallelFor(vertices, kVertexGrain, [&](int64_t v) {
    Float3 sum{0.f, 0.f, 0.f};
    for (uint32_t k = vertex_triangle_offsets_[v]; k < vertex_triangle_offsets_[v + 1]; ++k) {
      sum += face_normals_[vertex_triangles_[k]];
    }
    normals_[v] = NormalizeOr(sum, Float3{0.f, 0.f, 0.f});
  });
}

// Stage 2: the triangles whose offset box meets the region across the view axis, ascending. Not
// along it: a texel's slab needs every surface on its ray, or a region that cuts the body along
// the axis (a blanket's box over a fox's back, seen from above) leaves the top surface without
// the bottom one, a thin shell the cloth falls through. The air a part outside the region adds
// in front of or behind the garment is the gap pass's to find.
void BodyMapRenderer::CullTriangles(const RenderRegion& region) {
  drawn_.clear();
  const uint32_t* tri = mesh_->triangles.data();
  const uint32_t triangles = static_cast<uint32_t>(face_normals_.size());
  const bool everywhere = region.min.x == -kInf && region.max.x == kInf && region.min.y == -kInf &&
                          region.max.y == kInf;
  if (everywhere) {  // the offset surface is finite: every triangle reaches
    drawn_.resize(triangles);
    std::iota(drawn_.begin(), drawn_.end(), 0u);
    stats_.triangles_drawn = triangles;
    return;
  }
  for (uint32_t t = 0; t < triangles; ++t) {
    const Float3 a = offset_[tri[3 * t]], b = offset_[tri[3 * t + 1]], c = offset_[tri[3 * t + 2]];
    const bool reaches =
        std::max({a.x, b.x, c.x}) >= region.min.x && std::min({a.x, b.x, c.x}) <= region.max.x &&
        std::max({a.y, b.y, c.y}) >= region.min.y && std::min({a.y, b.y, c.y}) <= region.max.y;
    if (reaches) drawn_.push_back(t);  // reserved for every triangle at Init
  }
  stats_.triangles_drawn = static_cast<uint32_t>(drawn_.size());
}

// Stage 3: the texel lattice (multiples of the texel size, so the grid does not slide between
// frames) over the drawn triangles' box, cut to the region, with one background texel around.
Status BodyMapRenderer::PlaceWindow(const RenderRegion& region, Window* window) const {
  *window = Window{};
  if (drawn_.empty()) return Status::Ok();
  const uint32_t* tri = mesh_->triangles.data();
  double lo_x = kInf, lo_y = kInf, hi_x = -kInf, hi_y = -kInf;
  const auto extend = [&](const Float3& p) {
    lo_x = std::min<double>(lo_x, p.x);
    hi_x = std::max<double>(hi_x, p.x);
    lo_y = std::min<double>(lo_y, p.y);
    hi_y = std::max<double>(hi_y, p.y);
  };
  if (drawn_.size() == face_normals_.size() && every_vertex_in_a_triangle_) {
    for (const Float3& p : offset_) extend(p);  // the same box, a third of the reads
  } else {
    for (uint32_t t : drawn_) {
      for (int k = 0; k < 3; ++k) extend(offset_[tri[3 * t + k]]);
    }
  }
  const double drawn_lo_x = lo_x, drawn_hi_x = hi_x, drawn_lo_y = lo_y, drawn_hi_y = hi_y;
  lo_x = std::max<double>(lo_x, region.min.x);
  hi_x = std::min<double>(hi_x, region.max.x);
  lo_y = std::max<double>(lo_y, region.min.y);
  hi_y = std::min<double>(hi_y, region.max.y);
  const double t = options_.texel_size;
  const double gx = options_.grid_x, gy = options_.grid_y;
  const double i0 = std::floor((lo_x - gx) / t) - 1.0, i1 = std::floor((hi_x - gx) / t) + 1.0;
  const double j0 = std::floor((lo_y - gy) / t) - 1.0, j1 = std::floor((hi_y - gy) / t) + 1.0;
  const double width = i1 - i0 + 1.0, height = j1 - j0 + 1.0;
  if (!(width <= options_.max_side && height <= options_.max_side)) {
    return Invalid("the pose needs a " + std::to_string(width) + " x " + std::to_string(height) +
                   "-texel window (max_side " + std::to_string(options_.max_side) +
                   "): pass a region or a larger texel size");
  }
  // The collider stores its origin in float; the raster samples the same lattice.
  window->origin_x = static_cast<float>(gx + i0 * t);
  window->origin_y = static_cast<float>(gy + j0 * t);
  window->width = static_cast<uint32_t>(width);
  window->height = static_cast<uint32_t>(height);
  // The raster grid's precision: the farthest drawn corner from the origin, a texel to spare.
  const double reach =
      std::max({std::fabs(drawn_lo_x - window->origin_x), std::fabs(drawn_hi_x - window->origin_x),
                std::fabs(drawn_lo_y - window->origin_y),
                std::fabs(drawn_hi_y - window->origin_y)}) /
          t +
      1.0;
  window->sub_bits = detail::RasterWindow::SubBitsFor(reach);
  return Status::Ok();
}

// The collider's grid for this window, every texel background.
void BodyMapRenderer::Publish(const Window& window, BodyMapCollider* maps) {
  const size_t texels = static_cast<size_t>(window.width) * window.height;
  if (texels > reserved_texels_) {
    grew_ = true;
    reserved_texels_ = texels;
  }
  Reserve(reserved_texels_);
  // The collider's grid and everything Finish derives from it, for the largest window so far.
  maps->slabs_.reserve(reserved_texels_);
  maps->normals_.reserve(reserved_texels_);
  maps->air_reach_.reserve(reserved_texels_);
  maps->blocks_.reserve(reserved_texels_ / 64 + options_.max_side / 4 + 1);  // 8x8 blocks
  if (options_.sampling == DepthSampling::kBilinear) maps->bilinear_ok_.reserve(reserved_texels_);
  if (options_.air_gaps > 0) {
    // Gaps on up to an eighth of the texels (a human has them on a few percent).
    maps->gap_texel_bits_.reserve(reserved_texels_ / 32 + 1);
    maps->gap_word_first_.reserve(reserved_texels_ / 32 + 1);
    maps->gaps_.reserve(reserved_texels_ / 8 * options_.air_gaps);
    maps->gap_normals_.reserve(reserved_texels_ / 8 * options_.air_gaps);
  }
  maps->slabs_.assign(texels, BodyMapCollider::Slab{-kInf, kInf});
  maps->normals_.resize(texels);
  // The renderer's per-texel entries are set by a texel's first fragment (its slab's top is
  // then still -inf) and read only where the slab is valid: not cleared here, where most of the
  // window is background.
  texel_raster_.resize(texels);
  row_spans_.resize(2 * static_cast<size_t>(window.height));
  maps->gap_layers_ = options_.air_gaps > 0 ? 1u : 0u;         // PublishGaps sets the deepest found
  if (options_.air_gaps > 0) fragment_cursor_.resize(texels);  // set by FindGaps
  maps->width_ = window.width;
  maps->height_ = window.height;
  maps->width_f_ = static_cast<float>(window.width);
  maps->height_f_ = static_cast<float>(window.height);
  maps->origin_x_ = static_cast<float>(window.origin_x);
  maps->origin_y_ = static_cast<float>(window.origin_y);
  maps->texel_size_ = options_.texel_size;
  maps->inv_texel_size_ = 1.f / options_.texel_size;
  maps->sampling_ = options_.sampling;
  maps->view_axis_ = options_.view_axis;
  stats_.width = window.width;
  stats_.height = window.height;
}

void BodyMapRenderer::Reserve(size_t texels) {
  texel_raster_.reserve(texels);
  row_spans_.reserve(2 * size_t{options_.max_side});  // a taller window is refused
  if (options_.air_gaps == 0) return;
  fragment_cursor_.reserve(texels);
  // Gap texels (rays crossing more than one part) on up to an eighth of the window, with four
  // surfaces each on average: a human has them on a few percent.
  const size_t gap_texels = texels / 8 + 1;
  gap_texels_.reserve(gap_texels);
  fragment_offsets_.reserve(gap_texels + 1);
  fragments_.reserve(4 * gap_texels);
  gaps_per_texel_.reserve(gap_texels);
  texel_gaps_.reserve(gap_texels * options_.air_gaps);
  gap_tiles_.reserve(texels / 64 + options_.max_side / 4 + 1);  // 8 x 8 tiles
}

// Stage 4: each drawn triangle set up once, then per texel the highest (front) and lowest (back)
// z of the triangles covering its centre, and which triangle it was (ties: the lower index, as
// triangles are drawn ascending).
void BodyMapRenderer::Rasterize(const Window& window, BodyMapCollider* maps) {
  BodyMapCollider::Slab* slabs = maps->slabs_.data();
  const bool gaps = options_.air_gaps > 0;
  const detail::RasterWindow w = RasterWindowOf(window);
  // Reserved for every triangle at Init; never shrunk (a set-up is 112 bytes to clear again).
  const size_t drawn = drawn_.size();
  all_boxes_.resize(std::max(all_boxes_.size(), drawn));
  placed_.resize(offset_.size());
  raster_faces_.resize(std::max(raster_faces_.size(), drawn));
  raster_boxes_.resize(std::max(raster_boxes_.size(), drawn));
  raster_.resize(std::max(raster_.size(), drawn));
  raster_count_ = detail::SetUpTriangles(offset_, mesh_->triangles.data(), drawn_, w, placed_,
                                         all_boxes_, raster_faces_, raster_boxes_, raster_);
  // A plain pointer: the fragment writes through it, and the compiler would reload the vector's
  // data pointer after every store.
  TexelRaster* texel_raster = texel_raster_.data();
  detail::RasterizeInBands(
      RasterFaces(), RasterSetUps(), RasterBoxes(), w, nullptr,
      [&](uint32_t t, const RasterTriangle& r, size_t k, double px, double py, bool) {
        const float z = r.Depth(px, py);
        BodyMapCollider::Slab& s = slabs[k];
        TexelRaster& e = texel_raster[k];
        if (gaps && s.top == -kInf) {  // the texel's first fragment (z is finite)
          e.fragment_count = 0;
          e.exit_z = -kInf;
          e.exit_face = kNoFace;
          e.lowest_entry_z = kInf;
        }
        if (z > s.top) {
          s.top = z;
          e.top_face = t;
        }
        if (z < s.bottom) {
          s.bottom = z;
          e.bottom_face = t;
        }
        if (!gaps) return;
        ++e.fragment_count;
        // A surface leaving the body going along -z: a gap's upper boundary candidate.
        if (!r.entering && z > e.exit_z) {
          e.exit_z = z;
          e.exit_face = t;
        }
        // A surface entering it: where none lies below the first candidate, no gap can.
        if (r.entering && z < e.lowest_entry_z) e.lowest_entry_z = z;
      },
      row_spans_.data());
}

// Stage 5: the normal rule of every drawn triangle, then the outward normal of each covered
// texel's front and back surfaces, oct16.
void BodyMapRenderer::SetUpShading(const Window& window) {
  const double inverse_texel = 1.0 / static_cast<double>(options_.texel_size);
  const uint32_t* tri = mesh_->triangles.data();
  // Only a triangle that covers a texel centre can give a texel its normal.
  detail::ParallelFor(static_cast<int64_t>(raster_count_), kVertexGrain, [&](int64_t c) {
    const uint32_t t = raster_faces_[static_cast<size_t>(c)];
    shading_[t].SetUp(offset_.data(), normals_.data(), tri + 3 * size_t{t}, face_normals_[t],
                      window.origin_x, window.origin_y, inverse_texel);
  });
}

void BodyMapRenderer::ShadeNormals(const Window& window, BodyMapCollider* maps) const {
  const int64_t width = window.width, height = window.height;
  const std::array<uint16_t, 2> up = EncodeOct16({0.f, 0.f, 1.f});
  const BodyMapCollider::TexelNormals background{{up[0], up[1]}, {up[0], up[1]}};
  constexpr Float3 kUp{0.f, 0.f, 1.f}, kDown{0.f, 0.f, -1.f};
  const BodyMapCollider::Slab* slabs = maps->slabs_.data();
  BodyMapCollider::TexelNormals* normals = maps->normals_.data();
  const auto valid = [&](size_t k) { return slabs[k].top >= slabs[k].bottom; };
  const auto one_texel = [&](size_t k, float px, float py) {
    if (!valid(k)) {  // background: no fragment set its faces
      normals[k] = background;
      return;
    }
    const TexelRaster& e = texel_raster_[k];
    const std::array<uint16_t, 2> a = EncodeOct16(shading_[e.top_face].At(px, py, kUp));
    const std::array<uint16_t, 2> b = EncodeOct16(shading_[e.bottom_face].At(px, py, kDown));
    normals[k] = {{a[0], a[1]}, {b[0], b[1]}};
  };
  detail::ParallelFor(height, 8, [&](int64_t j) {
    const float py = static_cast<float>(j) + 0.5f;
    // Only the row's span can hold covered texels (RasterizeInBands); the rest is background.
    const int64_t span_begin = std::min<int64_t>(row_spans_[2 * j], width);
    const int64_t span_end = std::max<int64_t>(row_spans_[2 * j + 1], span_begin);
    std::fill(normals + j * width, normals + j * width + span_begin, background);
    std::fill(normals + j * width + span_end, normals + (j + 1) * width, background);
    int64_t i = span_begin;
#if defined(__SSE2__)
    // Four texels at a time, the same bits (texel_normal_lanes.h). A background lane borrows a
    // covered lane's triangles and is overwritten.
    for (; i + 4 <= span_end; i += 4) {
      const size_t k = static_cast<size_t>(j * width + i);
      uint32_t covered = 0;
      for (uint32_t l = 0; l < 4; ++l) covered |= valid(k + l) ? 1u << l : 0u;
      if (covered == 0) {
        for (uint32_t l = 0; l < 4; ++l) normals[k + l] = background;
        continue;
      }
      const size_t any = k + static_cast<size_t>(__builtin_ctz(covered));
      const detail::TriangleShading* front[4];
      const detail::TriangleShading* back[4];
      for (uint32_t l = 0; l < 4; ++l) {
        const size_t texel = (covered >> l) & 1u ? k + l : any;
        front[l] = &shading_[texel_raster_[texel].top_face];
        back[l] = &shading_[texel_raster_[texel].bottom_face];
      }
      const __m128 px =
          _mm_add_ps(_mm_cvtepi32_ps(_mm_add_epi32(_mm_set1_epi32(static_cast<int32_t>(i)),
                                                   _mm_setr_epi32(0, 1, 2, 3))),
                     _mm_set1_ps(0.5f));
      const __m128 py_lanes = _mm_set1_ps(py);
      uint32_t front_codes[4], back_codes[4];
      detail::EncodeOct16Lanes(detail::ShadeLanes(front, px, py_lanes, kUp), front_codes);
      detail::EncodeOct16Lanes(detail::ShadeLanes(back, px, py_lanes, kDown), back_codes);
      for (uint32_t l = 0; l < 4; ++l) {
        const auto half = [](uint32_t code, int shift) {
          return static_cast<uint16_t>(code >> shift);
        };
        normals[k + l] =
            (covered >> l) & 1u
                ? BodyMapCollider::TexelNormals{{half(front_codes[l], 0), half(front_codes[l], 16)},
                                                {half(back_codes[l], 0), half(back_codes[l], 16)}}
                : background;
      }
    }
#endif
    for (; i < span_end; ++i) {
      one_texel(static_cast<size_t>(j * width + i), static_cast<float>(i) + 0.5f, py);
    }
  });
}

Status BodyMapRenderer::Load(const RenderedMapsView& view, BodyMapCollider* maps,
                             DepthSampling sampling) {
  if (maps == nullptr) return Invalid("Load: no collider to load into");
  maps->Clear();
  const size_t texels = static_cast<size_t>(view.width) * view.height;
  if (view.width < 1 || view.height < 1 || view.width > 16384 || view.height > 16384) {
    return Invalid("Load: " + std::to_string(view.width) + " x " + std::to_string(view.height) +
                   " texels is outside [1, 16384] per side");
  }
  if (!std::isfinite(view.origin_x) || !std::isfinite(view.origin_y) ||
      !(view.texel_size >= 1e-6f && view.texel_size <= 1e3f)) {
    return Invalid("Load: the origin is not finite or the texel size is outside [1e-6, 1e3] m");
  }
  if (view.front_z.size() != texels || view.back_z.size() != texels ||
      view.front_normals.size() != texels || view.back_normals.size() != texels) {
    return Invalid("Load: every array must hold width * height = " + std::to_string(texels) +
                   " entries (front_z " + std::to_string(view.front_z.size()) + ", back_z " +
                   std::to_string(view.back_z.size()) + ", normals " +
                   std::to_string(view.front_normals.size()) + " and " +
                   std::to_string(view.back_normals.size()) + ")");
  }
  if (sampling != DepthSampling::kNearest && sampling != DepthSampling::kBilinear) {
    return Invalid("Load: unknown depth sampling");
  }
  if (static_cast<uint8_t>(view.view_axis) > 2) {
    return Invalid("Load: view_axis " + std::to_string(static_cast<int>(view.view_axis)) +
                   " is not 0 (z), 1 (x) or 2 (y)");
  }
  const BodyMapViewAxis axis = view.view_axis;
  maps->slabs_.resize(texels);  // capacity kept from earlier grids
  maps->normals_.resize(texels);
  const int64_t count = static_cast<int64_t>(texels);
  detail::ParallelFor(count, count > 65536 ? 16384 : count, [&](int64_t k) {
    const float top = view.front_z[k], bottom = view.back_z[k];
    const bool body = std::isfinite(top) && std::isfinite(bottom) && top >= bottom;
    maps->slabs_[k] =
        body ? BodyMapCollider::Slab{top, bottom} : BodyMapCollider::Slab{-kInf, kInf};
    const std::array<uint16_t, 2> front = EncodeOct16(ToBodyMapView(axis, view.front_normals[k]));
    const std::array<uint16_t, 2> back =
        EncodeOct16(IsFinite(view.back_normals[k]) ? ToBodyMapView(axis, view.back_normals[k])
                                                   : Float3{0.f, 0.f, -1.f});
    maps->normals_[k] = {{front[0], front[1]}, {back[0], back[1]}};
  });
  maps->width_ = view.width;
  maps->height_ = view.height;
  maps->width_f_ = static_cast<float>(view.width);
  maps->height_f_ = static_cast<float>(view.height);
  maps->origin_x_ = view.origin_x;
  maps->origin_y_ = view.origin_y;
  maps->texel_size_ = view.texel_size;
  maps->inv_texel_size_ = 1.f / view.texel_size;
  maps->sampling_ = sampling;
  maps->view_axis_ = view.view_axis;
  maps->Finish();
  return Status::Ok();
}

size_t BodyMapRenderer::memory_bytes() const {
  return sizeof(*this) +
         (vertex_triangle_offsets_.capacity() + vertex_triangles_.capacity() + drawn_.capacity() +
          raster_faces_.capacity() + gap_triangles_.capacity() + fragment_cursor_.capacity() +
          gap_texels_.capacity() + fragment_offsets_.capacity()) *
             sizeof(uint32_t) +
         texel_raster_.capacity() * sizeof(TexelRaster) + row_spans_.capacity() * sizeof(uint32_t) +
         fragments_.capacity() * sizeof(GapFragment) + texel_gaps_.capacity() * sizeof(FoundGap) +
         gaps_per_texel_.capacity() +
         (posed_.capacity() + normals_.capacity() + offset_.capacity() + face_normals_.capacity()) *
             sizeof(Float3) +
         shading_.capacity() * sizeof(detail::TriangleShading) +
         raster_.capacity() * sizeof(detail::RasterTriangle) +
         (raster_boxes_.capacity() + all_boxes_.capacity()) * sizeof(detail::RasterBox) +
         placed_.capacity() * sizeof(detail::RasterVertex) + gap_tiles_.capacity();
}

}  // namespace drape
