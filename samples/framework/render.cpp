#include "render.hpp"  // the GL header first: it must precede every other GL header

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <string>
#include <string_view>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#ifdef __EMSCRIPTEN__
#include <emscripten/html5.h>
#else
#include <GLFW/glfw3.h>
#include <stb/stb_image.h>
#endif

namespace sample {

#ifdef __EMSCRIPTEN__
bool has_current_context() { return emscripten_webgl_get_current_context() != 0; }
#else
bool has_current_context() { return glfwGetCurrentContext() != nullptr; }
#endif

// ---------------------------------------------------------------------------------------------------------------
// Camera

void OrbitCamera::handle(const Input& input, glm::ivec2 viewport) {
  const float scale = 1.0f / float(std::max(1, viewport.y));
  const bool pan = input.middle_down || (input.right_down && input.shift);
  if (pan) {
    const glm::mat4 inv = glm::inverse(view());
    const glm::vec3 right(inv[0]), up(inv[1]);
    target -= (right * input.mouse_delta.x - up * input.mouse_delta.y) * distance * scale;
  } else if (input.right_down) {
    yaw -= input.mouse_delta.x * scale * 3.0f;
    pitch = std::clamp(pitch + input.mouse_delta.y * scale * 3.0f, -1.5f, 1.5f);
  }
  if (input.scroll != 0.0f) distance = std::clamp(distance * std::pow(0.88f, input.scroll), 0.1f, 100.0f);
  // Above the floor: the target first, then the eye (target.y + distance · sin(pitch) >= floor, which a target on
  // or above it always allows), after every kind of move, since zooming in can lift a low eye's bound too.
  target.y = std::max(target.y, floor);
  pitch = std::max(pitch, std::asin(std::clamp((floor - target.y) / distance, -1.0f, 0.0f)));
}

glm::vec3 OrbitCamera::eye() const {
  return target +
         distance * glm::vec3(std::cos(pitch) * std::sin(yaw), std::sin(pitch), std::cos(pitch) * std::cos(yaw));
}

glm::mat4 OrbitCamera::view() const { return glm::lookAt(eye(), target, glm::vec3(0, 1, 0)); }

glm::mat4 OrbitCamera::projection(float aspect) const {
  const glm::mat4 shift = glm::translate(glm::mat4(1.0f), glm::vec3(shift_x, 0.0f, 0.0f));  // x += shift_x · w
  return shift * glm::perspective(fov_y, aspect, 0.01f * distance, 100.0f * distance);
}

// ---------------------------------------------------------------------------------------------------------------
// Shaders

namespace {

// A source without a version line gets the context's (glsl_version); one with its own is compiled as it is.
GLuint compile(GLenum kind, const char* source) {
  const GLuint shader = glCreateShader(kind);
  const bool versioned = std::string_view(source).starts_with("#version");
  const char* sources[] = {glsl_version, source};
  glShaderSource(shader, versioned ? 1 : 2, versioned ? sources + 1 : sources, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetShaderInfoLog(shader, sizeof log, nullptr, log);
    std::fprintf(stderr, "shader compilation failed:\n%s\n", log);
    std::abort();
  }
  return shader;
}

GLuint link(std::initializer_list<GLuint> shaders) {
  const GLuint program = glCreateProgram();
  for (GLuint s : shaders) glAttachShader(program, s);
  glLinkProgram(program);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetProgramInfoLog(program, sizeof log, nullptr, log);
    std::fprintf(stderr, "program link failed:\n%s\n", log);
    std::abort();
  }
  for (GLuint s : shaders) glDeleteShader(s);
  return program;
}

const char* mesh_vs = R"(layout(location = 0) in vec2 uv;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec3 position;
uniform mat4 model, view, projection;
out vec3 world_position; out vec3 world_normal; out vec2 tex;
void main() {
  vec4 p = model * vec4(position, 1.0);
  world_position = p.xyz;
  world_normal = mat3(transpose(inverse(model))) * normal;
  tex = uv;
  gl_Position = projection * view * p;
})";

// Blinn-Phong with the MTL colours; map_Kd modulates Kd.
const char* mesh_fs = R"(in vec3 world_position; in vec3 world_normal; in vec2 tex;
uniform vec3 eye, ka, kd, ks, tint; uniform float shininess; uniform bool textured; uniform sampler2D diffuse_map;
out vec4 colour;
void main() {
  vec3 n = normalize(world_normal);
  vec3 v = normalize(eye - world_position);
  if (dot(n, v) < 0.0) n = -n;
  vec3 albedo = kd * tint * (textured ? texture(diffuse_map, tex).rgb : vec3(1.0));
  vec3 result = ka * 0.25 * albedo;
  vec3 lights[2] = vec3[](normalize(vec3(0.4, 1.0, 0.7)), normalize(vec3(-0.6, 0.3, -0.5)));
  float power[2] = float[](0.85, 0.35);
  for (int i = 0; i < 2; ++i) {
    vec3 h = normalize(lights[i] + v);
    result += power[i] * (albedo * max(dot(n, lights[i]), 0.0) +
                          ks * pow(max(dot(n, h), 0.0), max(shininess, 1.0)));
  }
  colour = vec4(pow(result + 0.12 * albedo, vec3(1.0 / 1.6)), 1.0);
})";

const char* overlay_vs = R"(layout(location = 0) in vec3 position;
layout(location = 1) in vec4 colour_size;
uniform mat4 view_projection;
out vec3 colour;
void main() { colour = colour_size.rgb; gl_PointSize = colour_size.a; gl_Position = view_projection * vec4(position, 1.0); })";

const char* overlay_fs = R"(in vec3 colour; out vec4 result;
void main() { result = vec4(colour, 1.0); })";

}  // namespace

GLuint build_program(const char* vertex_source, const char* fragment_source) {
  return link({compile(GL_VERTEX_SHADER, vertex_source), compile(GL_FRAGMENT_SHADER, fragment_source)});
}

// ---------------------------------------------------------------------------------------------------------------
// MeshRenderer

// Renderers may outlive their window (a sample's locals outlive run_sample): without a context there is nothing left
// to delete, the context took its objects with it.
MeshRenderer::~MeshRenderer() {
  if (!vao_ || !has_current_context()) return;
  glDeleteVertexArrays(1, &vao_);
  glDeleteBuffers(1, &vbo_);
  glDeleteBuffers(1, &ibo_);
  glDeleteProgram(program_);
  for (GLuint t : textures_)
    if (t) glDeleteTextures(1, &t);
}

void MeshRenderer::create(const deform::Mesh& mesh) {
  mesh_ = &mesh;
  program_ = build_program(mesh_vs, mesh_fs);
  interleaved_.assign(mesh.vertex_count() * floats_per_vertex, 0.0f);
  for (std::size_t v = 0; v < mesh.vertex_count() && !mesh.vertex_uvs.empty(); ++v) {
    interleaved_[v * floats_per_vertex + 0] = mesh.vertex_uvs[v].x;
    interleaved_[v * floats_per_vertex + 1] = mesh.vertex_uvs[v].y;
  }
  glGenVertexArrays(1, &vao_);
  glBindVertexArray(vao_);
  glGenBuffers(1, &vbo_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(interleaved_.size() * sizeof(float)), interleaved_.data(), GL_STREAM_DRAW);
  const GLsizei stride = floats_per_vertex * sizeof(float);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(0));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(2 * sizeof(float)));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(5 * sizeof(float)));
  glGenBuffers(1, &ibo_);
  glBindVertexArray(0);
  set_triangles({}, {});

  textures_.assign(mesh.materials.size(), 0);
#ifndef __EMSCRIPTEN__  // the browser has no files: a page sets its textures from memory (set_texture_rgb)
  for (std::size_t m = 0; m < mesh.materials.size(); ++m) {
    const deform::Material& material = mesh.materials[m];
    const std::string& path = material.diffuse_map;
    const std::vector<std::uint8_t>* embedded = material.diffuse_image.get();  // an image inside the model file
    if (embedded == nullptr && (path.empty() || !std::ifstream(path))) continue;
    if (embedded != nullptr && embedded->size() > std::size_t(std::numeric_limits<int>::max())) continue;
    int w = 0, h = 0, channels = 0;
    stbi_set_flip_vertically_on_load(1);
    unsigned char* pixels = embedded != nullptr
                                ? stbi_load_from_memory(embedded->data(), int(embedded->size()), &w, &h, &channels, 4)
                                : stbi_load(path.c_str(), &w, &h, &channels, 4);
    if (!pixels) {
      std::fprintf(stderr, "warning: cannot load texture %s: %s\n",
                   embedded != nullptr ? ("of material " + material.name).c_str() : path.c_str(),
                   stbi_failure_reason());
      continue;
    }
    glGenTextures(1, &textures_[m]);
    glBindTexture(GL_TEXTURE_2D, textures_[m]);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_SRGB8_ALPHA8, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, pixels);
    glGenerateMipmap(GL_TEXTURE_2D);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    stbi_image_free(pixels);
  }
#endif
}

void MeshRenderer::set_texture_rgb(std::size_t material, int width, int height, const std::uint8_t* pixels) {
  if (material >= textures_.size()) return;
  if (!textures_[material]) glGenTextures(1, &textures_[material]);
  // GL's texture rows run bottom-up (v = 0 first): upload the rows in reverse. As RGBA: OpenGL ES 3.0 (WebGL2) makes
  // mipmaps of sRGB textures only with alpha (GL_SRGB8 is not colour-renderable there).
  std::vector<std::uint8_t> flipped(std::size_t(width) * std::size_t(height) * 4);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const std::uint8_t* from = pixels + (std::size_t(height - 1 - y) * std::size_t(width) + std::size_t(x)) * 3;
      std::uint8_t* to = flipped.data() + (std::size_t(y) * std::size_t(width) + std::size_t(x)) * 4;
      to[0] = from[0], to[1] = from[1], to[2] = from[2], to[3] = 255;
    }
  glBindTexture(GL_TEXTURE_2D, textures_[material]);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_SRGB8_ALPHA8, width, height, 0, GL_RGBA, GL_UNSIGNED_BYTE, flipped.data());
  glGenerateMipmap(GL_TEXTURE_2D);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
}

void MeshRenderer::set_triangles(std::span<const std::uint32_t> triangles, std::span<const deform::Submesh> submeshes) {
  const bool own = triangles.empty();
  const std::span<const std::uint32_t> drawn = own ? std::span<const std::uint32_t>(mesh_->triangles) : triangles;
  const std::span<const deform::Submesh> groups = own ? std::span<const deform::Submesh>(mesh_->submeshes) : submeshes;
  submeshes_.assign(groups.begin(), groups.end());
  glBindVertexArray(vao_);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo_);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, GLsizeiptr(drawn.size() * sizeof(std::uint32_t)), drawn.data(), GL_STATIC_DRAW);
  glBindVertexArray(0);
}

std::size_t MeshRenderer::triangle_count() const {
  std::size_t count = 0;
  for (const deform::Submesh& s : submeshes_) count += s.triangle_count;
  return count;
}

void MeshRenderer::upload(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals) {
  float* out = interleaved_.data();
  for (std::size_t v = 0; v < positions.size(); ++v, out += floats_per_vertex) {
    out[2] = normals[v].x, out[3] = normals[v].y, out[4] = normals[v].z;
    out[5] = positions[v].x, out[6] = positions[v].y, out[7] = positions[v].z;
  }
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glBufferSubData(GL_ARRAY_BUFFER, 0, GLsizeiptr(interleaved_.size() * sizeof(float)), interleaved_.data());
}

void MeshRenderer::draw(const glm::mat4& model, const glm::mat4& view, const glm::mat4& projection, glm::vec3 eye,
                        glm::vec3 tint) const {
  glUseProgram(program_);
  glUniformMatrix4fv(glGetUniformLocation(program_, "model"), 1, GL_FALSE, glm::value_ptr(model));
  glUniformMatrix4fv(glGetUniformLocation(program_, "view"), 1, GL_FALSE, glm::value_ptr(view));
  glUniformMatrix4fv(glGetUniformLocation(program_, "projection"), 1, GL_FALSE, glm::value_ptr(projection));
  glUniform3fv(glGetUniformLocation(program_, "eye"), 1, glm::value_ptr(eye));
  glUniform3fv(glGetUniformLocation(program_, "tint"), 1, glm::value_ptr(tint));
  glUniform1i(glGetUniformLocation(program_, "diffuse_map"), 0);
  glBindVertexArray(vao_);
  for (const deform::Submesh& s : submeshes_) {
    const deform::Material fallback;
    const deform::Material& m = s.material >= 0 && std::size_t(s.material) < mesh_->materials.size()
                                    ? mesh_->materials[std::size_t(s.material)]
                                    : fallback;
    const GLuint texture =
        s.material >= 0 && std::size_t(s.material) < textures_.size() ? textures_[std::size_t(s.material)] : 0;
    glUniform3fv(glGetUniformLocation(program_, "ka"), 1, glm::value_ptr(m.ambient));
    glUniform3fv(glGetUniformLocation(program_, "kd"), 1, glm::value_ptr(m.diffuse));
    glUniform3fv(glGetUniformLocation(program_, "ks"), 1, glm::value_ptr(m.specular));
    glUniform1f(glGetUniformLocation(program_, "shininess"), m.shininess);
    glUniform1i(glGetUniformLocation(program_, "textured"), texture != 0);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, texture);
    glDrawElements(GL_TRIANGLES, GLsizei(s.triangle_count * 3), GL_UNSIGNED_INT,
                   reinterpret_cast<void*>(std::size_t(s.first_triangle) * 3 * sizeof(std::uint32_t)));
  }
  glBindVertexArray(0);
}

// ---------------------------------------------------------------------------------------------------------------
// OverlayRenderer

OverlayRenderer::~OverlayRenderer() {
  if (!vao_ || !has_current_context()) return;
  glDeleteVertexArrays(1, &vao_);
  glDeleteBuffers(1, &vbo_);
  glDeleteProgram(program_);
}

void OverlayRenderer::create() {
  program_ = build_program(overlay_vs, overlay_fs);
  glGenVertexArrays(1, &vao_);
  glGenBuffers(1, &vbo_);
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 7 * sizeof(float), reinterpret_cast<void*>(0));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, 7 * sizeof(float), reinterpret_cast<void*>(3 * sizeof(float)));
  glBindVertexArray(0);
}

void OverlayRenderer::line(glm::vec3 a, glm::vec3 b, glm::vec3 c) {
  lines_.insert(lines_.end(), {a.x, a.y, a.z, c.x, c.y, c.z, 1.0f, b.x, b.y, b.z, c.x, c.y, c.z, 1.0f});
}

void OverlayRenderer::triangle(glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 ca, glm::vec3 cb, glm::vec3 cc) {
  triangles_.insert(triangles_.end(), {a.x,  a.y,  a.z,  ca.x, ca.y, ca.z, 1.0f, b.x,  b.y,  b.z, cb.x,
                                       cb.y, cb.z, 1.0f, c.x,  c.y,  c.z,  cc.x, cc.y, cc.z, 1.0f});
}

void OverlayRenderer::point(glm::vec3 p, glm::vec3 c, float size) {
  points_.insert(points_.end(), {p.x, p.y, p.z, c.x, c.y, c.z, size});
}

void OverlayRenderer::flush(const glm::mat4& view_projection, bool on_top) {
  glUseProgram(program_);
  glUniformMatrix4fv(glGetUniformLocation(program_, "view_projection"), 1, GL_FALSE, glm::value_ptr(view_projection));
#ifdef GL_PROGRAM_POINT_SIZE  // desktop GL; OpenGL ES always takes gl_PointSize
  glEnable(GL_PROGRAM_POINT_SIZE);
#endif
  if (on_top) glDisable(GL_DEPTH_TEST);
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, vbo_);
  for (auto [data, mode] : {std::pair{&triangles_, GLenum(GL_TRIANGLES)}, std::pair{&lines_, GLenum(GL_LINES)},
                            std::pair{&points_, GLenum(GL_POINTS)}}) {
    if (data->empty()) continue;
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(data->size() * sizeof(float)), data->data(), GL_STREAM_DRAW);
    glDrawArrays(mode, 0, GLsizei(data->size() / 7));
    data->clear();
  }
  glBindVertexArray(0);
  if (on_top) glEnable(GL_DEPTH_TEST);
}

}  // namespace sample
