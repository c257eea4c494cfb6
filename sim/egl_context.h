#pragma once
/// @file A headless OpenGL context through EGL, for MuJoCo's off-screen renderer. No X server.
///
/// On a machine with a GPU, the first EGL device that is not Mesa's software device is used; on a
/// machine without one, Mesa's surfaceless platform (llvmpipe). EGL_PLATFORM=surfaceless and
/// HGRASP_EGL_DEVICE=software force the software path.
/// llvmpipe renders in the calling thread (LP_NUM_THREADS=0) unless the environment sets
/// LP_NUM_THREADS: see egl_context.cc for why.

#include <string>

namespace hgrasp::sim {

class EglContext {
 public:
  /// Creates the context and makes it current on the calling thread. Throws std::runtime_error
  /// naming the EGL call and error code when no context can be had.
  EglContext();
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  /// Makes the context current on the calling thread again.
  void MakeCurrent();

  /// "EGL device 0 (NVIDIA ...)" or "Mesa surfaceless (llvmpipe ...)": what renders.
  const std::string& description() const { return description_; }

 private:
  void* display_ = nullptr;
  void* context_ = nullptr;
  std::string description_;
};

}  // namespace hgrasp::sim
