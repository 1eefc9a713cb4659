#pragma once

// Headless OpenGL through EGL: device platform first, surfaceless Mesa as fallback, desktop GL
// core with version fallback. One context per worker thread.
//
// With the software renderer (Mesa llvmpipe), contexts on one EGL display share one llvmpipe
// screen, which rasterises one scene at a time, so worker threads would wait for each other.
// The automatically chosen software device and the surfaceless platform are two displays with
// independent screens: each new context goes to the one holding fewer contexts (checked to be
// the same software renderer). Mesa offers no third software display, so with more than two
// workers contexts share screens.

#include <memory>
#include <stdexcept>
#include <string>

namespace clutterscope::render {

// Rendering or GL/EGL runtime failure; the CLI maps it to exit code 4.
class RenderError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct EglOptions {
  // EGL device index to use; -1 picks a hardware device when one exists, else the software one
  // (then spread over two software screens, see above).
  int device_index = -1;
};

// An EGL display + GL context made current on the creating thread. Move-only; a shared display
// is terminated only with its last context (earlier would kill other threads' contexts).
class EglContext {
 public:
  static EglContext create(const EglOptions& options = {});  // throws RenderError

  EglContext(EglContext&&) noexcept;
  EglContext& operator=(EglContext&&) noexcept;
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;
  ~EglContext();

  void make_current() const;     // for use on the thread that owns the context
  std::string renderer() const;  // GL_RENDERER
  std::string version() const;   // GL_VERSION
  bool is_software() const;      // llvmpipe / softpipe
  // The EGL display the context lives on: "EGL device N", "surfaceless Mesa platform" or
  // "surfaceless Mesa platform (second software screen)".
  std::string display_description() const;

 private:
  struct State;
  explicit EglContext(std::unique_ptr<State> state);
  static EglContext create_on_display(int device_index, bool allow_second_screen);
  std::unique_ptr<State> state_;
};

// While alive and LP_NUM_THREADS is unset, sets LP_NUM_THREADS=0 so that every worker's
// context rasterises on the worker's own thread: `--jobs N` then uses N cores, as a cluster
// allocation of N cores expects. llvmpipe's own rasteriser threads would add synchronisation
// (16.5 against 21 ms CPU per visibility image) and, at --jobs 1, bought 7-28% throughput for
// 17-46% more CPU. llvmpipe reads the variable when a display is initialised, so create the
// scope before the workers' contexts and while no other thread runs. No effect on hardware
// drivers.
class WorkerRasterisationScope {
 public:
  WorkerRasterisationScope();
  ~WorkerRasterisationScope();
  WorkerRasterisationScope(const WorkerRasterisationScope&) = delete;
  WorkerRasterisationScope& operator=(const WorkerRasterisationScope&) = delete;

 private:
  bool set_ = false;
};

// True when an EGL display can be opened at all (tests skip with a message when not).
bool egl_available(std::string* why_not = nullptr);

}  // namespace clutterscope::render
