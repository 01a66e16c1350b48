// stipple platform — the GL client's renderer. See gl_renderer.h.
#include "platform/gl/gl_renderer.h"

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/gaussian_table.h"
#include "core/node_format.h"

namespace stipple {
namespace {

constexpr int kBuckets = 11;
// Points per node: the 2σ ellipse's area in point-sized squares, five times
// over (gl_renderer.h).
constexpr float kCoverage = 5.f;  // counts up to 1, 2, 4, ... 1024 (and above, the buffer's size)

// Instance data. GPU decode: the record's 8 words, then the count. CPU
// decode: mean, the three scaled axes and the normal (floats, MU and unit),
// the colour (0..1), then the count.
constexpr size_t kGpuStride = 8 * 4 + 4;
constexpr size_t kCpuStride = (3 + 9 + 3 + 3) * 4 + 4;

const char kCommon[] = R"(#version 330 core
uniform mat3 rotation;     // world -> camera rows: right, down, forward
uniform vec3 eye;          // MU
uniform vec4 lens;         // focal px, cx px, cy px, point size px
uniform vec4 screen;       // width, height, near, far (MU)
uniform samplerBuffer gauss;
uniform vec3 light;
uniform float ambient;
uniform int lighting;
out vec3 v_color;

void emit(vec3 mean, vec3 a0, vec3 a1, vec3 a2, vec3 normal, vec3 color, uint count) {
  if (uint(gl_VertexID) >= count) {  // beyond this node's own count: dropped
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
    return;
  }
  vec3 g = texelFetch(gauss, gl_VertexID).xyz;
  vec3 p = mean + a0 * g.x + a1 * g.y + a2 * g.z;
  vec3 c = rotation * (p - eye);
  float sx = lens.x * c.x / c.z + lens.y, sy = lens.x * c.y / c.z + lens.z;
  float depth = 2.0 * (c.z - screen.z) / (screen.w - screen.z) - 1.0;
  gl_Position = vec4((2.0 * sx / screen.x - 1.0) * c.z, (1.0 - 2.0 * sy / screen.y) * c.z, depth * c.z, c.z);
  gl_PointSize = lens.w;
  float k = 1.0;
  if (lighting != 0) k = ambient + (1.0 - ambient) * max(0.0, dot(light, rotation * normal));
  v_color = color * k;
}
)";

const char kCpuMain[] = R"(
layout(location = 0) in vec3 mean;
layout(location = 1) in vec3 axis0;
layout(location = 2) in vec3 axis1;
layout(location = 3) in vec3 axis2;
layout(location = 4) in vec3 normal;
layout(location = 5) in vec3 color;
layout(location = 6) in uint count;
void main() { emit(mean, axis0, axis1, axis2, normal, color, count); }
)";

// The record's bit fields, decoded as docs/format.md §5 says.
const char kGpuMain[] = R"(
layout(location = 0) in uvec4 rec0;
layout(location = 1) in uvec4 rec1;
layout(location = 6) in uint count;
uniform int field_offset[18];
uniform int field_bits[18];
uniform vec3 extent_mu;
uniform samplerBuffer sigma_p;  // per class: sigma1..3, MU
uniform int has_normals, has_color, grey;
uniform vec3 grey_rgb;
const float PI = 3.14159265358979;

uint field(int k) {
  int b = field_bits[k];
  if (b == 0) return 0u;
  int o = field_offset[k], i = o >> 5, s = o & 31;
  uint w[8] = uint[8](rec0.x, rec0.y, rec0.z, rec0.w, rec1.x, rec1.y, rec1.z, rec1.w);
  uint v = w[i] >> uint(s);
  if (s + b > 32) v |= w[i + 1] << uint(32 - s);
  return v & ((1u << uint(b)) - 1u);
}

// Columns f1, f2, f3 of the frame of fields k..k+2 (theta over `range`).
mat3 frame(int k, float range) {
  float theta = float(field(k)) * range / float((1 << field_bits[k]) - 1);
  float phi = float(field(k + 1)) * 2.0 * PI / float(1 << field_bits[k + 1]);
  float psi = float(field(k + 2)) * PI / float(1 << field_bits[k + 2]);
  float st = sin(theta), ct = cos(theta), sp = sin(phi), cp = cos(phi);
  vec3 f3 = vec3(cp * st, sp * st, ct);
  vec3 a = vec3(-sp, cp, 0.0);
  // x and y rotated by theta about a (Rodrigues).
  vec3 x = vec3(1.0, 0.0, 0.0) * ct + cross(a, vec3(1.0, 0.0, 0.0)) * st + a * a.x * (1.0 - ct);
  vec3 y = vec3(0.0, 1.0, 0.0) * ct + cross(a, vec3(0.0, 1.0, 0.0)) * st + a * a.y * (1.0 - ct);
  float s = sin(psi), c = cos(psi);
  return mat3(c * x + s * y, c * y - s * x, f3);
}

void main() {
  vec3 mean;
  for (int a = 0; a < 3; ++a) mean[a] = (float(field(a)) + 0.5) * extent_mu[a] / float(1 << field_bits[a]);
  mat3 f = frame(3, PI);
  vec3 s = texelFetch(sigma_p, int(field(6))).xyz;
  vec3 normal = has_normals != 0 ? frame(7, PI)[2] : vec3(0.0, 0.0, -1.0);
  vec3 color = grey_rgb;
  if (has_color != 0 && grey == 0)
    color = vec3(float(field(11)) / float((1 << field_bits[11]) - 1), float(field(12)) / float((1 << field_bits[12]) - 1),
                 float(field(13)) / float((1 << field_bits[13]) - 1));
  emit(mean, f[0] * s.x, f[1] * s.y, f[2] * s.z, normal, color, count);
}
)";

const char kFragment[] = R"(#version 330 core
in vec3 v_color;
out vec4 out_color;
void main() { out_color = vec4(v_color, 1.0); }
)";

bool compile(GLenum type, const std::string& source, GLuint* out, std::string& error) {
  const GLuint s = glCreateShader(type);
  const char* text = source.c_str();
  glShaderSource(s, 1, &text, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    glDeleteShader(s);
    return error = std::string("GL shader: ") + log, false;
  }
  *out = s;
  return true;
}

void rgb_of(uint32_t rgb, float out[3]) {
  out[0] = static_cast<float>((rgb >> 16) & 0xFF) / 255.f;
  out[1] = static_cast<float>((rgb >> 8) & 0xFF) / 255.f;
  out[2] = static_cast<float>(rgb & 0xFF) / 255.f;
}

int bucket_of(uint32_t count) {
  int b = 0;
  while (b < kBuckets - 1 && (1u << b) < count) ++b;
  return b;
}

}  // namespace

GlRenderer::~GlRenderer() {
  if (programs_[0]) glDeleteProgram(programs_[0]);
  if (programs_[1]) glDeleteProgram(programs_[1]);
  const GLuint buffers[] = {instances_, sigma_buffer_, gauss_buffer_};
  const GLuint textures[] = {sigma_texture_, gauss_texture_};
  glDeleteBuffers(3, buffers);
  glDeleteTextures(2, textures);
  if (vao_) glDeleteVertexArrays(1, &vao_);
}

std::string GlRenderer::describe() {
  const auto str = [](GLenum e) {
    const GLubyte* s = glGetString(e);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
  };
  return str(GL_RENDERER) + ", OpenGL " + str(GL_VERSION);
}

bool GlRenderer::build_program(bool gpu, std::string& error) {
  GLuint vs = 0, fs = 0;
  if (!compile(GL_VERTEX_SHADER, std::string(kCommon) + (gpu ? kGpuMain : kCpuMain), &vs, error)) return false;
  if (!compile(GL_FRAGMENT_SHADER, kFragment, &fs, error)) {
    glDeleteShader(vs);
    return false;
  }
  const GLuint p = glCreateProgram();
  glAttachShader(p, vs);
  glAttachShader(p, fs);
  glLinkProgram(p);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetProgramInfoLog(p, sizeof log, nullptr, log);
    glDeleteProgram(p);
    return error = std::string("GL link: ") + log, false;
  }
  programs_[gpu ? 1 : 0] = p;
  return true;
}

bool GlRenderer::init(const NodeCache& cache, const GlRenderOptions& options, std::string& error) {
  if (!cache.ready()) return error = "the node cache holds no startup", false;
  if (epoxy_gl_version() < 33) return error = "OpenGL 3.3 is needed, the context has " + describe(), false;
  if (!build_program(false, error) || !build_program(true, error)) return false;
  const SpgHeader& h = cache.header();
  for (int k = 0, at = 0; k < kFieldCount; ++k) {
    field_offset_[k] = at;
    field_bits_[k] = h.layout.bits[k];
    at += h.layout.bits[k];
  }
  glGenVertexArrays(1, &vao_);
  glGenBuffers(1, &instances_);
  // The client's quasi-random Gaussian samples (core/gaussian_table.h).
  samples_ = options.samples;
  std::vector<Gaussian3Q12> g(samples_);
  build_gaussian3_table(GaussianSource::kSobol, g.data(), g.size());
  std::vector<float> gauss(4 * size_t{samples_}, 0.f);
  for (size_t i = 0; i < g.size(); ++i)
    for (int k = 0; k < 3; ++k) gauss[4 * i + k] = static_cast<float>(g[i].v[k]) / kGaussianOne;
  const auto texture_buffer = [](const std::vector<float>& data, GLuint* buffer, GLuint* texture) {
    glGenBuffers(1, buffer);
    glBindBuffer(GL_TEXTURE_BUFFER, *buffer);
    glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(data.size() * 4), data.data(), GL_STATIC_DRAW);
    glGenTextures(1, texture);
    glBindTexture(GL_TEXTURE_BUFFER, *texture);
    glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, *buffer);
  };
  texture_buffer(std::vector<float>(4, 0.f), &sigma_buffer_, &sigma_texture_);
  upload_sigmas(cache);
  texture_buffer(gauss, &gauss_buffer_, &gauss_texture_);
  const GLenum e = glGetError();
  if (e != GL_NO_ERROR) return error = "GL error " + std::to_string(e) + " setting up the renderer", false;
  return true;
}

void GlRenderer::upload_sigmas(const NodeCache& cache) {
  // The class sigmas as the decoder holds them (MU), one RGBA32F texel each;
  // again whenever classes arrive (protocol 4 sends them in pieces).
  const uint16_t classes = cache.header().class_count[0];
  std::vector<float> sigma(4 * size_t{std::max<uint16_t>(classes, 1)}, 0.f);
  for (uint16_t c = 0; c < classes; ++c)
    for (int k = 0; k < 3; ++k) sigma[4 * size_t{c} + k] = static_cast<float>(cache.decoder().sigma_p_mu(ClassId{c})[k]);
  glBindBuffer(GL_TEXTURE_BUFFER, sigma_buffer_);
  glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(sigma.size() * 4), sigma.data(), GL_STATIC_DRAW);
  uploaded_classes_ = cache.classes_changed();
}

bool GlRenderer::draw(const NodeCache& cache, const Camera& camera, int width, int height, const GlRenderOptions& o,
                      GlFrameStats* stats, std::string& error) {
  GlFrameStats s;
  if (cache.classes_changed() != uploaded_classes_) upload_sigmas(cache);
  const SpgHeader& h = cache.header();
  const uint32_t n = cache.count();
  const float focal = static_cast<float>(camera.focal_q4) / 16.f;
  // Per node: in front of the near plane, and its count from its size on screen.
  // Each node is decoded once a frame: for its count, and kept for the
  // CPU-decode path's instance data.
  counts_.assign(n, 0);
  if (!o.gpu_decode) decoded_.resize(n);
  uint32_t in_bucket[kBuckets] = {};
  FixedNode scratch;
  const float point_area = static_cast<float>(o.point_size) * o.point_size;
  for (uint32_t slot = 0; slot < n; ++slot) {
    FixedNode& node = o.gpu_decode ? scratch : decoded_[slot];
    if (!cache.node_at(slot, &node)) continue;
    int32_t c[3];
    camera_space(camera, node.mean, c);
    if (c[2] <= camera.near_mu) continue;
    const auto length = [](const int32_t* v) {
      const float x = static_cast<float>(v[0]), y = static_cast<float>(v[1]), z = static_cast<float>(v[2]);
      return std::sqrt(x * x + y * y + z * z);
    };
    const float scale = focal / static_cast<float>(c[2]);
    const float s1 = length(node.axis[0]) * scale, s2 = length(node.axis[1]) * scale;
    const float want = kCoverage * 3.14159265f * (2 * s1) * (2 * s2) / point_area * static_cast<float>(o.quality_q8) / 256.f;
    const uint32_t count = static_cast<uint32_t>(std::clamp(std::ceil(want), 1.f, static_cast<float>(samples_)));
    counts_[slot] = static_cast<uint16_t>(count);
    ++in_bucket[bucket_of(count)];
  }
  // Slots by bucket (a counting sort), then their instance data in that order.
  uint32_t start[kBuckets + 1] = {};
  for (int b = 0; b < kBuckets; ++b) start[b + 1] = start[b] + in_bucket[b];
  order_.assign(start[kBuckets], 0);
  uint32_t fill[kBuckets];
  std::copy(start, start + kBuckets, fill);
  for (uint32_t slot = 0; slot < n; ++slot)
    if (counts_[slot]) order_[fill[bucket_of(counts_[slot])]++] = slot;
  const size_t stride = o.gpu_decode ? kGpuStride : kCpuStride;
  staging_.assign(order_.size() * stride, 0);
  float grey[3];
  rgb_of(o.grey_rgb, grey);
  for (size_t i = 0; i < order_.size(); ++i) {
    uint8_t* out = staging_.data() + i * stride;
    const uint32_t slot = order_[i];
    const uint32_t count = counts_[slot];
    s.points += count;
    if (o.gpu_decode) {
      const uint8_t* record = cache.decoded() ? nullptr : cache.record_at(slot);
      if (record == nullptr) return error = "GPU decode needs the packed records (a cache without decoded nodes)", false;
      std::memcpy(out, record, cache.record_bytes());
      std::memcpy(out + 32, &count, 4);
    } else {
      const FixedNode& node = decoded_[slot];
      float f[18];
      for (int k = 0; k < 3; ++k) f[k] = static_cast<float>(node.mean[k]);
      for (int a = 0; a < 3; ++a)
        for (int k = 0; k < 3; ++k) f[3 + 3 * a + k] = static_cast<float>(node.axis[a][k]);
      for (int k = 0; k < 3; ++k) f[12 + k] = h.has_normals() ? node.normal_frame[2][k] / 16384.f : (k == 2 ? -1.f : 0.f);
      for (int k = 0; k < 3; ++k) f[15 + k] = h.has_color() && !o.grey ? node.color[k] / 255.f : grey[k];
      std::memcpy(out, f, sizeof f);
      std::memcpy(out + sizeof f, &count, 4);
    }
  }
  s.nodes = static_cast<uint32_t>(order_.size());

  float clear[3];
  rgb_of(o.clear_rgb, clear);
  glViewport(0, 0, width, height);
  glClearColor(clear[0], clear[1], clear[2], 1.f);
  glClearDepth(1.0);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glEnable(GL_PROGRAM_POINT_SIZE);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  const GLuint p = programs_[o.gpu_decode ? 1 : 0];
  glUseProgram(p);
  float rot[9];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) rot[c * 3 + r] = static_cast<float>(camera.rotation[r][c]) / 16384.f;  // column-major
  glUniformMatrix3fv(glGetUniformLocation(p, "rotation"), 1, GL_FALSE, rot);
  glUniform3f(glGetUniformLocation(p, "eye"), static_cast<float>(camera.eye[0]), static_cast<float>(camera.eye[1]),
              static_cast<float>(camera.eye[2]));
  glUniform4f(glGetUniformLocation(p, "lens"), focal, static_cast<float>(camera.center_q4[0]) / 16.f,
              static_cast<float>(camera.center_q4[1]) / 16.f, static_cast<float>(o.point_size));
  glUniform4f(glGetUniformLocation(p, "screen"), static_cast<float>(width), static_cast<float>(height),
              static_cast<float>(camera.near_mu), static_cast<float>(camera.far_mu));
  const float ll = std::sqrt(o.light[0] * o.light[0] + o.light[1] * o.light[1] + o.light[2] * o.light[2]);
  glUniform3f(glGetUniformLocation(p, "light"), o.light[0] / ll, o.light[1] / ll, o.light[2] / ll);
  glUniform1f(glGetUniformLocation(p, "ambient"), o.ambient);
  glUniform1i(glGetUniformLocation(p, "lighting"), o.lighting && h.has_normals());
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_BUFFER, gauss_texture_);
  glUniform1i(glGetUniformLocation(p, "gauss"), 0);
  if (o.gpu_decode) {
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_BUFFER, sigma_texture_);
    glUniform1i(glGetUniformLocation(p, "sigma_p"), 1);
    glUniform1iv(glGetUniformLocation(p, "field_offset"), kFieldCount, field_offset_);
    glUniform1iv(glGetUniformLocation(p, "field_bits"), kFieldCount, field_bits_);
    const int32_t* e = cache.decoder().extent_mu();
    glUniform3f(glGetUniformLocation(p, "extent_mu"), static_cast<float>(e[0]), static_cast<float>(e[1]),
                static_cast<float>(e[2]));
    glUniform1i(glGetUniformLocation(p, "has_normals"), h.has_normals());
    glUniform1i(glGetUniformLocation(p, "has_color"), h.has_color());
    glUniform1i(glGetUniformLocation(p, "grey"), o.grey);
    glUniform3f(glGetUniformLocation(p, "grey_rgb"), grey[0], grey[1], grey[2]);
  }
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, instances_);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(staging_.size()), staging_.data(), GL_STREAM_DRAW);
  for (int b = 0; b < kBuckets; ++b) {
    if (in_bucket[b] == 0) continue;
    // This bucket's instances: the attributes start at its first one.
    const size_t base = start[b] * stride;
    const auto at = [&](size_t offset) { return reinterpret_cast<const void*>(base + offset); };
    const GLsizei st = static_cast<GLsizei>(stride);
    if (o.gpu_decode) {
      glVertexAttribIPointer(0, 4, GL_UNSIGNED_INT, st, at(0));
      glVertexAttribIPointer(1, 4, GL_UNSIGNED_INT, st, at(16));
      glVertexAttribIPointer(6, 1, GL_UNSIGNED_INT, st, at(32));
      for (GLuint a : {0u, 1u, 6u}) {
        glEnableVertexAttribArray(a);
        glVertexAttribDivisor(a, 1);
      }
    } else {
      for (GLuint a = 0; a < 6; ++a) {
        glVertexAttribPointer(a, 3, GL_FLOAT, GL_FALSE, st, at(12 * a));
        glEnableVertexAttribArray(a);
        glVertexAttribDivisor(a, 1);
      }
      glVertexAttribIPointer(6, 1, GL_UNSIGNED_INT, st, at(72));
      glEnableVertexAttribArray(6);
      glVertexAttribDivisor(6, 1);
    }
    const GLsizei vertices = std::min<GLsizei>(1 << b, samples_);
    glDrawArraysInstanced(GL_POINTS, 0, b == kBuckets - 1 ? samples_ : vertices, static_cast<GLsizei>(in_bucket[b]));
    ++s.draws;
  }
  glBindVertexArray(0);
  const GLenum e = glGetError();
  if (e != GL_NO_ERROR) return error = "GL error " + std::to_string(e) + " while drawing", false;
  if (stats) *stats = s;
  return true;
}

GlOffscreen::~GlOffscreen() {
  const GLuint fbos[] = {fbo_, resolve_fbo_};
  const GLuint rbs[] = {color_, depth_, resolve_color_};
  glDeleteFramebuffers(2, fbos);
  glDeleteRenderbuffers(3, rbs);
}

bool GlOffscreen::init(int width, int height, int msaa, std::string& error) {
  width_ = width;
  height_ = height;
  msaa_ = msaa;
  GLint max_samples = 0;
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  if (msaa > max_samples) return error = "--msaa " + std::to_string(msaa) + ": this GL has at most " + std::to_string(max_samples), false;
  const auto make = [&](GLuint* fbo, GLuint* color, GLuint* depth, int samples) {
    glGenFramebuffers(1, fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, *fbo);
    glGenRenderbuffers(1, color);
    glBindRenderbuffer(GL_RENDERBUFFER, *color);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_RGBA8, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, *color);
    if (depth) {
      glGenRenderbuffers(1, depth);
      glBindRenderbuffer(GL_RENDERBUFFER, *depth);
      glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, GL_DEPTH_COMPONENT24, width, height);
      glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, *depth);
    }
    return glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
  };
  if (!make(&fbo_, &color_, &depth_, msaa)) return error = "GL: the offscreen framebuffer is incomplete", false;
  if (msaa > 0 && !make(&resolve_fbo_, &resolve_color_, nullptr, 0))
    return error = "GL: the resolve framebuffer is incomplete", false;
  return true;
}

void GlOffscreen::bind() const { glBindFramebuffer(GL_FRAMEBUFFER, fbo_); }

bool GlOffscreen::read(std::vector<uint8_t>& rgb, std::string& error) {
  if (msaa_ > 0) {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, resolve_fbo_);
    glBlitFramebuffer(0, 0, width_, height_, 0, 0, width_, height_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    glBindFramebuffer(GL_FRAMEBUFFER, resolve_fbo_);
  } else {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  }
  const bool ok = gl_read_pixels(width_, height_, rgb, error);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  return ok;
}

void gl_finish() { glFinish(); }

bool gl_read_pixels(int width, int height, std::vector<uint8_t>& rgb, std::string& error) {
  std::vector<uint8_t> rows(static_cast<size_t>(width) * height * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rows.data());
  const GLenum e = glGetError();
  if (e != GL_NO_ERROR) return error = "GL error " + std::to_string(e) + " reading the pixels back", false;
  rgb.resize(static_cast<size_t>(width) * height * 3);
  for (int y = 0; y < height; ++y)  // GL's rows run bottom to top
    for (int x = 0; x < width; ++x)
      for (int k = 0; k < 3; ++k)
        rgb[(static_cast<size_t>(y) * width + x) * 3 + k] = rows[(static_cast<size_t>(height - 1 - y) * width + x) * 4 + k];
  return true;
}

EglContext::~EglContext() {
  if (display_ == nullptr) return;
  EGLDisplay d = static_cast<EGLDisplay>(display_);
  eglMakeCurrent(d, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  if (surface_) eglDestroySurface(d, static_cast<EGLSurface>(surface_));
  if (context_) eglDestroyContext(d, static_cast<EGLContext>(context_));
  eglTerminate(d);
}

bool EglContext::open(std::string& error) {
  EGLDisplay d = EGL_NO_DISPLAY;
  const bool surfaceless = epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_MESA_platform_surfaceless");
  if (surfaceless) d = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (d == EGL_NO_DISPLAY) d = eglGetDisplay(EGL_DEFAULT_DISPLAY);
  EGLint major = 0, minor = 0;
  if (d == EGL_NO_DISPLAY || !eglInitialize(d, &major, &minor))
    return error = "EGL: no display could be initialized (error " + std::to_string(eglGetError()) + ")", false;
  display_ = d;
  if (!eglBindAPI(EGL_OPENGL_API)) return error = "EGL: this EGL has no desktop OpenGL", false;
  const EGLint config_attributes[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint configs = 0;
  eglChooseConfig(d, config_attributes, &config, 1, &configs);
  const EGLint context_attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3,
                                       EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
  EGLContext c = eglCreateContext(d, configs > 0 ? config : EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, context_attributes);
  if (c == EGL_NO_CONTEXT)
    return error = "EGL: no OpenGL 3.3 core context (error " + std::to_string(eglGetError()) + ")", false;
  context_ = c;
  EGLSurface surface = EGL_NO_SURFACE;
  if (!eglMakeCurrent(d, EGL_NO_SURFACE, EGL_NO_SURFACE, c)) {
    // No surfaceless contexts here: a small pbuffer to be current on (we draw offscreen anyway).
    const EGLint pbuffer[] = {EGL_WIDTH, 16, EGL_HEIGHT, 16, EGL_NONE};
    if (configs > 0) surface = eglCreatePbufferSurface(d, config, pbuffer);
    if (surface == EGL_NO_SURFACE || !eglMakeCurrent(d, surface, surface, c))
      return error = "EGL: the context cannot be made current (error " + std::to_string(eglGetError()) + ")", false;
    surface_ = surface;
  }
  return true;
}

}  // namespace stipple
