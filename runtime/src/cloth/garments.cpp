#include "drape/runtime/garments.h"

#include <cmath>
#include <numbers>
#include <string>

#include "drape/runtime/math.h"

namespace drape {
namespace {

constexpr uint64_t kMaxGarmentParticles = 1u << 24;

Status Invalid(const char* function, const std::string& message) {
  return Status(StatusCode::kInvalidArgument, std::string(function) + ": " + message);
}

bool PositiveFinite(float v) { return std::isfinite(v) && v > 0.f; }
bool IsUnit(Float3 a) { return IsFinite(a) && std::fabs(Length(a) - 1.f) <= 1e-3f; }

// Checks the named sizes and counts; `wrap` grids need at least 3 columns.
Status CheckGrid(const char* function, uint32_t columns, uint32_t rows, bool wrap) {
  if (columns < (wrap ? 3u : 1u))
    return Invalid(function, std::string(wrap ? "segments" : "columns") + " = " +
                                 std::to_string(columns) + ": must be >= " + (wrap ? "3" : "1"));
  if (rows < 1) return Invalid(function, "rows = " + std::to_string(rows) + ": must be >= 1");
  const uint64_t particles = uint64_t(wrap ? columns : columns + 1ull) * (rows + 1ull);
  if (particles > kMaxGarmentParticles)
    return Invalid(function, std::to_string(particles) + " particles: at most 2^24");
  return Status::Ok();
}

// Triangles of a grid with `columns` cells around (wrapping onto column 0 when `wrap`) and
// `rows` cells along; particle (i, j) is j * stride + i. Diagonals alternate like a checkerboard
// (with an even number of wrapped columns the pattern is seamless).
void GridTriangles(uint32_t columns, uint32_t rows, bool wrap, std::vector<uint32_t>* out) {
  const uint32_t stride = wrap ? columns : columns + 1;
  out->clear();
  out->reserve(size_t(columns) * rows * 6);
  for (uint32_t j = 0; j < rows; ++j) {
    for (uint32_t i = 0; i < columns; ++i) {
      const uint32_t i1 = wrap ? (i + 1) % columns : i + 1;
      const uint32_t v00 = j * stride + i, v10 = j * stride + i1;
      const uint32_t v01 = (j + 1) * stride + i, v11 = (j + 1) * stride + i1;
      if ((i + j) % 2 == 0) {
        out->insert(out->end(), {v00, v10, v11, v00, v11, v01});
      } else {
        out->insert(out->end(), {v00, v10, v01, v10, v11, v01});
      }
    }
  }
}

void HeldRow(uint32_t stride, uint32_t row, std::vector<uint32_t>* held) {
  held->resize(stride);
  for (uint32_t i = 0; i < stride; ++i) (*held)[i] = row * stride + i;
}

float Fraction(uint32_t i, uint32_t count) {
  return static_cast<float>(i) / static_cast<float>(count);
}

}  // namespace

Status MakeSheet(const SheetShape& s, GarmentMesh* mesh) {
  *mesh = GarmentMesh{};
  const char* fn = "MakeSheet";
  if (!IsFinite(s.center)) return Invalid(fn, "center is not finite");
  if (!IsUnit(s.axis_u) || !IsUnit(s.axis_v)) return Invalid(fn, "axis_u and axis_v must be unit");
  if (std::fabs(Dot(s.axis_u, s.axis_v)) > 1e-3f)
    return Invalid(fn, "axis_u and axis_v must be perpendicular");
  if (!PositiveFinite(s.width) || !PositiveFinite(s.height))
    return Invalid(fn, "width and height must be finite and > 0");
  if (Status st = CheckGrid(fn, s.columns, s.rows, false); !st.ok()) return st;
  const uint32_t stride = s.columns + 1;
  mesh->positions.resize(size_t(stride) * (s.rows + 1));
  for (uint32_t j = 0; j <= s.rows; ++j) {
    for (uint32_t i = 0; i <= s.columns; ++i) {
      mesh->positions[size_t(j) * stride + i] =
          s.center + s.axis_u * ((Fraction(i, s.columns) - 0.5f) * s.width) +
          s.axis_v * ((Fraction(j, s.rows) - 0.5f) * s.height);
    }
  }
  GridTriangles(s.columns, s.rows, false, &mesh->triangles);
  HeldRow(stride, s.rows, &mesh->held);
  return Status::Ok();
}

Status MakeSkirt(const SkirtShape& s, GarmentMesh* mesh) {
  *mesh = GarmentMesh{};
  const char* fn = "MakeSkirt";
  if (!IsFinite(s.top_center)) return Invalid(fn, "top_center is not finite");
  if (!PositiveFinite(s.top_radius) || !PositiveFinite(s.bottom_radius) ||
      !PositiveFinite(s.length))
    return Invalid(fn, "top_radius, bottom_radius and length must be finite and > 0");
  if (Status st = CheckGrid(fn, s.segments, s.rings, true); !st.ok()) return st;
  mesh->positions.resize(size_t(s.segments) * (s.rings + 1));
  for (uint32_t j = 0; j <= s.rings; ++j) {
    const float f = Fraction(j, s.rings);
    const float radius = s.top_radius * (1.f - f) + s.bottom_radius * f;
    for (uint32_t i = 0; i < s.segments; ++i) {
      const double angle = 2.0 * std::numbers::pi * i / s.segments;
      const Float3 offset{radius * static_cast<float>(std::cos(angle)), -s.length * f,
                          radius * static_cast<float>(std::sin(angle))};
      mesh->positions[size_t(j) * s.segments + i] = s.top_center + offset;
    }
  }
  GridTriangles(s.segments, s.rings, true, &mesh->triangles);
  HeldRow(s.segments, 0, &mesh->held);
  return Status::Ok();
}

Status MakeCape(const CapeShape& s, GarmentMesh* mesh) {
  *mesh = GarmentMesh{};
  const char* fn = "MakeCape";
  if (!IsFinite(s.top_center)) return Invalid(fn, "top_center is not finite");
  if (!PositiveFinite(s.top_width) || !PositiveFinite(s.bottom_width) || !PositiveFinite(s.length))
    return Invalid(fn, "top_width, bottom_width and length must be finite and > 0");
  if (Status st = CheckGrid(fn, s.columns, s.rows, false); !st.ok()) return st;
  const uint32_t stride = s.columns + 1;
  mesh->positions.resize(size_t(stride) * (s.rows + 1));
  for (uint32_t j = 0; j <= s.rows; ++j) {
    const float f = Fraction(j, s.rows);
    const float width = s.top_width * (1.f - f) + s.bottom_width * f;
    for (uint32_t i = 0; i <= s.columns; ++i) {
      const Float3 offset{(Fraction(i, s.columns) - 0.5f) * width, -s.length * f, 0.f};
      mesh->positions[size_t(j) * stride + i] = s.top_center + offset;
    }
  }
  GridTriangles(s.columns, s.rows, false, &mesh->triangles);
  HeldRow(stride, 0, &mesh->held);
  return Status::Ok();
}

Status MakeSleeve(const SleeveShape& s, GarmentMesh* mesh) {
  *mesh = GarmentMesh{};
  const char* fn = "MakeSleeve";
  if (!IsFinite(s.start)) return Invalid(fn, "start is not finite");
  if (!IsUnit(s.axis)) return Invalid(fn, "axis must be unit");
  if (!PositiveFinite(s.radius) || !PositiveFinite(s.length))
    return Invalid(fn, "radius and length must be finite and > 0");
  if (Status st = CheckGrid(fn, s.segments, s.rings, true); !st.ok()) return st;
  // (e1, e2, axis) right-handed: e1 is the unit axis least aligned with `axis`, made
  // perpendicular.
  const Float3 a = s.axis * (1.f / Length(s.axis));
  const Float3 pick =
      std::fabs(a.x) <= std::fabs(a.y) && std::fabs(a.x) <= std::fabs(a.z)
          ? Float3{1.f, 0.f, 0.f}
          : (std::fabs(a.y) <= std::fabs(a.z) ? Float3{0.f, 1.f, 0.f} : Float3{0.f, 0.f, 1.f});
  const Float3 e1 = NormalizeOr(pick - a * Dot(pick, a), Float3{1.f, 0.f, 0.f});
  const Float3 e2 = Cross(a, e1);
  mesh->positions.resize(size_t(s.segments) * (s.rings + 1));
  for (uint32_t j = 0; j <= s.rings; ++j) {
    const Float3 ring_center = s.start + a * (s.length * Fraction(j, s.rings));
    for (uint32_t i = 0; i < s.segments; ++i) {
      const double angle = 2.0 * std::numbers::pi * i / s.segments;
      const Float3 radial =
          e1 * static_cast<float>(std::cos(angle)) + e2 * static_cast<float>(std::sin(angle));
      mesh->positions[size_t(j) * s.segments + i] = ring_center + radial * s.radius;
    }
  }
  GridTriangles(s.segments, s.rings, true, &mesh->triangles);
  HeldRow(s.segments, 0, &mesh->held);
  return Status::Ok();
}

ClothDescription DescribeAttachedGarment(const GarmentMesh& mesh, int32_t joint) {
  ClothDescription description;
  description.positions = mesh.positions;
  description.triangles = mesh.triangles;
  for (const uint32_t p : mesh.held)
    description.attachments.push_back({p, joint, mesh.positions[p]});
  return description;
}

}  // namespace drape
