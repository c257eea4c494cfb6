#include "sim/egl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/gl.h>

#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace hgrasp::sim {
namespace {

// Mesa's software renderer (llvmpipe) rasterises on a thread per core by default. The twin's
// frames are 320 x 240 and its scenes run beside each other (a sweep's jobs, ctest -j2): on this
// project's 2-core machine the threads' hand-offs cost more than they save. Measured on the
// default scenario (`hgrasp run --no-video`, two runs each, 2026-12-08): with a thread per core
// 10.0-10.4 s wall and 12.2-12.7 s of CPU; with one worker thread (LP_NUM_THREADS=1) 10.7-10.9 s
// and 11.1 s; in the calling thread (LP_NUM_THREADS=0) 9.0-9.2 s and 9.1-9.3 s. A colour-only
// stereo frame 15.0 -> 13.4 ms, a full one 108 -> 113 ms; the images are the same bytes. So the
// rendering stays in the thread that asks for it unless the environment says otherwise. Set
// before main (no thread yet to race the environment); a GPU's driver never reads it.
const bool kLlvmpipeInCallingThread = [] {
  ::setenv("LP_NUM_THREADS", "0", /*overwrite=*/0);
  return true;
}();

[[noreturn]] void Fail(const char* what) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "EGL: %s failed (error 0x%04x)", what, eglGetError());
  throw std::runtime_error(buf);
}

bool HasExtension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const size_t n = std::strlen(name);
  for (const char* p = std::strstr(list, name); p != nullptr; p = std::strstr(p + n, name)) {
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  }
  return false;
}

// A hardware EGL device, or EGL_NO_DISPLAY when there is none (or software is forced).
EGLDisplay HardwareDisplay(std::string* description) {
  const char* forced = std::getenv("HGRASP_EGL_DEVICE");
  if (forced != nullptr && std::strcmp(forced, "software") == 0) return EGL_NO_DISPLAY;
  const char* platform = std::getenv("EGL_PLATFORM");
  if (platform != nullptr && std::strcmp(platform, "surfaceless") == 0) return EGL_NO_DISPLAY;
  auto query_devices =
      reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  auto query_string = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
      eglGetProcAddress("eglQueryDeviceStringEXT"));
  auto platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (!query_devices || !query_string || !platform_display) return EGL_NO_DISPLAY;
  EGLint n = 0;
  if (!query_devices(0, nullptr, &n) || n <= 0) return EGL_NO_DISPLAY;
  std::vector<EGLDeviceEXT> devices(n);
  query_devices(n, devices.data(), &n);
  for (EGLint i = 0; i < n; ++i) {
    const char* ext = query_string(devices[i], EGL_EXTENSIONS);
    if (HasExtension(ext, "EGL_MESA_device_software")) continue;
    EGLDisplay d = platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
    if (d == EGL_NO_DISPLAY) continue;
    EGLint major = 0, minor = 0;
    if (!eglInitialize(d, &major, &minor)) continue;
    *description = "EGL device " + std::to_string(i);
    return d;
  }
  return EGL_NO_DISPLAY;
}

}  // namespace

EglContext::EglContext() {
  EGLDisplay display = HardwareDisplay(&description_);
  if (display == EGL_NO_DISPLAY) {
    auto platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (!platform_display) Fail("eglGetProcAddress(eglGetPlatformDisplayEXT)");
    display = platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (display == EGL_NO_DISPLAY) Fail("eglGetPlatformDisplayEXT(surfaceless)");
    EGLint major = 0, minor = 0;
    if (!eglInitialize(display, &major, &minor)) Fail("eglInitialize(surfaceless)");
    description_ = "Mesa surfaceless";
  }
  const EGLint config_attribs[] = {EGL_RED_SIZE,   8,  EGL_GREEN_SIZE,      8,
                                   EGL_BLUE_SIZE,  8,  EGL_ALPHA_SIZE,      8,
                                   EGL_DEPTH_SIZE, 24, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                                   EGL_NONE};
  EGLConfig config = nullptr;
  EGLint num_configs = 0;
  if (!eglChooseConfig(display, config_attribs, &config, 1, &num_configs)) {
    Fail("eglChooseConfig");
  }
  if (!eglBindAPI(EGL_OPENGL_API)) Fail("eglBindAPI(EGL_OPENGL_API)");
  // MuJoCo 2.2 draws with the fixed-function pipeline: the default (compatibility) profile.
  EGLContext context = eglCreateContext(display, num_configs > 0 ? config : EGL_NO_CONFIG_KHR,
                                        EGL_NO_CONTEXT, nullptr);
  if (context == EGL_NO_CONTEXT) Fail("eglCreateContext");
  display_ = display;
  context_ = context;
  MakeCurrent();
  const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  if (renderer != nullptr) description_ += std::string(" (") + renderer + ")";
}

EglContext::~EglContext() {
  if (display_ != nullptr) {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (context_ != nullptr) eglDestroyContext(display_, context_);
    eglTerminate(display_);
  }
}

void EglContext::MakeCurrent() {
  if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_)) {
    Fail("eglMakeCurrent");
  }
}

}  // namespace hgrasp::sim
