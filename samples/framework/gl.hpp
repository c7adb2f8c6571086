#pragma once
// The OpenGL of the platform, included before any other GL header: desktop OpenGL through epoxy natively, OpenGL ES
// 3.0 (WebGL2 in the browser) under emscripten. glsl_version is the version line the samples' shaders are compiled
// with (render.cpp's compile() puts it in front of a source that has none): GLSL 3.30 core and GLSL ES 3.00 read the
// same shaders once the ES one has a default float precision.
#ifdef __EMSCRIPTEN__
#include <GLES3/gl3.h>
#else
#include <epoxy/gl.h>
#endif

namespace sample {

#ifdef __EMSCRIPTEN__
inline constexpr const char* glsl_version = "#version 300 es\nprecision highp float;\n";
#else
inline constexpr const char* glsl_version = "#version 330 core\n";
#endif

// True while a GL context is current: the renderers' destructors delete their objects only then (a sample's
// renderers may outlive its window, whose context took its objects with it).
bool has_current_context();

}  // namespace sample
