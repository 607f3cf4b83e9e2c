#pragma once
// cereal serialisation of the .drape schema. Private to drape_formats: only asset_file.cpp
// instantiates archives. Every type carries CEREAL_CLASS_VERSION and refuses versions it does
// not know, naming the type. Arrays are bounded by the payload size before anything is
// allocated, so a corrupt count cannot make the loader allocate gigabytes.

#include <algorithm>
#include <cereal/archives/json.hpp>
#include <cereal/archives/portable_binary.hpp>
#include <cereal/cereal.hpp>
#include <cereal/types/string.hpp>
#include <cstdint>
#include <stdexcept>
#include <streambuf>
#include <string>
#include <type_traits>
#include <vector>

#include "drape/formats/character_asset.h"

namespace drape {

// Thrown inside the decoder only; asset_file.cpp turns it into a Status.
struct DecodeError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

namespace detail {

// The payload stream being decoded on this thread, so array and string loads can bound their
// counts by the bytes that are actually left before they allocate anything. Set by the decoder.
class SpanBuffer : public std::streambuf {
 public:
  SpanBuffer(const uint8_t* data, size_t size) {
    char* begin = const_cast<char*>(reinterpret_cast<const char*>(data));
    setg(begin, begin, begin + size);
  }
  size_t consumed() const { return static_cast<size_t>(gptr() - eback()); }
  size_t remaining() const { return static_cast<size_t>(egptr() - gptr()); }
};
inline thread_local const SpanBuffer* g_decoding = nullptr;
// The header's format version of the payload being decoded (0 when not decoding a file), so a
// type can refuse a class version that this format version never contained.
inline thread_local uint32_t g_format_version = 0;

// Fewest payload bytes one element of T can take when encoded: a count of n elements needs at
// least n times this many bytes, which is checked before the vector is allocated.
template <class T>
constexpr size_t MinEncodedBytes() {
  if constexpr (std::is_arithmetic_v<T> || std::is_same_v<T, Float3> || std::is_same_v<T, Quat> ||
                std::is_same_v<T, Mat34> || std::is_same_v<T, Plane> ||
                std::is_same_v<T, Transform>) {
    return sizeof(T);
  } else if constexpr (std::is_same_v<T, std::string>) {
    return sizeof(cereal::size_type);  // the length
  } else {
    // A struct of this schema: at least its class version and one array length.
    return sizeof(uint32_t) + sizeof(cereal::size_type);
  }
}

inline void CheckCount(uint64_t count, size_t element_bytes) {
  if (g_decoding == nullptr) return;  // not decoding a payload (e.g. JSON)
  const uint64_t available = g_decoding->remaining();
  if (count > available / element_bytes) {
    throw DecodeError("an array of " + std::to_string(count) + " elements of at least " +
                      std::to_string(element_bytes) + " bytes exceeds the " +
                      std::to_string(available) + " payload bytes left");
  }
}

// Strings through the same bound (cereal's own loader would resize to any length it reads).
template <class Archive>
void LoadString(Archive& ar, std::string& text) {
  cereal::size_type length = 0;
  ar(cereal::make_size_tag(length));
  CheckCount(length, 1);
  text.resize(static_cast<size_t>(length));
  ar(cereal::binary_data(text.data(), text.size()));
}

inline void CheckVersion(uint32_t version, uint32_t known, const char* type) {
  if (version != known) {
    throw DecodeError(std::string("unsupported version ") + std::to_string(version) + " of " +
                      type + " (this build reads version " + std::to_string(known) + ")");
  }
}

// For types whose older class versions are still read: [oldest, newest].
inline void CheckVersionRange(uint32_t version, uint32_t oldest, uint32_t newest,
                              const char* type) {
  if (version < oldest || version > newest) {
    throw DecodeError(std::string("unsupported version ") + std::to_string(version) + " of " +
                      type + " (this build reads versions " + std::to_string(oldest) + " to " +
                      std::to_string(newest) + ")");
  }
}

template <class T>
constexpr bool kIsFlatFloats = std::is_same_v<T, Float3> || std::is_same_v<T, Quat> ||
                               std::is_same_v<T, Mat34> || std::is_same_v<T, Plane>;

template <class Archive, class T>
void SaveArray(Archive& ar, const std::vector<T>& values) {
  ar(cereal::make_size_tag(static_cast<cereal::size_type>(values.size())));
  constexpr bool binary = std::is_same_v<Archive, cereal::PortableBinaryOutputArchive>;
  if constexpr (binary && std::is_arithmetic_v<T>) {
    ar(cereal::binary_data(values.data(), values.size() * sizeof(T)));
  } else if constexpr (binary && kIsFlatFloats<T>) {
    static_assert(sizeof(T) % sizeof(float) == 0);
    ar(cereal::binary_data(reinterpret_cast<const float*>(values.data()),
                           values.size() * sizeof(T)));
  } else {
    for (const T& v : values) ar(v);
  }
}

template <class Archive, class T>
void LoadArray(Archive& ar, std::vector<T>& values) {
  cereal::size_type count = 0;
  ar(cereal::make_size_tag(count));
  CheckCount(count, MinEncodedBytes<T>());
  values.resize(static_cast<size_t>(count));
  if constexpr (std::is_same_v<T, std::string>) {
    for (T& v : values) LoadString(ar, v);
  } else if constexpr (std::is_arithmetic_v<T>) {
    ar(cereal::binary_data(values.data(), values.size() * sizeof(T)));
  } else if constexpr (kIsFlatFloats<T>) {
    ar(cereal::binary_data(reinterpret_cast<float*>(values.data()), values.size() * sizeof(T)));
  } else {
    for (T& v : values) ar(v);
  }
}

}  // namespace detail

// Small value types: fixed layouts, no version of their own (versioned through their owners).
template <class Archive>
void serialize(Archive& ar, Float3& v) {
  ar(cereal::make_nvp("x", v.x), cereal::make_nvp("y", v.y), cereal::make_nvp("z", v.z));
}
template <class Archive>
void serialize(Archive& ar, Quat& q) {
  ar(cereal::make_nvp("x", q.x), cereal::make_nvp("y", q.y), cereal::make_nvp("z", q.z),
     cereal::make_nvp("w", q.w));
}
template <class Archive>
void serialize(Archive& ar, Mat34& m) {
  ar(cereal::make_nvp("m", m.m));
}
template <class Archive>
void serialize(Archive& ar, Transform& t) {
  ar(cereal::make_nvp("translation", t.translation), cereal::make_nvp("rotation", t.rotation),
     cereal::make_nvp("scale", t.scale));
}
template <class Archive>
void serialize(Archive& ar, Plane& p) {
  ar(cereal::make_nvp("normal", p.normal), cereal::make_nvp("offset", p.offset));
}
template <class Archive>
void serialize(Archive& ar, Obb& o) {
  ar(cereal::make_nvp("center", o.center), cereal::make_nvp("axes", o.axes),
     cereal::make_nvp("half_extents", o.half_extents));
}

// A named reference to a vector, so every array goes through the bounded loader and the
// binary fast path, and still shows up as a named JSON array.
template <class T>
struct ArrayRef {
  std::vector<T>* values;
};
template <class Archive, class T>
void save(Archive& ar, const ArrayRef<T>& ref) {
  detail::SaveArray(ar, *ref.values);
}
template <class Archive, class T>
void load(Archive& ar, ArrayRef<T>& ref) {
  detail::LoadArray(ar, *ref.values);
}
template <class Archive>
void Text(Archive& ar, const char* name, std::string& text) {
  if constexpr (Archive::is_loading::value) {
    detail::LoadString(ar, text);
  } else {
    ar(cereal::make_nvp(name, text));
  }
}

template <class Archive, class T>
void Array(Archive& ar, const char* name, std::vector<T>& values) {
  ArrayRef<T> ref{&values};
  ar(cereal::make_nvp(name, ref));
}

template <class Archive>
void serialize(Archive& ar, AssetInfo& info, const uint32_t version) {
  detail::CheckVersion(version, 1, "AssetInfo");
  Text(ar, "source_name", info.source_name);
  Text(ar, "tool_version", info.tool_version);
  ar(cereal::make_nvp("unit_scale", info.unit_scale));
  Text(ar, "up_axis", info.up_axis);
  ar(cereal::make_nvp("source_to_asset", info.source_to_asset));
}

template <class Archive>
void serialize(Archive& ar, SkeletonData& s, const uint32_t version) {
  detail::CheckVersion(version, 1, "SkeletonData");
  Array(ar, "joint_names", s.joint_names);
  Array(ar, "parents", s.parents);
  Array(ar, "rest_local", s.rest_local);
  Array(ar, "inverse_bind", s.inverse_bind);
}

template <class Archive>
void serialize(Archive& ar, ClipData& c, const uint32_t version) {
  detail::CheckVersion(version, 1, "ClipData");
  Text(ar, "name", c.name);
  ar(cereal::make_nvp("duration", c.duration), cereal::make_nvp("sample_rate", c.sample_rate),
     cereal::make_nvp("frame_count", c.frame_count));
  Array(ar, "keys", c.keys);
}

template <class Archive>
void serialize(Archive& ar, MeshData& m, const uint32_t version) {
  detail::CheckVersion(version, 1, "MeshData");
  Array(ar, "positions", m.positions);
  Array(ar, "triangles", m.triangles);
  Array(ar, "influence_offsets", m.influence_offsets);
  Array(ar, "influence_joints", m.influence_joints);
  Array(ar, "influence_weights", m.influence_weights);
}

// Version 1 (format version 1): always dense, no layout field and no span table. Version 2
// (format version 2): `layout` and the span table follow normal_encoding. Version 3 (format
// version 3): `layers` (uint8) follows `layout`, before the span table, and `gap_texels`
// follows the span table. Version 4 (format version 7): `view_axis` (uint8) follows `layers`.
// Writing is always version 4; a version-1 pose loads as dense with an empty span table,
// versions 1 and 2 load with one layer, versions 1 to 3 with view axis z. Format version N holds
// exactly class version min(N, 3) up to 6 and 4 from 7 on (what its writer wrote; format
// versions 4 to 6 changed other classes): a newer class in an older format is impossible, an
// older one in a newer format is a forgery that would not re-encode to the same bytes.
inline uint32_t BodyMapPoseVersionOfFormat(uint32_t format_version) {
  return format_version >= 7 ? 4u : std::min(format_version, 3u);
}

template <class Archive>
void serialize(Archive& ar, BodyMapPose& p, const uint32_t version) {
  detail::CheckVersionRange(version, 1, 4, "BodyMapPose");
  if constexpr (Archive::is_loading::value) {
    if (detail::g_format_version != 0 &&
        version != BodyMapPoseVersionOfFormat(detail::g_format_version)) {
      throw DecodeError("BodyMapPose version " + std::to_string(version) + " in a format version " +
                        std::to_string(detail::g_format_version) + " file");
    }
  }
  ar(cereal::make_nvp("clip", p.clip), cereal::make_nvp("time", p.time),
     cereal::make_nvp("width", p.width), cereal::make_nvp("height", p.height),
     cereal::make_nvp("origin_x", p.origin_x), cereal::make_nvp("origin_y", p.origin_y),
     cereal::make_nvp("texel_size", p.texel_size), cereal::make_nvp("front_z", p.front_z),
     cereal::make_nvp("depth_range", p.depth_range),
     cereal::make_nvp("depth_encoding", p.depth_encoding),
     cereal::make_nvp("normal_encoding", p.normal_encoding));
  if (version >= 2) {
    ar(cereal::make_nvp("layout", p.layout));
    if (version >= 3) {
      ar(cereal::make_nvp("layers", p.layers));
    } else {
      p.layers = 1;
    }
    if (version >= 4) {
      ar(cereal::make_nvp("view_axis", p.view_axis));
    } else {
      p.view_axis = BodyMapViewAxis::kZ;
    }
    Array(ar, "row_span_offsets", p.row_span_offsets);
    Array(ar, "span_begin", p.span_begin);
    Array(ar, "span_texel_offsets", p.span_texel_offsets);
    if (version >= 3) {
      Array(ar, "gap_texels", p.gap_texels);
    } else {
      p.gap_texels.clear();
    }
  } else {
    p.layout = BodyMapLayout::kDense;
    p.layers = 1;
    p.view_axis = BodyMapViewAxis::kZ;
    p.gap_texels.clear();
    p.row_span_offsets.clear();
    p.span_begin.clear();
    p.span_texel_offsets.clear();
  }
  static const char* const kViews[2] = {"front", "back"};
  for (int view = 0; view < 2; ++view) {
    const std::string v = kViews[view];
    Array(ar, ("depth_f32_" + v).c_str(), p.depth_f32[view]);
    Array(ar, ("depth_u16_" + v).c_str(), p.depth_u16[view]);
    Array(ar, ("normal_f32_" + v).c_str(), p.normal_f32[view]);
    Array(ar, ("normal_oct16_" + v).c_str(), p.normal_oct16[view]);
    Array(ar, ("normal_rgb8_" + v).c_str(), p.normal_rgb8[view]);
  }
}

template <class Archive>
void serialize(Archive& ar, BoneMapData& b, const uint32_t version) {
  detail::CheckVersion(version, 1, "BoneMapData");
  ar(cereal::make_nvp("joint", b.joint), cereal::make_nvp("view_from_bind", b.view_from_bind),
     cereal::make_nvp("pose", b.pose));
}

template <class Archive>
void serialize(Archive& ar, BodyMapSet& s, const uint32_t version) {
  detail::CheckVersion(version, 1, "BodyMapSet");
  ar(cereal::make_nvp("epsilon", s.epsilon), cereal::make_nvp("resolution", s.resolution),
     cereal::make_nvp("fitted_window", s.fitted_window));
  Array(ar, "poses", s.poses);
}

template <class Archive>
void serialize(Archive& ar, BoneMapSet& s, const uint32_t version) {
  detail::CheckVersion(version, 1, "BoneMapSet");
  ar(cereal::make_nvp("epsilon", s.epsilon));
  Array(ar, "maps", s.maps);
}

template <class Archive>
void serialize(Archive& ar, KirkpatrickHierarchy& k, const uint32_t version) {
  detail::CheckVersion(version, 1, "KirkpatrickHierarchy");
  Array(ar, "vertices_uv", k.vertices_uv);
  Array(ar, "node_triangles", k.node_triangles);
  Array(ar, "child_offsets", k.child_offsets);
  Array(ar, "children", k.children);
  Array(ar, "leaf_planes", k.leaf_planes);
  ar(cereal::make_nvp("root_begin", k.root_begin), cereal::make_nvp("root_end", k.root_end));
}

template <class Archive>
void serialize(Archive& ar, MapTableData& t, const uint32_t version) {
  detail::CheckVersion(version, 1, "MapTableData");
  ar(cereal::make_nvp("kind", t.kind), cereal::make_nvp("rows", t.rows),
     cereal::make_nvp("cols", t.cols), cereal::make_nvp("origin", t.origin),
     cereal::make_nvp("axis", t.axis), cereal::make_nvp("reference", t.reference),
     cereal::make_nvp("length", t.length));
  Array(ar, "cell_offsets", t.cell_offsets);
  Array(ar, "cell_triangles", t.cell_triangles);
}

template <class Archive>
void serialize(Archive& ar, HullColliderData& h, const uint32_t version) {
  detail::CheckVersionRange(version, 1, 2, "HullColliderData");
  if constexpr (Archive::is_loading::value) {
    // Version 2 from format version 4 on, 1 before (as BodyMapPose's check explains).
    if (detail::g_format_version != 0 && version != (detail::g_format_version >= 4 ? 2u : 1u)) {
      throw DecodeError("HullColliderData version " + std::to_string(version) +
                        " in a format version " + std::to_string(detail::g_format_version) +
                        " file");
    }
  }
  ar(cereal::make_nvp("joint", h.joint), cereal::make_nvp("bind_frame", h.bind_frame));
  Array(ar, "vertices", h.vertices);
  Array(ar, "triangles", h.triangles);
  Array(ar, "triangle_planes", h.triangle_planes);
  Array(ar, "planes", h.planes);
  if (version >= 2) Array(ar, "plane_internal", h.plane_internal);  // format 4
  ar(cereal::make_nvp("obb", h.obb), cereal::make_nvp("projection_axis", h.projection_axis),
     cereal::make_nvp("projection_u", h.projection_u),
     cereal::make_nvp("projection_v", h.projection_v), cereal::make_nvp("upper", h.upper),
     cereal::make_nvp("lower", h.lower), cereal::make_nvp("map", h.map));
}

template <class Archive>
void serialize(Archive& ar, JointSphereData& s, const uint32_t version) {
  detail::CheckVersion(version, 1, "JointSphereData");
  ar(cereal::make_nvp("joint", s.joint), cereal::make_nvp("parent_joint", s.parent_joint),
     cereal::make_nvp("center", s.center), cereal::make_nvp("radius", s.radius));
}

template <class Archive>
void serialize(Archive& ar, CapsuleColliderData& c, const uint32_t version) {
  detail::CheckVersion(version, 1, "CapsuleColliderData");
  ar(cereal::make_nvp("joint", c.joint), cereal::make_nvp("from", c.from),
     cereal::make_nvp("to", c.to), cereal::make_nvp("radius_from", c.radius_from),
     cereal::make_nvp("radius_to", c.radius_to));
}

template <class Archive>
void serialize(Archive& ar, CharacterAsset& a, const uint32_t version) {
  detail::CheckVersionRange(version, 1, 4, "CharacterAsset");
  ar(cereal::make_nvp("info", a.info), cereal::make_nvp("skeleton", a.skeleton));
  Array(ar, "clips", a.clips);
  ar(cereal::make_nvp("mesh", a.mesh), cereal::make_nvp("body_maps", a.body_maps));
  Array(ar, "hulls", a.hulls);
  Array(ar, "joint_spheres", a.joint_spheres);
  if (version < 2) return;
  // Version 2 (bone maps, at the end) from format version 5 on. Checked here rather than first,
  // so that a file of an older format with a newer field inside names that field.
  if constexpr (Archive::is_loading::value) {
    if (detail::g_format_version != 0 && detail::g_format_version < 5) {
      throw DecodeError("CharacterAsset version " + std::to_string(version) +
                        " in a format version " + std::to_string(detail::g_format_version) +
                        " file");
    }
  }
  ar(cereal::make_nvp("bone_maps", a.bone_maps));
  if (version < 3) return;
  // Version 3 (tapered capsules, at the end) from format version 6 on.
  if constexpr (Archive::is_loading::value) {
    if (detail::g_format_version != 0 && detail::g_format_version < 6) {
      throw DecodeError("CharacterAsset version " + std::to_string(version) +
                        " in a format version " + std::to_string(detail::g_format_version) +
                        " file");
    }
  }
  Array(ar, "capsules", a.capsules);
  if (version < 4) return;
  // Version 4 (the render mesh, at the end) from format version 8 on.
  if constexpr (Archive::is_loading::value) {
    if (detail::g_format_version != 0 && detail::g_format_version < 8) {
      throw DecodeError("CharacterAsset version " + std::to_string(version) +
                        " in a format version " + std::to_string(detail::g_format_version) +
                        " file");
    }
  }
  ar(cereal::make_nvp("render_mesh", a.render_mesh));
}

}  // namespace drape

CEREAL_CLASS_VERSION(drape::AssetInfo, 1)
CEREAL_CLASS_VERSION(drape::SkeletonData, 1)
CEREAL_CLASS_VERSION(drape::ClipData, 1)
CEREAL_CLASS_VERSION(drape::MeshData, 1)
// 2: layout, spans (format 2); 3: layers (format 3); 4: view axis (format 7)
CEREAL_CLASS_VERSION(drape::BodyMapPose, 4)
CEREAL_CLASS_VERSION(drape::BodyMapSet, 1)
CEREAL_CLASS_VERSION(drape::BoneMapData, 1)
CEREAL_CLASS_VERSION(drape::BoneMapSet, 1)
CEREAL_CLASS_VERSION(drape::KirkpatrickHierarchy, 1)
CEREAL_CLASS_VERSION(drape::MapTableData, 1)
CEREAL_CLASS_VERSION(drape::HullColliderData, 2)
CEREAL_CLASS_VERSION(drape::JointSphereData, 1)
CEREAL_CLASS_VERSION(drape::CapsuleColliderData, 1)
// 2: bone_maps (format 5); 3: capsules (format 6); 4: render_mesh (format 8)
CEREAL_CLASS_VERSION(drape::CharacterAsset, 4)
