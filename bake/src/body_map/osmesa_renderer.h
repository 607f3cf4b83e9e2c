#pragma once
// Private to the body map baker: paper A's GL render path on OSMesa (docs/ALGORITHMS.md §6.7).
// One OSMesa context (llvmpipe, core profile >= 3.3) is created lazily on first use and kept for
// the life of the process, guarded by a mutex, so the ~60 ms of shader JIT is paid once. Renders
// into float render targets (RGBA32F normals, R32F linear depth, DEPTH_COMPONENT32F), culling off,
// GL_LESS, read back with glReadPixels(GL_FLOAT). Large rectangles are rendered in tiles of at most
// 2048 x 2048 texels to bound memory.

#include "body_map/cpu_rasterizer.h"
#include "drape/formats/status.h"

namespace drape::bake {

// True when built with DRAPE_HAVE_OSMESA.
bool OsMesaCompiledIn();

// Renders both views of `input`. On success fills images[0..1], the wall time of each view in
// milliseconds, and *renderer_name ("osmesa (<GL_RENDERER>)", static storage). Returns
// kInvalidState with "OSMesa renderer not available in this build" when compiled without
// OSMesa, or with the GL failure otherwise.
Status RenderViewsOsMesa(const MapRasterInput& input, MapViewImage images[2], double view_ms[2],
                         const char** renderer_name);

}  // namespace drape::bake
