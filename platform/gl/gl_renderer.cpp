// stipple platform — the GL client's renderer. See gl_renderer.h.
#include "platform/gl/gl_renderer.h"

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/gaussian_table.h"
#include "core/node_format.h"
#include "core/elevation_ramp.h"

namespace stipple {
namespace {

constexpr int kBuckets = 11;
// Points per node: the 2σ ellipse's area in point-sized squares, five times
// over (gl_renderer.h).
constexpr float kCoverage = 5.f;  // counts up to 1, 2, 4, ... 1024 (and above, the buffer's size)
// Close-ups: nodes of σ over kDiscSigma px are drawn as their kDiscCut σ
// ellipse; smaller ones' points grow to at most kMaxPointSize px.
constexpr float kDiscSigma = 8.f;
constexpr float kDiscCut = 3.f;
constexpr int kDiscBucket = kBuckets;
constexpr float kMaxPointSize = 64.f;
// Splats (measured on the bunny and dragon, docs/viewers.md): cut at 3σ;
// the visibility pass draws each splat's core (1.5σ) pushed back by one
// radius, so that a splat's tail never hides its neighbours' centres.
constexpr float kSplatCut = 3.0f;
constexpr float kVisibilityCut = 1.5f;
constexpr float kVisibilityOffset = 1.0f;

// Instance data. GPU decode: the record's 8 words, then the count. CPU
// decode: mean, the three scaled axes, the normal frame's three columns
// (tangents, then the normal), σn (two floats and a pad), the colour (0..1),
// then the count (its low 16 bits; the point size in px above).
constexpr size_t kGpuStride = 8 * 4 + 4;
constexpr size_t kCpuFloats = 3 + 9 + 9 + 3 + 3;
constexpr size_t kCpuStride = kCpuFloats * 4 + 4;

// A node, decoded: what both kinds of drawing start from.
const char kCommon[] = R"(#version 330 core
uniform mat3 rotation;     // world -> camera rows: right, down, forward
uniform vec3 eye;          // MU
uniform vec4 lens;         // focal px, cx px, cy px, point size px
uniform vec4 screen;       // width, height, near, far (MU)
uniform samplerBuffer gauss;
uniform int shading;       // 0 none, 1 the node's normal, 2 surface normals
uniform int has_normals;
uniform vec3 extent_mu;
uniform int elevation_axis;  // -1: the model's colour; else a ramp of the mean along it
uniform int elevation_down;  // the axis points down
uniform vec3 ramp[5];        // core/elevation_ramp.h's kElevationRamp

struct Node {
  vec3 mean;      // MU
  mat3 axes;      // columns: sigma-scaled axes, MU
  mat3 nframe;    // columns: tangents t1, t2, the mean normal
  vec2 sigma_n;   // radians
  vec3 color;     // 0..1
};

// The node's colour: the model's, or by elevation.
vec3 node_color(Node n) {
  if (elevation_axis < 0) return n.color;
  float t = clamp(n.mean[elevation_axis] / extent_mu[elevation_axis], 0.0, 1.0);
  if (elevation_down != 0) t = 1.0 - t;
  float x = t * 4.0;
  int i = min(int(x), 3);
  return mix(ramp[i], ramp[i + 1], x - float(i));
}

// Clip position of a camera-space point.
vec4 clip_of(vec3 c) {
  float sx = lens.x * c.x / c.z + lens.y, sy = lens.x * c.y / c.z + lens.z;
  float depth = 2.0 * (c.z - screen.z) / (screen.w - screen.z) - 1.0;
  return vec4((2.0 * sx / screen.x - 1.0) * c.z, (1.0 - 2.0 * sy / screen.y) * c.z, depth * c.z, c.z);
}

// Surface normals (raster/point_renderer.h): a sample's offset along each
// tangent of the normal frame, in units of the node's spread along it, is
// how many sigma_n its normal turns. Rows of the map from the sample (in
// sigma units) to those offsets.
mat3 surface_rows(Node n) {
  vec3 r0 = transpose(n.axes) * n.nframe[0], r1 = transpose(n.axes) * n.nframe[1];
  float l0 = length(r0), l1 = length(r1);
  return mat3(l0 > 0.0 ? r0 / l0 : vec3(0.0), l1 > 0.0 ? r1 / l1 : vec3(0.0), vec3(0.0));
}
)";

// Lambert with ambient and a Blinn highlight, as raster/shading.h: the
// colour times ambient + (1 - ambient) max(0, L.n), plus strength
// max(0, H.n)^shininess on every channel. L, H and n in camera space.
// And the surface normals' turn (raster/point_renderer.h): the normal of a
// frame (columns: tangents, normal) turned by tangent offsets t, in units
// of sigma_n. Both the vertex and the fragment shaders use them.
const char kShade[] = R"(
uniform vec3 light;
uniform vec3 half_vector;
uniform float ambient;
uniform float specular;
uniform float shininess;
vec3 shade(vec3 color, vec3 n) {
  float k = ambient + (1.0 - ambient) * max(0.0, dot(light, n));
  float h = specular > 0.0 ? specular * pow(max(0.0, dot(half_vector, n)), shininess) : 0.0;
  return min(color * k + vec3(h), vec3(1.0));
}
vec3 turned(mat3 frame, vec2 sigma_n, vec2 t) {
  float a = sigma_n.x * t.x, b = sigma_n.y * t.y, theta = sqrt(a * a + b * b);
  float sinc = theta > 1e-6 ? sin(theta) / theta : 1.0;
  return cos(theta) * frame[2] + sinc * (a * frame[0] + b * frame[1]);
}
)";

// Points: vertex k of an instance is sample k of its node.
const char kPointsEmit[] = R"(
out vec3 v_color;
void emit(Node n, uint count) {
  if (uint(gl_VertexID) >= (count & 0xFFFFu)) {  // beyond this node's own count: dropped
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
    return;
  }
  vec3 g = texelFetch(gauss, gl_VertexID).xyz;
  vec3 c = rotation * (n.mean + n.axes * g - eye);
  gl_Position = clip_of(c);
  gl_PointSize = float(count >> 16);  // the node's point size (close-ups: larger)
  vec3 color = node_color(n);
  if (shading != 0) {
    vec3 normal = n.nframe[2];
    if (shading == 2) normal = turned(n.nframe, n.sigma_n, (transpose(surface_rows(n)) * g).xy);
    color = shade(color, rotation * normal);
  }
  v_color = color;
}
)";

// Splats: a quad (4 vertices, a strip) in the node's tangent plane spanned
// by its two main axes, cut at splat_cut sigma, each radius at least a pixel's
// footprint at the node's depth times kLowPass (the low-pass filter's
// approximation, gl_renderer.h). The visibility pass pushes it back along
// the view ray by depth_offset times its larger radius.
const char kSplatEmit[] = R"(
const float kLowPass = 1.0;
uniform float splat_cut;     // sigma
uniform float depth_offset;
out vec2 v_uv;                 // the fragment's place in the splat, sigma units
flat out vec3 v_color;
flat out mat3 v_frame;         // camera space: tangents, mean normal
flat out vec2 v_sigma_n;
flat out mat2 v_surface;       // the uv -> tangent-offset map (zero without surface normals)
void emit(Node n, uint count) {
  vec2 corner = vec2((gl_VertexID & 1) != 0 ? 1.0 : -1.0, (gl_VertexID & 2) != 0 ? 1.0 : -1.0) * splat_cut;
  vec3 c0 = rotation * (n.mean - eye);
  float footprint = kLowPass * max(c0.z, screen.z) / lens.x;  // MU a pixel at the node
  float s0 = length(n.axes[0]), s1 = length(n.axes[1]);
  vec3 e0 = s0 > 0.0 ? n.axes[0] / s0 : vec3(1.0, 0.0, 0.0), e1 = s1 > 0.0 ? n.axes[1] / s1 : vec3(0.0, 1.0, 0.0);
  float r0 = sqrt(s0 * s0 + footprint * footprint), r1 = sqrt(s1 * s1 + footprint * footprint);
  vec3 c = rotation * (n.mean + e0 * r0 * corner.x + e1 * r1 * corner.y - eye);
  c += depth_offset * max(r0, r1) * normalize(c);
  gl_Position = clip_of(c);
  // A splat facing away is dropped: its surface's front is another's.
  if (has_normals != 0 && dot(rotation * n.nframe[2], c0) > 0.0) gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
  v_uv = corner;
  v_color = node_color(n);
  v_frame = rotation * n.nframe;
  v_sigma_n = n.sigma_n;
  mat3 rows = surface_rows(n);  // columns: the two rows; the sample is (u, v, 0)
  v_surface = mat2(rows[0].x, rows[1].x, rows[0].y, rows[1].y);
  if (shading != 2) v_surface = mat2(0.0);
}
)";

const char kCpuMain[] = R"(
layout(location = 0) in vec3 mean;
layout(location = 1) in vec3 axis0;
layout(location = 2) in vec3 axis1;
layout(location = 3) in vec3 axis2;
layout(location = 4) in vec3 tangent1;
layout(location = 5) in vec3 tangent2;
layout(location = 7) in vec3 normal;
layout(location = 8) in vec3 sigma_n;
layout(location = 9) in vec3 color;
layout(location = 6) in uint count;
void main() { emit(Node(mean, mat3(axis0, axis1, axis2), mat3(tangent1, tangent2, normal), sigma_n.xy, color), count); }
)";

// The record's bit fields, decoded as docs/format.md §5 says.
const char kGpuMain[] = R"(
layout(location = 0) in uvec4 rec0;
layout(location = 1) in uvec4 rec1;
layout(location = 6) in uint count;
uniform int field_offset[18];
uniform int field_bits[18];
uniform samplerBuffer sigmas;  // sigma_p classes (sigma1..3, MU), then sigma_n classes (radians)
uniform int sigma_n_base;
uniform int has_color, grey;
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
  Node n;
  for (int a = 0; a < 3; ++a) n.mean[a] = (float(field(a)) + 0.5) * extent_mu[a] / float(1 << field_bits[a]);
  mat3 f = frame(3, PI);
  vec3 s = texelFetch(sigmas, int(field(6))).xyz;
  n.axes = mat3(f[0] * s.x, f[1] * s.y, f[2] * s.z);
  n.nframe = mat3(vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0), vec3(0.0, 0.0, -1.0));
  n.sigma_n = vec2(0.0);
  if (has_normals != 0) {
    n.nframe = frame(7, PI);
    n.sigma_n = texelFetch(sigmas, sigma_n_base + int(field(10))).xy;
  }
  n.color = grey_rgb;
  if (has_color != 0 && grey == 0)
    n.color = vec3(float(field(11)) / float((1 << field_bits[11]) - 1), float(field(12)) / float((1 << field_bits[12]) - 1),
                   float(field(13)) / float((1 << field_bits[13]) - 1));
  emit(n, count);
}
)";

// Points: the colour, alpha 1 (the coverage the resolve reads).
const char kPointsFragment[] = R"(#version 330 core
in vec3 v_color;
out vec4 out_color;
void main() { out_color = vec4(v_color, 1.0); }
)";

// Splats: outside the cut ellipse nothing; else the Gaussian weight times
// the pixel's shaded colour, and the weight (added up by blending; the
// visibility pass writes depth only).
const char kSplatFragment[] = R"(
in vec2 v_uv;
flat in vec3 v_color;
flat in mat3 v_frame;
flat in vec2 v_sigma_n;
flat in mat2 v_surface;
uniform int visibility;  // 1: the visibility pass, 2: opaque discs, else the attribute pass
uniform float cut2;      // the splat's square radius (sigma^2): the attribute pass's cut
uniform float core2;     // the visibility pass: depth within this square radius
uniform float cover2;    // a disc's square radius
out vec4 out_color;
// The colour at this place in the splat, the normal turned as surface
// normals turn it.
vec3 shaded() { return shading == 0 ? v_color : shade(v_color, turned(v_frame, v_sigma_n, v_surface * v_uv)); }
void main() {
  float r2 = dot(v_uv, v_uv);
  if (visibility == 2) {  // a close-up's disc: opaque, out to cover2, shaded by its mean normal
    if (r2 > cover2) discard;
    out_color = vec4(shading == 0 ? v_color : shade(v_color, v_frame[2]), 1.0);
    return;
  }
  if (visibility != 0) {  // depth only, from the core
    if (r2 > core2) discard;
    out_color = vec4(0.0);
    return;
  }
  if (r2 > cut2) discard;
  float w = exp(-0.5 * r2);
  out_color = vec4(shaded() * w, w);
}
)";

// Full-screen passes: one triangle over the viewport.
const char kFullScreenVertex[] = R"(#version 330 core
void main() {
  vec2 p = vec2((gl_VertexID & 1) != 0 ? 3.0 : -1.0, (gl_VertexID & 2) != 0 ? 3.0 : -1.0);
  gl_Position = vec4(p, 0.0, 1.0);
}
)";

// The covered pixels among a pixel's 3 x 3 (inside `size`), as `at` reads
// them: their colours' sum and their count (each shader defines `at`).
const char kNeighbours[] = R"(
vec4 covered_around(ivec2 p, ivec2 size) {
  vec4 sum = vec4(0.0);
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      ivec2 q = p + ivec2(dx, dy);
      if (q.x < 0 || q.y < 0 || q.x >= size.x || q.y >= size.y) continue;
      vec4 c = at(q);
      if (c.a > 0.5) sum += vec4(c.rgb, 1.0);
    }
  return sum;
}
)";

// The resolve's step 1 (raster/resolve.h): an uncovered pixel with at least
// 6 of its 8 neighbours covered takes their mean colour; and, for holes wider
// than a pixel (close-ups: nodes seen larger than their samples cover), one
// the coarse level filled (below) takes that level's colour.
const char kFillFragment[] = R"(
uniform sampler2D coarse;  // alpha 0.5: filled at half the resolution
uniform int use_coarse;
out vec4 out_color;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy), size = textureSize(frame, 0);
  vec4 here = at(p);
  if (here.a > 0.5) {
    out_color = here;
    return;
  }
  vec4 sum = covered_around(p, size);
  out_color = sum.a >= 6.0 ? vec4(sum.rgb / sum.a, 1.0) : vec4(0.0);
  if (sum.a < 6.0 && use_coarse != 0) {
    vec4 c = texelFetch(coarse, p / 2, 0);
    if (c.a > 0.25 && c.a < 0.75) out_color = vec4(c.rgb, 1.0);
  }
}
)";
// The fine level, read as it is (alpha: covered).
const char kFineAt[] = R"(#version 330 core
uniform sampler2D frame;
vec4 at(ivec2 q) { return texelFetch(frame, q, 0); }
)";

// The coarse level, read from the fine: a coarse pixel is its 2 x 2's
// covered mean.
const char kCoarseAt[] = R"(#version 330 core
uniform sampler2D frame;  // the fine level, alpha: covered
vec4 at(ivec2 q) {
  ivec2 size = textureSize(frame, 0);
  vec4 sum = vec4(0.0);
  for (int k = 0; k < 4; ++k) {
    ivec2 f = 2 * q + ivec2(k & 1, k >> 1);
    if (f.x >= size.x || f.y >= size.y) continue;
    vec4 c = texelFetch(frame, f, 0);
    if (c.a > 0.5) sum += vec4(c.rgb, 1.0);
  }
  return sum.a > 0.0 ? vec4(sum.rgb / sum.a, 1.0) : vec4(0.0);
}
)";
// Holes wider than a pixel, at half the resolution (the pull of a pull-push
// hole filling: Grossman and Dally 1998; Marroquim, Kraus and Cavalcanti
// 2007): a coarse pixel is covered where any of its 2 x 2 is, with their
// mean colour; an uncovered one with all 8 of its coarse neighbours covered
// is filled with their mean (alpha 0.5) — a hole inside the surface, never
// a gap between two parts of it (with 6 of 8 it filled the dragon's).
const char kPullFragment[] = R"(
out vec4 out_color;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy), coarse = (textureSize(frame, 0) + 1) / 2;
  vec4 here = at(p);
  if (here.a > 0.5) {
    out_color = here;
    return;
  }
  vec4 sum = covered_around(p, coarse);
  out_color = sum.a >= 8.0 ? vec4(sum.rgb / sum.a, 0.5) : vec4(0.0);
}
)";

// Steps 2 and 3: a covered pixel is kept when its whole 3 x 3 block inside
// the frame is covered (beyond the frame counts as covered), or when it is
// an isolated speck (at most 3 covered neighbours); a kept pixel takes the
// mean of its block's covered pixels, every other pixel the clear colour.
const char kBlendFragment[] = R"(
uniform vec3 clear_rgb;
out vec4 out_color;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy), size = textureSize(frame, 0);
  out_color = vec4(clear_rgb, 1.0);
  if (at(p).a < 0.5) return;
  vec4 sum = covered_around(p, size);
  ivec2 lo = max(p - 1, ivec2(0)), hi = min(p + 1, size - 1);
  float inside = float((hi.x - lo.x + 1) * (hi.y - lo.y + 1));
  if (sum.a == inside || (inside == 9.0 && sum.a <= 4.0)) out_color = vec4(sum.rgb / sum.a, 1.0);
}
)";

// The splats' normalization: the weighted colour over the weight, where the
// visibility pass covered the pixel (alpha: covered, for the resolve).
const char kNormalizeFragment[] = R"(#version 330 core
uniform sampler2D frame;  // weighted colour, weight
uniform sampler2D cover;  // alpha: covered
uniform vec3 clear_rgb;
out vec4 out_color;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  vec4 a = texelFetch(frame, p, 0), points = texelFetch(cover, p, 0);
  out_color = points.a < 0.5 ? vec4(clear_rgb, 0.0) : a.a > 0.0 ? vec4(a.rgb / a.a, 1.0) : points;
}
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

bool link(const std::string& vertex, const std::string& fragment, GLuint* out, std::string& error) {
  GLuint vs = 0, fs = 0;
  if (!compile(GL_VERTEX_SHADER, vertex, &vs, error)) return false;
  if (!compile(GL_FRAGMENT_SHADER, fragment, &fs, error)) {
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
  *out = p;
  return true;
}

void delete_texture(GLuint* t) {
  if (*t) glDeleteTextures(1, t);
  *t = 0;
}

}  // namespace

GlRenderer::~GlRenderer() {
  for (auto& kind : programs_)
    for (GLuint p : kind)
      if (p) glDeleteProgram(p);
  for (GLuint p : {fill_program_, blend_program_, normalize_program_, pull_program_})
    if (p) glDeleteProgram(p);
  const GLuint buffers[] = {instances_, sigma_buffer_, gauss_buffer_};
  const GLuint textures[] = {sigma_texture_, gauss_texture_, scene_tex_, fill_tex_, accum_tex_, coarse_tex_};
  const GLuint fbos[] = {scene_fbo_, fill_fbo_, accum_fbo_, coarse_fbo_};
  glDeleteBuffers(3, buffers);
  glDeleteTextures(6, textures);
  glDeleteFramebuffers(4, fbos);
  if (depth_rb_) glDeleteRenderbuffers(1, &depth_rb_);
  if (vao_) glDeleteVertexArrays(1, &vao_);
  if (empty_vao_) glDeleteVertexArrays(1, &empty_vao_);
}

std::string GlRenderer::describe() {
  const auto str = [](GLenum e) {
    const GLubyte* s = glGetString(e);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
  };
  return str(GL_RENDERER) + ", OpenGL " + str(GL_VERSION);
}

bool GlRenderer::build_programs(std::string& error) {
  const std::string shade_header = std::string("#version 330 core\nuniform int shading;\n") + kShade;
  for (int gpu = 0; gpu < 2; ++gpu) {
    const std::string decode = gpu ? kGpuMain : kCpuMain;
    if (!link(std::string(kCommon) + kShade + kPointsEmit + decode, kPointsFragment, &programs_[gpu][0], error) ||
        !link(std::string(kCommon) + kShade + kSplatEmit + decode, shade_header + kSplatFragment, &programs_[gpu][1], error))
      return false;
  }
  return link(kFullScreenVertex, std::string(kFineAt) + kNeighbours + kFillFragment, &fill_program_, error) &&
         link(kFullScreenVertex, std::string(kFineAt) + kNeighbours + kBlendFragment, &blend_program_, error) &&
         link(kFullScreenVertex, kNormalizeFragment, &normalize_program_, error) &&
         link(kFullScreenVertex, std::string(kCoarseAt) + kNeighbours + kPullFragment, &pull_program_, error);
}

bool GlRenderer::init(const NodeCache& cache, const GlRenderOptions& options, std::string& error) {
  if (!cache.ready()) return error = "the node cache holds no startup", false;
  if (epoxy_gl_version() < 33) return error = "OpenGL 3.3 is needed, the context has " + describe(), false;
  if (!build_programs(error)) return false;
  const SpgHeader& h = cache.header();
  for (int k = 0, at = 0; k < kFieldCount; ++k) {
    field_offset_[k] = at;
    field_bits_[k] = h.layout.bits[k];
    at += h.layout.bits[k];
  }
  glGenVertexArrays(1, &vao_);
  glGenVertexArrays(1, &empty_vao_);
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
  // The class sigmas as the decoder holds them, one RGBA32F texel each: σp
  // (MU), then σn (radians); again whenever classes arrive (protocol 4
  // sends them in pieces).
  const uint16_t* classes = cache.header().class_count;
  std::vector<float> sigma(4 * (size_t{classes[0]} + classes[1] + 1), 0.f);
  for (uint16_t c = 0; c < classes[0]; ++c)
    for (int k = 0; k < 3; ++k) sigma[4 * size_t{c} + k] = static_cast<float>(cache.decoder().sigma_p_mu(ClassId{c})[k]);
  if (cache.header().has_normals())
    for (uint16_t c = 0; c < classes[1]; ++c)
      for (int k = 0; k < 2; ++k)
        sigma[4 * (size_t{classes[0]} + c) + k] = static_cast<float>(cache.decoder().sigma_n_q12(ClassId{c})[k]) / 4096.f;
  glBindBuffer(GL_TEXTURE_BUFFER, sigma_buffer_);
  glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(sigma.size() * 4), sigma.data(), GL_STATIC_DRAW);
  uploaded_classes_ = cache.classes_changed();
}

bool GlRenderer::size_targets(int width, int height, std::string& error) {
  if (width == target_width_ && height == target_height_) return true;
  const auto texture = [&](GLuint* t, GLenum format, GLenum type, int divide = 1) {
    delete_texture(t);
    glGenTextures(1, t);
    glBindTexture(GL_TEXTURE_2D, *t);
    glTexImage2D(GL_TEXTURE_2D, 0, static_cast<GLint>(format), (width + divide - 1) / divide, (height + divide - 1) / divide, 0,
                 GL_RGBA, type, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  };
  texture(&scene_tex_, GL_RGBA8, GL_UNSIGNED_BYTE);
  texture(&fill_tex_, GL_RGBA8, GL_UNSIGNED_BYTE);
  texture(&accum_tex_, GL_RGBA16F, GL_FLOAT);
  texture(&coarse_tex_, GL_RGBA8, GL_UNSIGNED_BYTE, 2);
  if (depth_rb_ == 0) glGenRenderbuffers(1, &depth_rb_);
  glBindRenderbuffer(GL_RENDERBUFFER, depth_rb_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, width, height);
  const auto attach = [&](GLuint* fbo, GLuint tex, bool depth) {
    if (*fbo == 0) glGenFramebuffers(1, fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, *fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex, 0);
    if (depth) glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_rb_);
    return glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
  };
  // The accumulation shares the scene's depth: the visibility pass writes it.
  if (!attach(&scene_fbo_, scene_tex_, true) || !attach(&fill_fbo_, fill_tex_, false) || !attach(&accum_fbo_, accum_tex_, true) ||
      !attach(&coarse_fbo_, coarse_tex_, false))
    return error = "GL: an offscreen target of " + std::to_string(width) + "x" + std::to_string(height) + " is incomplete", false;
  target_width_ = width;
  target_height_ = height;
  return true;
}

void GlRenderer::set_uniforms(unsigned p, const NodeCache& cache, const Camera& camera, int width, int height,
                              const GlRenderOptions& o) const {
  const SpgHeader& h = cache.header();
  const float focal = static_cast<float>(camera.focal_q4) / 16.f;
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
  // Light and half vector (light + the view's -z) in camera space, as raster/shading.cpp.
  float l[3], hv[3];
  const float ll = std::sqrt(o.light[0] * o.light[0] + o.light[1] * o.light[1] + o.light[2] * o.light[2]);
  for (int k = 0; k < 3; ++k) l[k] = o.light[k] / ll, hv[k] = l[k] + (k == 2 ? -1.f : 0.f);
  const float hl = std::sqrt(hv[0] * hv[0] + hv[1] * hv[1] + hv[2] * hv[2]);
  if (hl > 0) hv[0] /= hl, hv[1] /= hl, hv[2] /= hl;
  else hv[0] = hv[1] = 0, hv[2] = -1;
  glUniform3fv(glGetUniformLocation(p, "light"), 1, l);
  glUniform3fv(glGetUniformLocation(p, "half_vector"), 1, hv);
  glUniform1f(glGetUniformLocation(p, "ambient"), o.ambient);
  glUniform1f(glGetUniformLocation(p, "specular"), o.specular);
  glUniform1f(glGetUniformLocation(p, "shininess"), o.shininess);
  glUniform1i(glGetUniformLocation(p, "has_normals"), h.has_normals());
  const int32_t* e = cache.decoder().extent_mu();
  glUniform3f(glGetUniformLocation(p, "extent_mu"), static_cast<float>(e[0]), static_cast<float>(e[1]), static_cast<float>(e[2]));
  glUniform1i(glGetUniformLocation(p, "elevation_axis"), spg_axis_index(o.elevation));
  glUniform1i(glGetUniformLocation(p, "elevation_down"), spg_axis_negative(o.elevation));
  float ramp[15];
  for (int k = 0; k < 5; ++k) rgb_of(kElevationRamp[k], ramp + 3 * k);
  glUniform3fv(glGetUniformLocation(p, "ramp"), 5, ramp);
  glUniform1i(glGetUniformLocation(p, "shading"), !(o.lighting && h.has_normals()) ? 0 : o.surface_normals ? 2 : 1);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_BUFFER, gauss_texture_);
  glUniform1i(glGetUniformLocation(p, "gauss"), 0);
  if (o.gpu_decode) {
    float grey[3];
    rgb_of(o.grey_rgb, grey);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_BUFFER, sigma_texture_);
    glUniform1i(glGetUniformLocation(p, "sigmas"), 1);
    glUniform1i(glGetUniformLocation(p, "sigma_n_base"), h.class_count[0]);
    glUniform1iv(glGetUniformLocation(p, "field_offset"), kFieldCount, field_offset_);
    glUniform1iv(glGetUniformLocation(p, "field_bits"), kFieldCount, field_bits_);
    glUniform1i(glGetUniformLocation(p, "has_color"), h.has_color());
    glUniform1i(glGetUniformLocation(p, "grey"), o.grey);
    glUniform3fv(glGetUniformLocation(p, "grey_rgb"), 1, grey);
  }
}

void GlRenderer::full_screen(unsigned p, unsigned texture, const float clear_rgb[3]) const {
  glUseProgram(p);
  const GLint clear = glGetUniformLocation(p, "clear_rgb");
  if (clear >= 0) glUniform3fv(clear, 1, clear_rgb);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, texture);
  glUniform1i(glGetUniformLocation(p, "frame"), 0);
  glBindVertexArray(empty_vao_);
  glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
}

bool GlRenderer::draw(const NodeCache& cache, const Camera& camera, int width, int height, const GlRenderOptions& o,
                      GlFrameStats* stats, std::string& error) {
  GlFrameStats s;
  if (cache.classes_changed() != uploaded_classes_) upload_sigmas(cache);
  const SpgHeader& h = cache.header();
  const uint32_t n = cache.count();
  const bool splats = o.splat == GlSplat::kEwa;
  const float focal = static_cast<float>(camera.focal_q4) / 16.f;
  // Per node: in front of the near plane, and its count from its size on
  // screen (a splat: one quad). Each node is decoded once a frame: for its
  // count, and kept for the CPU-decode path's instance data.
  counts_.assign(n, 0);
  sizes_.assign(n, o.point_size);
  buckets_.assign(n, 0);
  if (!o.gpu_decode) decoded_.resize(n);
  uint32_t in_bucket[kBuckets + 1] = {};  // and the discs'
  FixedNode scratch;
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
    // Close-ups. A node whose σ spans more than kDiscSigma pixels is drawn
    // as its kDiscCut σ ellipse, opaque (the splat program): its samples
    // would be sparser than the pixels they cover, and points past GL's
    // size limit cannot close that. With the point cap (a sparse scan kept
    // sparse) there are no discs. A smaller node that wants more points
    // than the samples hold draws them larger, by the square root of the
    // shortfall.
    if (std::sqrt(s1 * s2) > kDiscSigma && o.point_cap == 0 && o.close_ups) {
      counts_[slot] = 1;
      buckets_[slot] = kDiscBucket;
      ++in_bucket[kDiscBucket];
      continue;
    }
    const float size = static_cast<float>(o.point_size);
    // (Not the software client's doubled close-up points, raster/close_up.h:
    // with this count they cost the bunny's three views 0.8 dB past 1 px,
    // 0.5 past 2 px — docs/viewers.md.)
    const float want = kCoverage * 3.14159265f * (2 * s1) * (2 * s2) / (size * size) * static_cast<float>(o.quality_q8) / 256.f;
    uint32_t count = static_cast<uint32_t>(std::clamp(std::ceil(want), 1.f, static_cast<float>(samples_)));
    const float grown = want > static_cast<float>(count) ? size * std::sqrt(want / static_cast<float>(count)) : size;
    sizes_[slot] = static_cast<uint8_t>(std::min(std::ceil(grown), kMaxPointSize));
    // The point cap: at most point_cap times the original points under the
    // node (a sparse scan stays sparse: the cap does not grow the points).
    const uint32_t points = cache.points_at(slot);
    if (o.point_cap > 0 && points > 0) count = std::min(count, uint32_t{o.point_cap} * points);
    counts_[slot] = static_cast<uint16_t>(count);
    buckets_[slot] = static_cast<uint8_t>(bucket_of(count));
    ++in_bucket[buckets_[slot]];
  }
  // Slots by bucket (a counting sort), then their instance data in that order.
  uint32_t start[kBuckets + 2] = {};
  for (int b = 0; b <= kBuckets; ++b) start[b + 1] = start[b] + in_bucket[b];
  order_.assign(start[kBuckets + 1], 0);
  uint32_t fill[kBuckets + 1];
  std::copy(start, start + kBuckets + 1, fill);
  for (uint32_t slot = 0; slot < n; ++slot)
    if (counts_[slot]) order_[fill[buckets_[slot]]++] = slot;
  const size_t stride = o.gpu_decode ? kGpuStride : kCpuStride;
  staging_.assign(order_.size() * stride, 0);
  float grey[3];
  rgb_of(o.grey_rgb, grey);
  for (size_t i = 0; i < order_.size(); ++i) {
    uint8_t* out = staging_.data() + i * stride;
    const uint32_t slot = order_[i];
    const uint32_t count = counts_[slot], word = count | uint32_t{sizes_[slot]} << 16;
    s.points += count;
    if (o.gpu_decode) {
      const uint8_t* record = cache.decoded() ? nullptr : cache.record_at(slot);
      if (record == nullptr) return error = "GPU decode needs the packed records (a cache without decoded nodes)", false;
      std::memcpy(out, record, cache.record_bytes());
      std::memcpy(out + 32, &word, 4);
    } else {
      const FixedNode& node = decoded_[slot];
      float f[kCpuFloats] = {};
      for (int k = 0; k < 3; ++k) f[k] = static_cast<float>(node.mean[k]);
      for (int a = 0; a < 3; ++a)
        for (int k = 0; k < 3; ++k) f[3 + 3 * a + k] = static_cast<float>(node.axis[a][k]);
      for (int a = 0; a < 3; ++a)
        for (int k = 0; k < 3; ++k) {
          const float missing = a == k ? (a == 2 ? -1.f : 1.f) : 0.f;  // no normals: the GPU decode's frame
          f[12 + 3 * a + k] = h.has_normals() ? node.normal_frame[a][k] / 16384.f : missing;
        }
      for (int k = 0; k < 2; ++k) f[21 + k] = static_cast<float>(node.sigma_n[k]) / 4096.f;
      for (int k = 0; k < 3; ++k) f[24 + k] = h.has_color() && !o.grey ? node.color[k] / 255.f : grey[k];
      std::memcpy(out, f, sizeof f);
      std::memcpy(out + sizeof f, &word, 4);
    }
  }
  s.nodes = static_cast<uint32_t>(order_.size());

  // Where the picture goes: the caller's framebuffer, straight (points
  // without the resolve) or through the offscreen targets.
  GLint caller = 0;
  glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &caller);
  const bool offscreen = splats || o.resolve;
  if (offscreen && !size_targets(width, height, error)) return false;
  float clear[3];
  rgb_of(o.clear_rgb, clear);
  glViewport(0, 0, width, height);
  glBindFramebuffer(GL_FRAMEBUFFER, offscreen ? scene_fbo_ : static_cast<GLuint>(caller));
  if (offscreen) glClearColor(0.f, 0.f, 0.f, 0.f);  // alpha: nothing covered, no weight
  else glClearColor(clear[0], clear[1], clear[2], 1.f);
  glClearDepth(1.0);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glEnable(GL_PROGRAM_POINT_SIZE);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  const GLuint p = programs_[o.gpu_decode ? 1 : 0][0];
  set_uniforms(p, cache, camera, width, height, o);
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, instances_);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(staging_.size()), staging_.data(), GL_STREAM_DRAW);
  // Buckets [first, last) as points (a bucket's power of two vertices an
  // instance) or as splats (4).
  const auto draw_instances = [&](int first, int last, bool as_splats) {
    for (int b = first; b < last; ++b) {
      if (in_bucket[b] == 0) continue;
      // This bucket's instances: the attributes start at its first one.
      const size_t base = start[b] * stride;
      const auto at = [&](size_t offset) { return reinterpret_cast<const void*>(base + offset); };
      const GLsizei st = static_cast<GLsizei>(stride);
      const auto per_instance = [](GLuint a) {
        glEnableVertexAttribArray(a);
        glVertexAttribDivisor(a, 1);
      };
      if (o.gpu_decode) {
        glVertexAttribIPointer(0, 4, GL_UNSIGNED_INT, st, at(0));
        glVertexAttribIPointer(1, 4, GL_UNSIGNED_INT, st, at(16));
        glVertexAttribIPointer(6, 1, GL_UNSIGNED_INT, st, at(32));
        for (GLuint a : {0u, 1u, 6u}) per_instance(a);
      } else {
        // mean, three axes, two tangents (locations 0-5), the normal (7), σn (8), the colour (9).
        const GLuint locations[9] = {0, 1, 2, 3, 4, 5, 7, 8, 9};
        for (int k = 0; k < 9; ++k) {
          glVertexAttribPointer(locations[k], 3, GL_FLOAT, GL_FALSE, st, at(12 * size_t(k)));
          per_instance(locations[k]);
        }
        glVertexAttribIPointer(6, 1, GL_UNSIGNED_INT, st, at(kCpuFloats * 4));
        per_instance(6);
      }
      if (as_splats) {
        glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, static_cast<GLsizei>(in_bucket[b]));
      } else {
        const GLsizei vertices = std::min<GLsizei>(1 << b, samples_);
        glDrawArraysInstanced(GL_POINTS, 0, b == kBuckets - 1 ? samples_ : vertices, static_cast<GLsizei>(in_bucket[b]));
      }
      ++s.draws;
    }
  };
  // The points: the picture, or with splats its coverage and where no
  // splat's colour reaches; then the close-ups' discs.
  draw_instances(0, kBuckets, false);
  const GLuint q = programs_[o.gpu_decode ? 1 : 0][1];
  if (in_bucket[kDiscBucket] > 0 || splats) set_uniforms(q, cache, camera, width, height, o);
  if (in_bucket[kDiscBucket] > 0) {
    glUniform1i(glGetUniformLocation(q, "visibility"), 2);
    glUniform1f(glGetUniformLocation(q, "splat_cut"), kDiscCut);
    glUniform1f(glGetUniformLocation(q, "cover2"), kDiscCut * kDiscCut);
    glUniform1f(glGetUniformLocation(q, "depth_offset"), 0.f);
    draw_instances(kDiscBucket, kDiscBucket + 1, true);
  }
  if (splats) {
    const GLint offset = glGetUniformLocation(q, "depth_offset");
    // Visibility: depth only, from each splat's core pushed back by
    // kVisibilityOffset radii.
    glClear(GL_DEPTH_BUFFER_BIT);
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glUniform1f(glGetUniformLocation(q, "splat_cut"), kSplatCut);
    glUniform1i(glGetUniformLocation(q, "visibility"), 1);
    glUniform1f(glGetUniformLocation(q, "core2"), kVisibilityCut * kVisibilityCut);
    glUniform1f(glGetUniformLocation(q, "cut2"), kSplatCut * kSplatCut);
    glUniform1f(offset, kVisibilityOffset);
    draw_instances(0, kBuckets + 1, true);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    // Attributes, into the accumulation (the same depth): every fragment
    // within that depth, its weight and weighted colour added up.
    glBindFramebuffer(GL_FRAMEBUFFER, accum_fbo_);
    glClear(GL_COLOR_BUFFER_BIT);
    glUniform1i(glGetUniformLocation(q, "visibility"), 0);
    glUniform1f(offset, 0.f);
    glDepthFunc(GL_LEQUAL);
    glDepthMask(GL_FALSE);
    glEnable(GL_BLEND);
    glBlendFunc(GL_ONE, GL_ONE);
    draw_instances(0, kBuckets + 1, true);
    glDisable(GL_BLEND);
    glDepthMask(GL_TRUE);
  }
  glBindVertexArray(0);
  if (offscreen) {
    glDisable(GL_DEPTH_TEST);
    // The frame the resolve starts from (alpha: covered): the points' own,
    // or the splats' normalized — which, without the resolve, is the picture.
    GLuint frame = scene_tex_;
    if (splats) {
      glBindFramebuffer(GL_FRAMEBUFFER, o.resolve ? fill_fbo_ : static_cast<GLuint>(caller));
      glUseProgram(normalize_program_);
      glActiveTexture(GL_TEXTURE1);
      glBindTexture(GL_TEXTURE_2D, scene_tex_);
      glUniform1i(glGetUniformLocation(normalize_program_, "cover"), 1);
      full_screen(normalize_program_, accum_tex_, clear);
      frame = fill_tex_;
    }
    if (o.resolve) {
      // The frames ping-pong between the scene's and the fill's textures.
      const auto other = [&](GLuint t) { return t == scene_tex_ ? fill_tex_ : scene_tex_; };
      const auto fbo_of = [&](GLuint t) { return t == scene_tex_ ? scene_fbo_ : fill_fbo_; };
      // Holes wider than a pixel, filled at half the resolution ...
      glBindFramebuffer(GL_FRAMEBUFFER, coarse_fbo_);
      glViewport(0, 0, (width + 1) / 2, (height + 1) / 2);
      full_screen(pull_program_, frame, clear);
      glViewport(0, 0, width, height);
      // ... pushed into the fill, which runs twice (the rims the coarse
      // level leaves), then trim and blend into the picture.
      for (int pass = 0; pass < 2; ++pass) {
        glBindFramebuffer(GL_FRAMEBUFFER, fbo_of(other(frame)));
        glUseProgram(fill_program_);
        glActiveTexture(GL_TEXTURE1);
        glBindTexture(GL_TEXTURE_2D, coarse_tex_);
        glUniform1i(glGetUniformLocation(fill_program_, "coarse"), 1);
        glUniform1i(glGetUniformLocation(fill_program_, "use_coarse"), pass == 0);
        full_screen(fill_program_, frame, clear);
        frame = other(frame);
      }
      glBindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(caller));
      full_screen(blend_program_, frame, clear);
    }
    glBindVertexArray(0);
    glEnable(GL_DEPTH_TEST);
  }
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
