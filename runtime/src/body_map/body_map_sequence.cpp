// BodyMapSequence: one clip's baked poses, answered nearest in time or blended between the two
// that bracket it.
#include "drape/runtime/body_map_sequence.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "tasks/parallel_for.h"

namespace drape {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

bool SameGrid(const BodyMapCollider& a, const BodyMapCollider& b) {
  return a.width() == b.width() && a.height() == b.height() && a.origin_x() == b.origin_x() &&
         a.origin_y() == b.origin_y() && a.texel_size() == b.texel_size() &&
         a.sampling() == b.sampling() && a.layers() == b.layers() && a.view_axis() == b.view_axis();
}

}  // namespace

Status BodyMapSequence::Build(std::span<const BodyMapPose> poses, DepthSampling sampling,
                              PoseBlend blend) {
  poses_.clear();
  blend_ = blend;
  if (poses.empty()) {
    return Status(StatusCode::kInvalidArgument, "BodyMapSequence::Build: no poses");
  }
  if (blend != PoseBlend::kNearest && blend != PoseBlend::kBracket) {
    return Status(StatusCode::kInvalidArgument, "BodyMapSequence::Build: unknown pose blend");
  }
  for (size_t k = 0; k < poses.size(); ++k) {
    const std::string where = "BodyMapSequence::Build: pose " + std::to_string(k);
    if (!std::isfinite(poses[k].time)) {
      return Status(StatusCode::kInvalidArgument, where + " has a non-finite time");
    }
    if (poses[k].clip != poses[0].clip) {
      return Status(StatusCode::kInvalidArgument,
                    where + " belongs to clip " + std::to_string(poses[k].clip) + ", pose 0 to " +
                        std::to_string(poses[0].clip));
    }
    if (k > 0 && poses[k].time < poses[k - 1].time) {
      return Status(
          StatusCode::kInvalidArgument,
          where + " is earlier than pose " + std::to_string(k - 1) + " (not sorted by time)");
    }
  }
  poses_.resize(poses.size());
  for (size_t k = 0; k < poses.size(); ++k) {
    Status status = poses_[k].Build(poses[k], sampling);
    if (!status.ok()) {
      poses_.clear();
      return Status(status.code(),
                    "BodyMapSequence::Build: pose " + std::to_string(k) + ": " + status.message());
    }
  }
  return Status::Ok();
}

const BodyMapCollider& BodyMapSequence::At(float time, BodyMapCollider* scratch) const {
  if (poses_.empty()) return empty_;
  if (!(time > poses_.front().time())) return poses_.front();  // also NaN
  if (!(time < poses_.back().time())) return poses_.back();
  // First pose later than `time`; its predecessor is at or before it.
  const auto later = std::upper_bound(
      poses_.begin(), poses_.end(), time,
      [](float value, const BodyMapCollider& pose) { return value < pose.time(); });
  const BodyMapCollider& b = *later;
  const BodyMapCollider& a = *(later - 1);
  const float w = (time - a.time()) / (b.time() - a.time());  // in (0, 1) up to rounding
  const bool a_nearer = w <= 0.5f;
  if (blend_ != PoseBlend::kBracket || scratch == nullptr || !(w > 0.f && w < 1.f) ||
      !SameGrid(a, b)) {
    return a_nearer ? a : b;
  }
  BodyMapCollider& out = *scratch;
  const BodyMapCollider& nearer = a_nearer ? a : b;
  const size_t n = a.slabs_.size();
  out.width_ = a.width_;
  out.height_ = a.height_;
  out.width_f_ = a.width_f_;
  out.height_f_ = a.height_f_;
  out.origin_x_ = a.origin_x_;
  out.origin_y_ = a.origin_y_;
  out.texel_size_ = a.texel_size_;
  out.inv_texel_size_ = a.inv_texel_size_;
  out.sampling_ = a.sampling_;
  out.view_axis_ = a.view_axis_;
  out.clip_ = a.clip_;
  out.time_ = time;
  out.stats_ = nearer.stats_;
  out.slabs_.resize(n);  // allocates only when the scratch has never held this grid size
  out.normals_.resize(n);
  const int64_t count = static_cast<int64_t>(n);
  detail::ParallelFor(count, count > 65536 ? 16384 : count, [&](int64_t k) {
    const BodyMapCollider::Slab sa = a.slabs_[k], sb = b.slabs_[k];
    const bool valid_a = sa.top >= sa.bottom, valid_b = sb.top >= sb.bottom;
    BodyMapCollider::Slab slab{-kInf, kInf};
    if (valid_a && valid_b) {
      slab = {(1.f - w) * sa.top + w * sb.top, (1.f - w) * sa.bottom + w * sb.bottom};
    } else if (valid_a && a_nearer) {
      slab = sa;
    } else if (valid_b && !a_nearer) {
      slab = sb;
    }
    out.slabs_[k] = slab;
    out.normals_[k] = nearer.normals_[k];
  });
  BlendGaps(a, b, w, &out);
  out.Finish();
  return out;
}

void BodyMapSequence::BlendGaps(const BodyMapCollider& a, const BodyMapCollider& b, float w,
                                BodyMapCollider* out) {
  using Slab = BodyMapCollider::Slab;
  const uint32_t layers = a.gap_layers_;
  out->gap_layers_ = layers;
  out->blocks_w_ = a.blocks_w_;
  out->blocks_h_ = a.blocks_h_;
  out->gaps_.clear();
  out->gap_normals_.clear();
  if (layers == 0) {
    out->gap_texel_bits_.clear();
    out->gap_word_first_.clear();
    return;
  }
  const size_t words = a.gap_texel_bits_.size();
  out->gap_texel_bits_.assign(words, 0u);  // no allocation once the scratch held this grid
  // Room for both poses' gaps: a blend never keeps more gap texels than the two have together.
  out->gaps_.reserve(a.gaps_.size() + b.gaps_.size());
  out->gap_normals_.reserve(a.gap_normals_.size() + b.gap_normals_.size());
  const BodyMapCollider& nearer = w <= 0.5f ? a : b;
  for (size_t word = 0; word < words; ++word) {
    uint32_t candidates = a.gap_texel_bits_[word] | b.gap_texel_bits_[word];
    while (candidates != 0) {
      const int bit = std::countr_zero(candidates);
      candidates &= candidates - 1;
      const size_t k = word * 32 + static_cast<size_t>(bit);
      const Slab slab = out->slabs_[k];
      if (!(slab.top >= slab.bottom)) continue;  // background has no gaps
      const bool both =
          a.slabs_[k].top >= a.slabs_[k].bottom && b.slabs_[k].top >= b.slabs_[k].bottom;
      const uint32_t texel = static_cast<uint32_t>(k);
      const int64_t base_a = a.GapBaseAt(texel), base_b = b.GapBaseAt(texel);
      const int64_t base_nearer = nearer.GapBaseAt(texel);
      Slab gaps[kMaxBodyMapLayers];
      bool more = true;
      for (uint32_t g = 0; g < layers; ++g) {
        Slab gap{-kInf, kInf};
        if (both) {
          // A convex combination keeps the strict order top > upper > lower > ... > bottom.
          if (base_a >= 0 && base_b >= 0) {
            const Slab ga = a.gaps_[base_a + g], gb = b.gaps_[base_b + g];
            if (ga.top > ga.bottom && gb.top > gb.bottom) {
              gap = {(1.f - w) * ga.top + w * gb.top, (1.f - w) * ga.bottom + w * gb.bottom};
            }
          }
        } else if (base_nearer >= 0) {  // the slab is the nearer pose's: so are its gaps
          gap = nearer.gaps_[base_nearer + g];
        }
        more = more && gap.top > gap.bottom;  // the first gap one pose lacks ends the list
        gaps[g] = more ? gap : Slab{-kInf, kInf};
      }
      if (!(gaps[0].top > gaps[0].bottom)) continue;
      // Kept gaps exist in the nearer pose (blended ones in both), so its normals are there.
      out->gap_texel_bits_[word] |= 1u << bit;
      out->gaps_.insert(out->gaps_.end(), gaps, gaps + layers);
      out->gap_normals_.insert(out->gap_normals_.end(), nearer.gap_normals_.begin() + base_nearer,
                               nearer.gap_normals_.begin() + base_nearer + layers);
    }
  }
  out->CountGapsBeforeWords();
}

size_t BodyMapSequence::memory_bytes() const {
  size_t bytes = sizeof(*this);
  for (const BodyMapCollider& pose : poses_) bytes += pose.memory_bytes();
  return bytes;
}

}  // namespace drape
