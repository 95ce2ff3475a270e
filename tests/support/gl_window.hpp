#pragma once
// A hidden GLFW window whose OpenGL 3.3 core context the render tests draw in (into an
// OffscreenTarget, not the window's own framebuffer). Null without an X display or such a context:
// the tests then skip, or fail under PHACO_TEST_STRICT=1 (environment.hpp).
#include <GLFW/glfw3.h>

#include <cstdlib>

#include "tests/support/environment.hpp"

namespace phaco::test {

// Makes the context current. Pair with glfwDestroyWindow and glfwTerminate.
inline GLFWwindow* make_hidden_gl_window(const char* title) {
  if (!std::getenv("DISPLAY") || !glfwInit()) return nullptr;
  glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  GLFWwindow* window = glfwCreateWindow(64, 64, title, nullptr, nullptr);
  if (window) glfwMakeContextCurrent(window);
  return window;
}

// Destroys the window (if any) and ends GLFW: a test suite's TearDownTestSuite.
inline void close_gl_window(GLFWwindow*& window) {
  if (window) glfwDestroyWindow(window);
  window = nullptr;
  glfwTerminate();
}

}  // namespace phaco::test

// In a test's SetUp: skips it (fails it under PHACO_TEST_STRICT=1) when there is no display or
// `window` got no context, saying which.
#define PHACO_REQUIRE_GL_WINDOW(window)                                                \
  do {                                                                                 \
    PHACO_REQUIRE_ENVIRONMENT(std::getenv("DISPLAY") != nullptr,                       \
                              "no X display ($DISPLAY unset): run under xvfb-run");    \
    PHACO_REQUIRE_ENVIRONMENT((window) != nullptr,                                     \
                              "no OpenGL 3.3 core context from GLFW on this display"); \
  } while (0)
