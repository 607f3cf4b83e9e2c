#pragma once
// The render mesh: the bind mesh simplified for the runtime's body-map renderer
// (BodyMapRenderer), whose cost per frame grows with the triangles it sets up. Maps of 5-7 mm
// texels gain nothing from triangles far smaller than a texel, and game characters carry 10-60k.
// Edge collapses onto existing vertices (meshoptimizer), so the kept vertices keep their positions
// and skin influences and the mesh skins as the bind mesh does; open borders stay in place.
//
//   MeshData render_mesh;
//   RenderMeshReport report;
//   SimplifyRenderMesh(character.mesh, 0.001f, &render_mesh, &report);

#include <cstdint>

#include "drape/formats/mesh_data.h"
#include "drape/formats/status.h"

namespace drape::bake {

struct RenderMeshReport {
  uint32_t triangles = 0;           // of the bind mesh
  uint32_t kept_triangles = 0;      // of the render mesh (0: none kept)
  uint32_t kept_vertices = 0;       // of the render mesh
  float error = 0.f;                // metres: the measured distance between the surfaces (below)
  float normal_turn_degrees = 0.f;  // the largest turn of a kept vertex's normal (below)
  uint32_t turned_vertices = 0;     // kept vertices whose normal turned beyond 30 degrees
  uint32_t attempts = 0;            // simplifications tried
  bool kept = false;                // false: *out is empty (below)
};

// Simplifies `mesh` until its surface would move more than `tolerance` (metres, > 0), or more
// than 0.2 % of the kept vertices' area-weighted normals, along which the renderer offsets them,
// would turn beyond 30 degrees, and writes the result to *out. The distance is measured, not
// estimated: the largest of every bind-mesh vertex and triangle centroid to the simplified surface
// and every simplified edge midpoint and centroid to the bind mesh (the exact reference,
// mesh_reference.h). (On a low-poly body's flat faces coarser triangles turned normals by up to 160
// degrees within the distance, and its maps filled with false air gaps.) A result beyond either is
// simplified again from the bind mesh at a target lowered by the overshoot, up to eight attempts in
// all. *out is left empty (report->kept false) when no attempt met the tolerance or the result
// keeps more than 70 % of the triangles: the renderer then draws the bind mesh. kInvalidArgument
// for a tolerance that is not finite and > 0 or a mesh whose indices are out of range.
Status SimplifyRenderMesh(const MeshData& mesh, float tolerance, MeshData* out,
                          RenderMeshReport* report);

}  // namespace drape::bake
