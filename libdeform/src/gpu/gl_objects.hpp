#pragma once
// Internal to deform::gpu: the GL objects both kinds of compute work build (a storage buffer, a compute program).
// Include after <epoxy/gl.h>; every call needs a current OpenGL 4.3 context.
#include <algorithm>
#include <cstddef>
#include <string>

namespace deform::gpu_detail {

// A shader storage buffer holding `bytes` of `data` (or uninitialised when data is null), never of zero size: an empty
// binding still binds valid storage.
inline GLuint storage_buffer(const void* data, std::size_t bytes, GLenum usage) {
  GLuint buffer = 0;
  glGenBuffers(1, &buffer);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, buffer);
  glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(std::max<std::size_t>(bytes, 16)), nullptr, usage);
  if (data && bytes) glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(bytes), data);
  return buffer;
}

// The driver's message about a shader or a program (get_parameter: glGetShaderiv or glGetProgramiv; get_log: the
// matching glGet...InfoLog).
template <class GetParameter, class GetLog>
std::string info_log(GLuint object, GetParameter get_parameter, GetLog get_log) {
  GLint length = 0;
  get_parameter(object, GL_INFO_LOG_LENGTH, &length);
  std::string log(std::size_t(std::max(length, 1)), '\0');
  get_log(object, GLsizei(log.size()), nullptr, log.data());
  log.resize(std::min(log.find('\0'), log.size()));
  return log;
}

// The compute program for `source`, or 0 with the driver's message in `log`.
inline GLuint build_compute_program(const char* source, std::string& log) {
  const GLuint shader = glCreateShader(GL_COMPUTE_SHADER);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    log = info_log(shader, glGetShaderiv, glGetShaderInfoLog);
    glDeleteShader(shader);
    return 0;
  }
  const GLuint program = glCreateProgram();
  glAttachShader(program, shader);
  glLinkProgram(program);
  glDetachShader(program, shader);
  glDeleteShader(shader);
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    log = info_log(program, glGetProgramiv, glGetProgramInfoLog);
    glDeleteProgram(program);
    return 0;
  }
  return program;
}

}  // namespace deform::gpu_detail
