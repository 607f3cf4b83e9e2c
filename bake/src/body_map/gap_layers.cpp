#include "body_map/gap_layers.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "body_map/pose_entries.h"

namespace drape::bake {
namespace {

struct Fragment {
  double depth;  // metres from the front plane
  uint32_t triangle;
  int8_t facing;  // +1 the ray along -z enters the body, -1 it leaves
};

// Front to back; at equal depth entering first (touching parts and zero-thickness slivers then
// make neither a negative count nor an empty gap), then by triangle: a total order, since a
// triangle covers a texel centre at most once.
bool FrontToBack(const Fragment& a, const Fragment& b) {
  if (a.depth != b.depth) return a.depth < b.depth;
  if (a.facing != b.facing) return a.facing > b.facing;
  return a.triangle < b.triangle;
}

struct GapCandidate {
  uint32_t upper;    // index in the sorted fragments of the leaving fragment; upper + 1 enters
  double thickness;  // metres
};

// The winding sweep of one texel's sorted fragments: appends its gaps thicker than
// kMinBodyMapGap to *gaps, front to back. Returns false, appending nothing, when the count goes
// negative or does not end at 0 (the texel keeps paper A's slab).
bool SweepWinding(std::span<const Fragment> sorted, std::vector<GapCandidate>* gaps) {
  const size_t first = gaps->size();
  int count = 0;
  for (size_t k = 0; k < sorted.size(); ++k) {
    count += sorted[k].facing;
    if (count < 0) break;
    // count == 0 before the last fragment: air up to the next fragment, which must enter (a
    // leaving one would make the count negative).
    if (count == 0 && k + 1 < sorted.size()) {
      const double thickness = sorted[k + 1].depth - sorted[k].depth;
      if (thickness > kMinBodyMapGap) {
        gaps->push_back({static_cast<uint32_t>(k), thickness});
      }
    }
  }
  if (count != 0) {
    gaps->resize(first);
    return false;
  }
  return true;
}

// Keeps the `keep` thickest of *gaps (equal thickness: the nearer), still front to back.
void KeepThickest(std::vector<GapCandidate>* gaps, size_t keep) {
  if (gaps->size() <= keep) return;
  std::sort(gaps->begin(), gaps->end(), [](const GapCandidate& a, const GapCandidate& b) {
    if (a.thickness != b.thickness) return a.thickness > b.thickness;
    return a.upper < b.upper;
  });
  gaps->resize(keep);
  std::sort(gaps->begin(), gaps->end(),
            [](const GapCandidate& a, const GapCandidate& b) { return a.upper < b.upper; });
}

// The decoded depth (metres from the view's plane) of array entry `entry` of `view`; for unorm16
// either the documented decoder (in double, DecodeDepthUnorm16) or the same formula in float
// (code / 65535 * depth_range), which a reader may use instead: the nesting check must hold for
// both.
float DecodedDepth(const BodyMapPose& pose, int view, size_t entry, bool float_decoder) {
  if (pose.depth_encoding == DepthEncoding::kFloat32) return pose.depth_f32[view][entry];
  const uint16_t code = pose.depth_u16[view][entry];
  return float_decoder ? static_cast<float>(code) / 65535.f * pose.depth_range
                       : DecodeDepthUnorm16(code, pose.depth_range);
}

// Decoded depths of one texel, metres from each view's plane: the slab (top from the front,
// bottom from the back), a gap (upper from the front, lower from the back) and the floor above
// the gap (the previous kept gap's lower, from the back; has_floor false for the first gap).
struct NestingDepths {
  float top = 0.f, bottom = 0.f, upper = 0.f, lower = 0.f, floor = 0.f;
  bool has_floor = false;
};

// top > upper > lower > bottom and floor (if any) > upper in asset z, computed exactly (double) and
// as a float reader would (front_z - d, and (front_z - depth_range) + d, each rounded to float).
bool StrictlyNested(const NestingDepths& d, float front_z, float depth_range) {
  const double back_z = double(front_z) - double(depth_range);
  const double top = double(front_z) - d.top, upper = double(front_z) - d.upper;
  const double lower = back_z + d.lower, bottom = back_z + d.bottom;
  const double ceiling = d.has_floor ? back_z + d.floor : top;
  if (!(ceiling > upper && upper > lower && lower > bottom)) return false;
  const float back_zf = front_z - depth_range;
  const float top_f = front_z - d.top, upper_f = front_z - d.upper;
  const float lower_f = back_zf + d.lower, bottom_f = back_zf + d.bottom;
  const float ceiling_f = d.has_floor ? back_zf + d.floor : top_f;
  return ceiling_f > upper_f && upper_f > lower_f && lower_f > bottom_f;
}

// Appends one background entry (depth: depth_range or 65535; normal: zeros) to every array of
// the pose's encodings.
void AppendBackground(BodyMapPose* pose) {
  for (int view = 0; view < 2; ++view) {
    if (pose->depth_encoding == DepthEncoding::kFloat32) {
      pose->depth_f32[view].push_back(pose->depth_range);
    } else {
      pose->depth_u16[view].push_back(kUnorm16Background);
    }
    switch (pose->normal_encoding) {
      case NormalEncoding::kFloat32:
        pose->normal_f32[view].insert(pose->normal_f32[view].end(), 3, 0.f);
        break;
      case NormalEncoding::kOct16:
        pose->normal_oct16[view].insert(pose->normal_oct16[view].end(), 2, uint16_t{0});
        break;
      case NormalEncoding::kRgb8:
        pose->normal_rgb8[view].insert(pose->normal_rgb8[view].end(), 3, uint8_t{0});
        break;
    }
  }
}

// Removes the last entry AppendBackground() added.
void PopEntry(BodyMapPose* pose) {
  const auto drop_last = [](auto& values, size_t count) {
    values.erase(values.end() - static_cast<std::ptrdiff_t>(std::min(count, values.size())),
                 values.end());
  };
  for (int view = 0; view < 2; ++view) {
    drop_last(pose->depth_f32[view], 1);
    drop_last(pose->depth_u16[view], 1);
    drop_last(pose->normal_f32[view], 3);
    drop_last(pose->normal_oct16[view], 2);
    drop_last(pose->normal_rgb8[view], 3);
  }
}

// Appends the arrays of `from` to those of `to`.
void AppendArrays(const BodyMapPose& from, BodyMapPose* to) {
  const auto append = [](const auto& src, auto& dst) {
    dst.insert(dst.end(), src.begin(), src.end());
  };
  for (int view = 0; view < 2; ++view) {
    append(from.depth_f32[view], to->depth_f32[view]);
    append(from.depth_u16[view], to->depth_u16[view]);
    append(from.normal_f32[view], to->normal_f32[view]);
    append(from.normal_oct16[view], to->normal_oct16[view]);
    append(from.normal_rgb8[view], to->normal_rgb8[view]);
  }
}

// Writes the texel's kept gaps, front to back, at entry `entry` of the gap layers: each gap goes
// to the next free layer when it stays strictly nested under both decoders (`depths` starts with
// the slab's decoded depths), else it is dropped and counted. Returns how many were stored.
size_t StoreTexelGaps(const MapRasterInput& input, std::span<const Fragment> sorted,
                      std::span<const GapCandidate> gaps, uint32_t raster_i, uint32_t raster_j,
                      const BodyMapPose& pose, float max_valid_depth, size_t entry,
                      NestingDepths depths[2], BodyMapPose* gap_layers, GapCounts* counts) {
  size_t stored = 0;  // gaps stored at this texel: the next one goes to gap_layers[stored]
  for (const GapCandidate& gap : gaps) {
    BodyMapPose* layer = &gap_layers[stored];
    const Fragment& upper = sorted[gap.upper];
    const Fragment& lower = sorted[gap.upper + 1];
    const double lower_depth = FragmentDepth(input, 1, lower.triangle, raster_i, raster_j);
    WriteDepth(layer, 0, entry, std::clamp(static_cast<float>(upper.depth), 0.f, max_valid_depth));
    WriteDepth(layer, 1, entry, std::clamp(static_cast<float>(lower_depth), 0.f, max_valid_depth));
    bool nested = true;
    for (int decoder = 0; decoder < 2; ++decoder) {
      depths[decoder].upper = DecodedDepth(*layer, 0, entry, decoder == 1);
      depths[decoder].lower = DecodedDepth(*layer, 1, entry, decoder == 1);
      nested = nested && StrictlyNested(depths[decoder], pose.front_z, pose.depth_range);
    }
    if (!nested) {  // restore the background; a later gap may take this layer
      WriteBackgroundDepth(layer, 0, entry);
      WriteBackgroundDepth(layer, 1, entry);
      ++counts->dropped_gaps;
      continue;
    }
    float normal[3];
    FragmentNormal(input, upper.triangle, raster_i, raster_j, -1.0, normal);
    WriteNormal(layer, 0, entry, {normal[0], normal[1], normal[2]});
    FragmentNormal(input, lower.triangle, raster_i, raster_j, 1.0, normal);
    WriteNormal(layer, 1, entry, {normal[0], normal[1], normal[2]});
    for (int decoder = 0; decoder < 2; ++decoder) {
      depths[decoder].floor = depths[decoder].lower;
      depths[decoder].has_floor = true;
    }
    ++stored;
  }
  return stored;
}

// A part thinner than kMinBodyMapGap at either end of the texel's ray (its centre on the
// silhouette of a part seen edge-on, whose two sides meet at one depth) is no body: layer 0 ends
// at the air next to it instead of taking that air in, and that air is no gap. The back first,
// as the renderer (air between two such parts leaves the front one). `dst` is layer 0's entry.
void TrimSlivers(const MapRasterInput& input, std::span<const Fragment> sorted, uint32_t raster_i,
                 uint32_t raster_j, float max_valid_depth, size_t dst, BodyMapPose* pose,
                 std::vector<GapCandidate>* gaps) {
  float normal[3];
  if (!gaps->empty()) {
    const Fragment& upper = sorted[gaps->back().upper];
    if (sorted.back().depth - sorted[gaps->back().upper + 1].depth <= kMinBodyMapGap) {
      const double back_depth = FragmentDepth(input, 1, upper.triangle, raster_i, raster_j);
      WriteDepth(pose, 1, dst, std::clamp(static_cast<float>(back_depth), 0.f, max_valid_depth));
      FragmentNormal(input, upper.triangle, raster_i, raster_j, -1.0, normal);
      WriteNormal(pose, 1, dst, {normal[0], normal[1], normal[2]});
      gaps->pop_back();
    }
  }
  if (!gaps->empty()) {
    const Fragment& lower = sorted[gaps->front().upper + 1];
    if (sorted[gaps->front().upper].depth - sorted.front().depth <= kMinBodyMapGap) {
      WriteDepth(pose, 0, dst, std::clamp(static_cast<float>(lower.depth), 0.f, max_valid_depth));
      FragmentNormal(input, lower.triangle, raster_i, raster_j, 1.0, normal);
      WriteNormal(pose, 0, dst, {normal[0], normal[1], normal[2]});
      gaps->erase(gaps->begin());
    }
  }
}

}  // namespace

Status BakeGapLayers(const MapRasterInput& input, std::span<const uint8_t> valid, uint32_t crop_i0,
                     uint32_t crop_j0, BodyMapPose* pose, GapCounts* out) {
  // A gap needs 4 fragments: enter, leave, enter, leave.
  constexpr uint32_t kMinGapFragments = 4;
  GapCounts counts;
  MapFragments fragments;
  if (!CollectFragmentsCpu(input, kMinGapFragments, &fragments)) {
    return Status(StatusCode::kInvalidArgument,
                  "BakeBodyMapPose: the gap layers would need more than 2^32 - 1 fragments "
                  "(triangles covering a texel centre); lower the resolution or set layers to 1");
  }
  const size_t max_gaps = pose->layers - 1u;
  const float max_valid_depth = std::nextafter(pose->depth_range, 0.f);
  // The gap layers k = 1 .. layers - 1, one entry per texel of pose->gap_texels, each held as a
  // pose with only those arrays (so the encoders and decoders above apply).
  BodyMapPose gap_layers[kMaxBodyMapLayers - 1];
  for (size_t k = 0; k < max_gaps; ++k) {
    gap_layers[k].depth_range = pose->depth_range;
    gap_layers[k].depth_encoding = pose->depth_encoding;
    gap_layers[k].normal_encoding = pose->normal_encoding;
  }
  pose->gap_texels.clear();
  std::vector<Fragment> sorted;
  std::vector<GapCandidate> gaps;
  for (uint32_t j = 0; j < pose->height; ++j) {
    for (uint32_t i = 0; i < pose->width; ++i) {
      const uint32_t raster_i = i + crop_i0, raster_j = j + crop_j0;
      const size_t src = static_cast<size_t>(raster_j) * input.width + raster_i;
      const uint32_t begin = fragments.offsets[src], end = fragments.offsets[src + 1];
      if (end - begin < kMinGapFragments) continue;
      sorted.clear();
      for (uint32_t f = begin; f < end; ++f) {
        sorted.push_back({fragments.depth[f], fragments.triangle[f], fragments.facing[f]});
      }
      std::sort(sorted.begin(), sorted.end(), FrontToBack);
      gaps.clear();
      if (!SweepWinding(sorted, &gaps) || gaps.empty()) continue;
      if (!valid[src]) {  // background in layer 0 (OSMesa's coverage differs from the CPU's)
        counts.dropped_gaps += gaps.size();
        continue;
      }
      const size_t dst = static_cast<size_t>(j) * pose->width + i;  // dense: also layer 0's entry
      TrimSlivers(input, sorted, raster_i, raster_j, max_valid_depth, dst, pose, &gaps);
      if (gaps.empty()) continue;
      counts.dropped_gaps += gaps.size() > max_gaps ? gaps.size() - max_gaps : 0;
      KeepThickest(&gaps, max_gaps);
      NestingDepths depths[2];  // [0] documented decoder, [1] float decoder
      for (int decoder = 0; decoder < 2; ++decoder) {
        depths[decoder].top = DecodedDepth(*pose, 0, dst, decoder == 1);
        depths[decoder].bottom = DecodedDepth(*pose, 1, dst, decoder == 1);
      }
      const size_t entry = pose->gap_texels.size();  // this texel's entry in every gap layer
      for (size_t k = 0; k < max_gaps; ++k) AppendBackground(&gap_layers[k]);
      const size_t stored = StoreTexelGaps(input, sorted, gaps, raster_i, raster_j, *pose,
                                           max_valid_depth, entry, depths, gap_layers, &counts);
      if (stored == 0) {  // every gap was dropped: the texel is not listed
        for (size_t k = 0; k < max_gaps; ++k) PopEntry(&gap_layers[k]);
        continue;
      }
      pose->gap_texels.push_back(static_cast<uint32_t>(dst));
      ++counts.gap_texels;
    }
  }
  for (size_t k = 0; k < max_gaps; ++k) AppendArrays(gap_layers[k], pose);
  *out = counts;
  return Status::Ok();
}

}  // namespace drape::bake
