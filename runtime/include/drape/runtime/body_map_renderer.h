#pragma once
// Paper A's body maps for any pose the engine drives: skins the stored bind mesh with the frame's
// skinning matrices, offsets it by epsilon along its vertex normals and rasterizes the front and
// back surfaces and the first air gap between them (along the view axis the options name)
// straight into a BodyMapCollider, over the window a region box allows. How it works and what it
// costs: docs/ALGORITHMS.md §7.9, docs/PERFORMANCE.md.
//
//   BodyMapRenderer renderer;
//   renderer.Init(RenderMeshOf(asset), {.texel_size = 0.002f, .epsilon = asset.body_maps.epsilon});
//   BodyMapCollider maps;
//   renderer.Render(pose.skinning(), &maps, &garment_reach);  // per frame
//   maps.CollideBatch(previous, positions, velocities, flags, params);
//
// RenderMeshOf(asset) is the bake's render mesh (the bind mesh simplified to within 1 mm, about
// half of a person's triangles, a fifth of a dense mesh's) when the asset has one: the render
// costs less and the surface moves by at most that. Baked poses (BodyMapCollider::Build) stay exact for the poses a
// bake saw; both hold up to three air gaps per texel (options.air_gaps).

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "drape/formats/mesh_data.h"
#include "drape/formats/status.h"
#include "drape/formats/types.h"
#include "drape/runtime/body_map_collider.h"

namespace drape {

namespace detail {
struct RasterWindow;     // body_map/raster_triangle.h
struct RasterTriangle;   // body_map/raster_triangle.h
struct RasterBox;        // body_map/raster_triangle.h
struct RasterVertex;     // body_map/raster_triangle.h
struct TriangleShading;  // body_map/raster_triangle.h
}  // namespace detail

struct BodyMapRenderOptions {
  float texel_size = 0.002f;  // metres, [1e-4, 1]: the maps' resolution
  float epsilon = 0.005f;     // metres, [0, 1]: the surface offset along the vertex normals
  DepthSampling sampling = DepthSampling::kNearest;
  uint32_t max_side = 8192;  // texels, [16, 16384]: a pose whose window needs more is an error
  // Texel corners lie at grid_x + k * texel_size (and y alike), every frame, so the grid does not
  // slide under the body as it moves; a baked pose's origin puts both on one grid. Finite.
  float grid_x = 0.f, grid_y = 0.f;  // metres, view frame (x', y')
  // The asset axis the maps are seen along (body_map_data.h); a baked pose's view_axis keeps
  // rendered and baked maps in one frame.
  BodyMapViewAxis view_axis = BodyMapViewAxis::kZ;
  // Air gaps per texel, [0, 3] (the collider's layers() is 1 + the deepest found): the air below
  // the front surface, gap by gap going down, from raster passes that count the surfaces along
  // each texel's ray. Without them the air between an arm and the chest is inside; a texel whose
  // surfaces do not nest there (an open or inconsistently wound mesh), or whose ray crosses more
  // than 1024 surfaces, keeps its slab. They cost 1.3-1.7x the render without them, the most
  // where parts sink into each other.
  uint32_t air_gaps = 3;
};

// An asset-frame box: only triangles that reach it are drawn and the window is cut to it. The
// maps answer for points inside the box; outside it they may miss body parts (a scene's garment
// reach, padded by what a particle moves in a step).
struct RenderRegion {
  static constexpr float kInf = std::numeric_limits<float>::infinity();
  Float3 min{-kInf, -kInf, -kInf};  // metres
  Float3 max{kInf, kInf, kInf};
};

// Maps the engine rendered itself (on its GPU, say): both views over one texel grid, in the
// caller's row-major arrays; texel (i, j) is entry j * width + i and covers x' in
// [origin_x + i * texel_size, + texel_size), y' alike, in the view frame of view_axis
// (body_map_data.h; x' = x, y' = y for z). z' values are the view-frame depth coordinate of the
// surfaces offset by epsilon: the front surface is the one nearest +z' (a GPU depth buffer read
// back and mapped through the camera's near/far planes). A texel is body where both are finite
// and front_z >= back_z; NaN or an infinity marks background. Normals are in the asset frame.
struct RenderedMapsView {
  uint32_t width = 0, height = 0;         // texels, [1, 16384] each
  float origin_x = 0.f, origin_y = 0.f;   // metres, finite, view frame
  float texel_size = 0.f;                 // metres, [1e-6, 1e3]
  std::span<const float> front_z;         // width * height
  std::span<const float> back_z;          // width * height
  std::span<const Float3> front_normals;  // width * height, outward; length is ignored
  std::span<const Float3> back_normals;   // width * height, outward (mostly away from the axis)
  BodyMapViewAxis view_axis = BodyMapViewAxis::kZ;
};

// What the last Render drew.
struct BodyMapRenderStats {
  uint32_t width = 0, height = 0;  // texels of the window
  uint32_t triangles_drawn = 0;    // triangles that reach the region
  uint32_t valid_texels = 0;       // texels the body covers
  uint32_t gap_texels = 0;         // texels holding an air gap
  uint32_t grew = 0;               // Render calls that had to enlarge the buffers (allocated)
};

class BodyMapRenderer {
 public:
  BodyMapRenderer();
  ~BodyMapRenderer();
  BodyMapRenderer(const BodyMapRenderer&);
  BodyMapRenderer(BodyMapRenderer&&) noexcept;
  BodyMapRenderer& operator=(const BodyMapRenderer&);
  BodyMapRenderer& operator=(BodyMapRenderer&&) noexcept;

  // Keeps a reference to `mesh`, which must outlive the renderer. Checks the mesh (indices,
  // influences, finite positions) and the options, and reserves buffers for 1.5x the bind
  // pose's window (allocates; the first Render into a collider allocates its grid once). On error
  // the renderer is empty and Render fails.
  Status Init(const MeshData& mesh, const BodyMapRenderOptions& options);

  // Renders the pose `skinning` (one matrix per joint, SkeletonPose::skinning()) into *maps,
  // replacing what it held (clip -1, time 0). region: null for the whole body. No allocation
  // unless the window, or the air gaps' texels and surfaces, outgrow every earlier pose's
  // (stats().grew counts those calls). Identical bits at any thread count. Too
  // few matrices, a non-finite skinned vertex, an empty or inverted region, or a window over
  // max_side: kInvalidArgument naming the reason, and *maps empty. Nothing of the body within the
  // region is Ok with *maps empty: skip the maps this frame.
  Status Render(std::span<const Mat34> skinning, BodyMapCollider* maps,
                const RenderRegion* region = nullptr);

  // Copies maps the engine rendered into *maps (the layout above): no allocation when *maps held
  // a grid at least as large before. A size, an origin or a texel size out of range is
  // kInvalidArgument naming it, and *maps empty.
  static Status Load(const RenderedMapsView& view, BodyMapCollider* maps,
                     DepthSampling sampling = DepthSampling::kNearest);

  bool empty() const { return mesh_ == nullptr; }
  const BodyMapRenderOptions& options() const { return options_; }
  const BodyMapRenderStats& stats() const { return stats_; }
  // The skinned, unoffset vertices of the last successful Render (asset frame, metres).
  std::span<const Float3> posed_vertices() const { return posed_; }
  size_t memory_bytes() const;  // the renderer's buffers, not the collider's

 private:
  struct FoundGap {      // one air gap the gap search found
    float upper, lower;  // view-frame z of its boundaries
    uint32_t upper_face, lower_face;
  };
  struct GapFragment {    // one surface on a gap texel's ray
    float z;              // view-frame depth at the texel centre
    uint32_t face_flags;  // the triangle, | kEnteringBit, | kCountsOnceBit
  };
  struct Window {                           // the texel grid of one render
    double origin_x = 0.0, origin_y = 0.0;  // metres, a multiple of the texel size
    uint32_t width = 0, height = 0;         // texels
    int sub_bits = 0;  // the raster grid: 2^sub_bits units per texel (raster_triangle.h)
  };
  detail::RasterWindow RasterWindowOf(const Window& window) const;
  // The triangles of the last raster set-up that cover a texel centre, in draw order.
  std::span<const uint32_t> RasterFaces() const;
  std::span<const detail::RasterTriangle> RasterSetUps() const;
  std::span<const detail::RasterBox> RasterBoxes() const;
  Status CheckRegion(const RenderRegion& region) const;
  Status SkinAndOffset(std::span<const Mat34> skinning);
  void ComputeNormals();
  void CullTriangles(const RenderRegion& region);
  Status PlaceWindow(const RenderRegion& region, Window* window) const;
  void Rasterize(const Window& window, BodyMapCollider* maps);
  // The gap search (body_map_renderer_gaps.cpp).
  void FindGaps(const Window& window, BodyMapCollider* maps);
  void SelectGapTexels(const BodyMapCollider& maps, size_t texels);
  void CollectGapFragments(const Window& window);
  uint32_t SearchTexelGaps(uint32_t candidate, BodyMapCollider* maps, FoundGap* found);
  void PublishGaps(const Window& window, BodyMapCollider* maps);
  void SetUpShading(const Window& window);
  void ShadeNormals(const Window& window, BodyMapCollider* maps) const;
  void Publish(const Window& window, BodyMapCollider* maps);
  void Reserve(size_t texels);

  const MeshData* mesh_ = nullptr;
  BodyMapRenderOptions options_;
  uint32_t joints_needed_ = 0;               // 1 + the largest joint index the influences name
  bool every_vertex_in_a_triangle_ = false;  // the drawn box is then the vertices' box
  BodyMapRenderStats stats_;
  // Per vertex: the triangles around it (compressed rows), for gathered normals.
  std::vector<uint32_t> vertex_triangle_offsets_;
  std::vector<uint32_t> vertex_triangles_;
  std::vector<Float3> posed_;         // skinned vertices
  std::vector<Float3> normals_;       // unit vertex normals (zero where undefined)
  std::vector<Float3> offset_;        // posed + epsilon * normal
  std::vector<Float3> face_normals_;  // per triangle, unnormalised (twice the area)
  std::vector<uint32_t> drawn_;       // triangles that reach the region, ascending
  // The drawn triangles' boxes; then those covering a texel centre (raster_count_ of them, in
  // draw order): the triangle, its box within the window, its set-up in window coordinates.
  std::vector<detail::RasterVertex> placed_;  // every vertex in the window (raster set-up)
  std::vector<detail::RasterBox> all_boxes_;
  size_t raster_count_ = 0;
  std::vector<uint32_t> raster_faces_;
  std::vector<detail::RasterBox> raster_boxes_;
  std::vector<detail::RasterTriangle> raster_;
  std::vector<detail::TriangleShading> shading_;  // per triangle; set for raster_faces_
  // What the raster pass keeps per texel, in one place: a fragment touches one entry (and its
  // slab), not a cache line per field (a body's triangle rows hold one or two fragments each).
  // 24 bytes.
  struct TexelRaster {
    uint32_t top_face;     // the triangle of the front surface
    uint32_t bottom_face;  // the triangle of the back surface
    // The gap search (air_gaps): the highest surface leaving the body going along -z (the first
    // candidate upper boundary) and its triangle, the lowest surface entering the body, and how
    // many surfaces the ray crosses (then the fragments still to collect, 0 off the gap texels).
    float exit_z;
    float lowest_entry_z;
    uint32_t exit_face;
    uint32_t fragment_count;
  };
  std::vector<TexelRaster> texel_raster_;  // per texel of the window
  // Per row of the window: the columns [first, second) the drawn triangles reach (the raster
  // pass's); the passes after it treat the rest of the row as background.
  std::vector<uint32_t> row_spans_;
  std::vector<uint32_t> fragment_cursor_;   // per texel: where its next fragment goes
  std::vector<uint32_t> gap_texels_;        // texels where a gap may lie, ascending
  std::vector<uint32_t> fragment_offsets_;  // per gap texel: its fragments' start, and the end
  std::vector<GapFragment> fragments_;      // every surface on the gap texels' rays, in draw order
  std::vector<uint8_t> gaps_per_texel_;     // per gap texel: the gaps found
  std::vector<FoundGap> texel_gaps_;        // per gap texel: air_gaps slots, top down
  std::vector<uint8_t> gap_tiles_;          // per 8 x 8 tile: whether a gap texel lies in it
  std::vector<uint32_t> gap_triangles_;     // positions in drawn_ of the triangles on those tiles
  size_t reserved_texels_ = 0;
  bool grew_ = false;  // this Render enlarged the window or the collider's gap storage
};

}  // namespace drape
