#include "body_map/osmesa_renderer.h"

#if DRAPE_HAVE_OSMESA

#include <GL/osmesa.h>
// clang-format off
#include <GL/gl.h>
#include <GL/glext.h>
// clang-format on

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <mutex>
#include <string>
#include <vector>

namespace drape::bake {
namespace {

constexpr GLsizei kMaxTile = 2048;  // texels per tile side: bounds the float targets to 96 MiB

constexpr const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 in_ndc;     // window position, already in normalised device coords
layout(location = 1) in float in_depth;  // metres from the view's camera plane
layout(location = 2) in vec3 in_normal;  // unit vertex normal of the offset surface
noperspective out float v_depth;
noperspective out vec3 v_normal;
void main() {
  v_depth = in_depth;
  v_normal = in_normal;
  gl_Position = vec4(in_ndc, 1.0);
}
)";

constexpr const char* kFragmentShader = R"(#version 330 core
noperspective in float v_depth;
noperspective in vec3 v_normal;
layout(location = 0) out vec4 out_normal;  // rgb = interpolated normal, a = 1 marks coverage
layout(location = 1) out vec4 out_depth;   // r = linear depth in metres
void main() {
  out_normal = vec4(v_normal, 1.0);
  out_depth = vec4(v_depth, 0.0, 0.0, 1.0);
}
)";

// The process-wide GL state. Created on first use and intentionally never destroyed (tearing
// down Mesa during static destruction is fragile); it stays reachable through a static pointer.
struct GlState {
  OSMesaContext context = nullptr;
  std::vector<uint8_t> default_buffer;  // OSMesa needs a colour buffer to make current
  GLuint program = 0, vao = 0, vertex_buffer = 0, index_buffer = 0;
  GLuint framebuffer = 0, normal_target = 0, depth_target = 0, depth_buffer = 0;
  GLsizei target_width = 0, target_height = 0;
  GLsizei max_tile = kMaxTile;
  GLint max_viewport[2] = {0, 0};  // GL_MAX_VIEWPORT_DIMS: the largest raster rectangle
  std::string name;                // "osmesa (<GL_RENDERER>)"
};

std::mutex g_mutex;
GlState* g_state = nullptr;  // guarded by g_mutex
std::string g_init_error;    // guarded by g_mutex; sticky: a failed init is not retried

Status GlError(const char* where) {
  const GLenum error = glGetError();
  if (error == GL_NO_ERROR) return Status::Ok();
  return Status(StatusCode::kInvalidState,
                std::string("OSMesa renderer: GL error ") + std::to_string(error) + " in " + where);
}

Status CompileShader(GLenum type, const char* source, GLuint* shader) {
  *shader = glCreateShader(type);
  glShaderSource(*shader, 1, &source, nullptr);
  glCompileShader(*shader);
  GLint ok = 0;
  glGetShaderiv(*shader, GL_COMPILE_STATUS, &ok);
  if (ok) return Status::Ok();
  char log[1024] = {};
  glGetShaderInfoLog(*shader, sizeof(log), nullptr, log);
  return Status(StatusCode::kInvalidState,
                std::string("OSMesa renderer: shader compile failed: ") + log);
}

Status CreateState(GlState* s) {
  // llvmpipe gives GL 4.5 core and bit-identical output across thread counts; softpipe is 2.5x
  // slower and rasterises differently (docs/ALGORITHMS.md §6.7). Pin it before the context exists.
  setenv("GALLIUM_DRIVER", "llvmpipe", 1);
  const int attributes[] = {OSMESA_FORMAT,
                            OSMESA_RGBA,
                            OSMESA_DEPTH_BITS,
                            0,
                            OSMESA_STENCIL_BITS,
                            0,
                            OSMESA_ACCUM_BITS,
                            0,
                            OSMESA_PROFILE,
                            OSMESA_CORE_PROFILE,
                            OSMESA_CONTEXT_MAJOR_VERSION,
                            3,
                            OSMESA_CONTEXT_MINOR_VERSION,
                            3,
                            0};
  s->context = OSMesaCreateContextAttribs(attributes, nullptr);
  if (s->context == nullptr) {
    return Status(StatusCode::kInvalidState,
                  "OSMesa renderer: OSMesaCreateContextAttribs failed (core profile 3.3)");
  }
  constexpr GLsizei kDefaultSize = 16;
  s->default_buffer.assign(kDefaultSize * kDefaultSize * 4, 0);
  if (!OSMesaMakeCurrent(s->context, s->default_buffer.data(), GL_UNSIGNED_BYTE, kDefaultSize,
                         kDefaultSize)) {
    return Status(StatusCode::kInvalidState, "OSMesa renderer: OSMesaMakeCurrent failed");
  }
  const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  s->name = std::string("osmesa (") + (renderer != nullptr ? renderer : "unknown") + ")";

  GLint max_renderbuffer = 0;
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_renderbuffer);
  glGetIntegerv(GL_MAX_VIEWPORT_DIMS, s->max_viewport);
  s->max_tile = std::min({kMaxTile, static_cast<GLsizei>(max_renderbuffer),
                          static_cast<GLsizei>(s->max_viewport[0]),
                          static_cast<GLsizei>(s->max_viewport[1])});
  if (s->max_tile < 16) {
    return Status(StatusCode::kInvalidState, "OSMesa renderer: maximum render target too small");
  }

  GLuint vertex_shader = 0, fragment_shader = 0;
  Status status = CompileShader(GL_VERTEX_SHADER, kVertexShader, &vertex_shader);
  if (!status.ok()) return status;
  status = CompileShader(GL_FRAGMENT_SHADER, kFragmentShader, &fragment_shader);
  if (!status.ok()) return status;
  s->program = glCreateProgram();
  glAttachShader(s->program, vertex_shader);
  glAttachShader(s->program, fragment_shader);
  glLinkProgram(s->program);
  GLint linked = 0;
  glGetProgramiv(s->program, GL_LINK_STATUS, &linked);
  glDeleteShader(vertex_shader);
  glDeleteShader(fragment_shader);
  if (!linked) {
    char log[1024] = {};
    glGetProgramInfoLog(s->program, sizeof(log), nullptr, log);
    return Status(StatusCode::kInvalidState, std::string("OSMesa renderer: link failed: ") + log);
  }

  glGenVertexArrays(1, &s->vao);
  glBindVertexArray(s->vao);
  glGenBuffers(1, &s->vertex_buffer);
  glGenBuffers(1, &s->index_buffer);
  glBindBuffer(GL_ARRAY_BUFFER, s->vertex_buffer);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, s->index_buffer);
  constexpr GLsizei kStride = 7 * sizeof(float);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, kStride, reinterpret_cast<const void*>(0));
  glVertexAttribPointer(1, 1, GL_FLOAT, GL_FALSE, kStride,
                        reinterpret_cast<const void*>(3 * sizeof(float)));
  glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, kStride,
                        reinterpret_cast<const void*>(4 * sizeof(float)));
  glEnableVertexAttribArray(0);
  glEnableVertexAttribArray(1);
  glEnableVertexAttribArray(2);

  glGenFramebuffers(1, &s->framebuffer);
  glGenRenderbuffers(1, &s->normal_target);
  glGenRenderbuffers(1, &s->depth_target);
  glGenRenderbuffers(1, &s->depth_buffer);
  return GlError("context setup");
}

Status EnsureTargets(GlState* s, GLsizei width, GLsizei height) {
  if (s->target_width >= width && s->target_height >= height) return Status::Ok();
  width = std::max(width, s->target_width);
  height = std::max(height, s->target_height);
  glBindRenderbuffer(GL_RENDERBUFFER, s->normal_target);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA32F, width, height);
  glBindRenderbuffer(GL_RENDERBUFFER, s->depth_target);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_R32F, width, height);
  glBindRenderbuffer(GL_RENDERBUFFER, s->depth_buffer);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, width, height);
  glBindFramebuffer(GL_FRAMEBUFFER, s->framebuffer);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                            s->normal_target);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_RENDERBUFFER, s->depth_target);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, s->depth_buffer);
  const GLenum complete = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (complete != GL_FRAMEBUFFER_COMPLETE) {
    return Status(StatusCode::kInvalidState,
                  "OSMesa renderer: framebuffer incomplete (" + std::to_string(complete) + ")");
  }
  s->target_width = width;
  s->target_height = height;
  return GlError("render target allocation");
}

double MillisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

Status RenderView(GlState* s, const MapRasterInput& in, int view, MapViewImage* image) {
  const size_t vertex_count = in.window_x.size();
  const size_t texels = static_cast<size_t>(in.width) * in.height;
  image->valid.assign(texels, 0);
  image->depth.assign(texels, 0.f);
  image->normal.assign(3 * texels, 0.f);
  // Depth [0, depth_range] to NDC z [-1, 1]; GL_DEPTH_CLAMP keeps a vertex that rounds onto
  // or past a camera plane from being clipped.
  const double depth_scale = 2.0 / in.depth_range;

  // One NDC mapping for the whole raster rectangle, computed in double and rounded once to
  // float. Each tile then moves the viewport (not the vertices): the clip volume is the same for
  // every tile, so triangles crossing a tile edge are not clipped there and seams cannot show;
  // the framebuffer bounds discard the texels outside the tile.
  std::vector<float> vertices(7 * vertex_count);
  const double scale_x = 2.0 / in.width, scale_y = 2.0 / in.height;
  for (size_t v = 0; v < vertex_count; ++v) {
    float* out = &vertices[7 * v];
    out[0] = static_cast<float>(in.window_x[v] * scale_x - 1.0);
    out[1] = static_cast<float>(in.window_y[v] * scale_y - 1.0);
    out[2] = static_cast<float>(in.view_depth[view][v] * depth_scale - 1.0);
    out[3] = static_cast<float>(in.view_depth[view][v]);
    for (int c = 0; c < 3; ++c) out[4 + c] = static_cast<float>(in.normals[3 * v + c]);
  }
  glBindBuffer(GL_ARRAY_BUFFER, s->vertex_buffer);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(float)),
               vertices.data(), GL_STREAM_DRAW);

  std::vector<float> normal_pixels, depth_pixels;
  const GLsizei tile = s->max_tile;
  for (uint32_t tile_y = 0; tile_y < in.height; tile_y += static_cast<uint32_t>(tile)) {
    for (uint32_t tile_x = 0; tile_x < in.width; tile_x += static_cast<uint32_t>(tile)) {
      const GLsizei tile_w = static_cast<GLsizei>(std::min<uint32_t>(tile, in.width - tile_x));
      const GLsizei tile_h = static_cast<GLsizei>(std::min<uint32_t>(tile, in.height - tile_y));
      glBindFramebuffer(GL_FRAMEBUFFER, s->framebuffer);
      const GLenum buffers[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
      glDrawBuffers(2, buffers);
      glViewport(-static_cast<GLint>(tile_x), -static_cast<GLint>(tile_y),
                 static_cast<GLsizei>(in.width), static_cast<GLsizei>(in.height));
      const GLfloat clear_normal[4] = {0.f, 0.f, 0.f, 0.f};
      const GLfloat clear_depth_colour[4] = {0.f, 0.f, 0.f, 0.f};
      const GLfloat clear_depth = 1.f;
      glClearBufferfv(GL_COLOR, 0, clear_normal);
      glClearBufferfv(GL_COLOR, 1, clear_depth_colour);
      glClearBufferfv(GL_DEPTH, 0, &clear_depth);
      glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(in.triangles.size()), GL_UNSIGNED_INT,
                     nullptr);
      glFinish();
      Status status = GlError("draw");
      if (!status.ok()) return status;

      const size_t tile_texels = static_cast<size_t>(tile_w) * static_cast<size_t>(tile_h);
      normal_pixels.resize(4 * tile_texels);
      depth_pixels.resize(tile_texels);
      glPixelStorei(GL_PACK_ALIGNMENT, 4);
      glReadBuffer(GL_COLOR_ATTACHMENT0);
      glReadPixels(0, 0, tile_w, tile_h, GL_RGBA, GL_FLOAT, normal_pixels.data());
      glReadBuffer(GL_COLOR_ATTACHMENT1);
      glReadPixels(0, 0, tile_w, tile_h, GL_RED, GL_FLOAT, depth_pixels.data());
      status = GlError("readback");
      if (!status.ok()) return status;

      const double view_axis_z = view == 0 ? 1.0 : -1.0;
      for (GLsizei row = 0; row < tile_h; ++row) {
        for (GLsizei col = 0; col < tile_w; ++col) {
          const size_t src =
              static_cast<size_t>(row) * static_cast<size_t>(tile_w) + static_cast<size_t>(col);
          if (!(normal_pixels[4 * src + 3] > 0.5f)) continue;
          const size_t dst = static_cast<size_t>(tile_y + static_cast<uint32_t>(row)) * in.width +
                             tile_x + static_cast<uint32_t>(col);
          double n[3] = {normal_pixels[4 * src], normal_pixels[4 * src + 1],
                         normal_pixels[4 * src + 2]};
          const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
          if (len > 1e-12 && std::isfinite(len)) {
            for (double& c : n) c /= len;
          } else {
            n[0] = 0.0;
            n[1] = 0.0;
            n[2] = view_axis_z;
          }
          image->valid[dst] = 1;
          image->depth[dst] = depth_pixels[src];
          for (int c = 0; c < 3; ++c) image->normal[3 * dst + c] = static_cast<float>(n[c]);
        }
      }
    }
  }
  return Status::Ok();
}

}  // namespace

bool OsMesaCompiledIn() { return true; }

Status RenderViewsOsMesa(const MapRasterInput& input, MapViewImage images[2], double view_ms[2],
                         const char** renderer_name) {
  std::lock_guard<std::mutex> lock(g_mutex);
  if (g_state == nullptr) {
    if (!g_init_error.empty()) return Status(StatusCode::kInvalidState, g_init_error);
    auto* state = new GlState();
    const Status status = CreateState(state);
    if (!status.ok()) {
      g_init_error = status.message();
      if (state->context != nullptr) OSMesaDestroyContext(state->context);
      delete state;
      return status;
    }
    g_state = state;
  }
  GlState* s = g_state;
  if (!OSMesaMakeCurrent(s->context, s->default_buffer.data(), GL_UNSIGNED_BYTE, 16, 16)) {
    return Status(StatusCode::kInvalidState, "OSMesa renderer: OSMesaMakeCurrent failed");
  }
  glGetError();  // clear any stale error

  if (input.width > static_cast<uint32_t>(s->max_viewport[0]) ||
      input.height > static_cast<uint32_t>(s->max_viewport[1])) {
    return Status(StatusCode::kInvalidState,
                  "OSMesa renderer: the raster rectangle " + std::to_string(input.width) + " x " +
                      std::to_string(input.height) + " exceeds GL_MAX_VIEWPORT_DIMS " +
                      std::to_string(s->max_viewport[0]) + " x " +
                      std::to_string(s->max_viewport[1]) + "; use the CPU renderer");
  }
  const auto upload_start = std::chrono::steady_clock::now();
  const GLsizei tile = s->max_tile;
  Status status = EnsureTargets(s, std::min<GLsizei>(tile, static_cast<GLsizei>(input.width)),
                                std::min<GLsizei>(tile, static_cast<GLsizei>(input.height)));
  if (!status.ok()) return status;
  glUseProgram(s->program);
  glBindVertexArray(s->vao);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, s->index_buffer);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER,
               static_cast<GLsizeiptr>(input.triangles.size() * sizeof(uint32_t)),
               input.triangles.data(), GL_STREAM_DRAW);
  glDisable(GL_CULL_FACE);  // open, inconsistently wound meshes; the back view is a reflection
  glDisable(GL_BLEND);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glEnable(GL_DEPTH_CLAMP);
  status = GlError("state setup");
  if (!status.ok()) return status;
  const double setup_ms = MillisecondsSince(upload_start);

  for (int view = 0; view < 2; ++view) {
    const auto start = std::chrono::steady_clock::now();
    status = RenderView(s, input, view, &images[view]);
    if (!status.ok()) return status;
    view_ms[view] = MillisecondsSince(start) + (view == 0 ? setup_ms : 0.0);
  }
  *renderer_name = s->name.c_str();
  return Status::Ok();
}

}  // namespace drape::bake

#else  // !DRAPE_HAVE_OSMESA

namespace drape::bake {

bool OsMesaCompiledIn() { return false; }

Status RenderViewsOsMesa(const MapRasterInput&, MapViewImage[2], double[2], const char**) {
  return Status(StatusCode::kInvalidState, "OSMesa renderer not available in this build");
}

}  // namespace drape::bake

#endif  // DRAPE_HAVE_OSMESA
