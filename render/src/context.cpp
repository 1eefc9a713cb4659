#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cerrno>
#include <climits>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/renderer_in_use.hpp>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <sstream>
#include <vector>

#include "gl.hpp"

namespace clutterscope::render {

namespace {

std::string egl_error_name(EGLint code) {
  switch (code) {
    case EGL_SUCCESS:
      return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED:
      return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS:
      return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC:
      return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE:
      return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONTEXT:
      return "EGL_BAD_CONTEXT";
    case EGL_BAD_CONFIG:
      return "EGL_BAD_CONFIG";
    case EGL_BAD_DISPLAY:
      return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH:
      return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER:
      return "EGL_BAD_PARAMETER";
    default: {
      std::ostringstream text;
      text << "EGL error 0x" << std::hex << code;
      return text.str();
    }
  }
}

bool has_extension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const std::size_t length = std::strlen(name);
  for (const char* p = std::strstr(list, name); p != nullptr; p = std::strstr(p + 1, name)) {
    const bool starts = p == list || p[-1] == ' ';
    const bool ends = p[length] == '\0' || p[length] == ' ';
    if (starts && ends) return true;
  }
  return false;
}

template <typename Function>
Function egl_function(const char* name) {
  return reinterpret_cast<Function>(eglGetProcAddress(name));
}

// Which display a context uses. Mesa creates one llvmpipe screen per EGL display, and contexts
// on one screen rasterise one scene at a time (the screen's rasterizer queue is locked), so
// worker threads on one display do not render in parallel. The software device of the device
// platform and the surfaceless platform are two displays with independent screens: contexts
// of the software renderer are spread over both.
enum class DisplayKind {
  kChosen,               // the device picked by open_display (or the surfaceless fallback)
  kSurfacelessSoftware,  // the surfaceless platform as a second software screen
};

// An initialised EGL display shared by contexts of the process. EGL displays are per-device
// singletons and eglTerminate would destroy every other thread's context, so displays are
// reference-counted here and terminated only when the last context is gone.
struct SharedDisplay {
  EGLDisplay display = EGL_NO_DISPLAY;
  std::string description;       // which platform/device was used, for error messages
  bool software_device = false;  // a device with EGL_MESA_device_software
  int references = 0;
};

std::mutex& display_mutex() {
  static std::mutex mutex;
  return mutex;
}

// Keyed by requested device index (-1 = auto) and kind.
std::map<std::pair<int, DisplayKind>, SharedDisplay>& displays() {
  static std::map<std::pair<int, DisplayKind>, SharedDisplay> map;
  return map;
}

// Set when the surfaceless platform cannot serve as a second software screen (no such
// platform, or it renders on something else than the software device), so it is not retried.
bool& second_screen_refused() {
  static bool refused = false;
  return refused;
}

struct DeviceChoice {
  EGLDisplay display = EGL_NO_DISPLAY;
  std::string description;
  bool software_device = false;
};

auto platform_display_function() {
  return egl_function<PFNEGLGETPLATFORMDISPLAYEXTPROC>("eglGetPlatformDisplayEXT");
}

bool initialise(EGLDisplay display, const std::string& description, std::string* failures) {
  if (display == EGL_NO_DISPLAY) {
    *failures += "\n  " + description + ": no display (" + egl_error_name(eglGetError()) + ")";
    return false;
  }
  EGLint major = 0, minor = 0;
  if (eglInitialize(display, &major, &minor) != EGL_TRUE) {
    *failures +=
        "\n  " + description + ": eglInitialize failed (" + egl_error_name(eglGetError()) + ")";
    return false;
  }
  return true;
}

// The surfaceless Mesa platform, initialised, or EGL_NO_DISPLAY (reason in `failures`).
EGLDisplay open_surfaceless(std::string* failures) {
  const char* client_extensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  auto get_platform_display = platform_display_function();
  if (get_platform_display == nullptr ||
      !has_extension(client_extensions, "EGL_MESA_platform_surfaceless")) {
    *failures += "\n  EGL_MESA_platform_surfaceless: not supported by this EGL";
    return EGL_NO_DISPLAY;
  }
  EGLDisplay display =
      get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  return initialise(display, "surfaceless Mesa platform", failures) ? display : EGL_NO_DISPLAY;
}

// Device platform first (a hardware device preferred over EGL_MESA_device_software), then
// the surfaceless Mesa platform. Returns an initialised display or throws RenderError.
DeviceChoice open_display(int device_index) {
  const char* client_extensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  std::string failures;
  auto get_platform_display = platform_display_function();

  if (get_platform_display != nullptr &&
      has_extension(client_extensions, "EGL_EXT_platform_device")) {
    auto query_devices = egl_function<PFNEGLQUERYDEVICESEXTPROC>("eglQueryDevicesEXT");
    auto query_device_string =
        egl_function<PFNEGLQUERYDEVICESTRINGEXTPROC>("eglQueryDeviceStringEXT");
    EGLint count = 0;
    if (query_devices != nullptr && query_devices(0, nullptr, &count) == EGL_TRUE && count > 0) {
      std::vector<EGLDeviceEXT> devices(static_cast<std::size_t>(count));
      query_devices(count, devices.data(), &count);
      devices.resize(static_cast<std::size_t>(count));
      if (device_index >= count) {
        throw RenderError("EGL device index " + std::to_string(device_index) +
                          " requested, but only " + std::to_string(count) + " devices exist");
      }
      const auto is_software = [&](int i) {
        const char* extensions = query_device_string != nullptr
                                     ? query_device_string(devices[i], EGL_EXTENSIONS)
                                     : nullptr;
        return has_extension(extensions, "EGL_MESA_device_software");
      };
      // Candidate order: the requested device, else hardware devices before software ones.
      std::vector<int> order;
      if (device_index >= 0) {
        order.push_back(device_index);
      } else {
        for (int pass = 0; pass < 2; ++pass) {
          for (int i = 0; i < count; ++i) {
            if (is_software(i) == (pass == 1)) order.push_back(i);
          }
        }
      }
      for (const int i : order) {
        const std::string description = "EGL device " + std::to_string(i);
        EGLDisplay display = get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
        if (initialise(display, description, &failures)) {
          return {display, description, is_software(i)};
        }
      }
    } else {
      failures += "\n  EGL_EXT_device_enumeration: no devices";
    }
  } else {
    failures += "\n  EGL_EXT_platform_device: not supported by this EGL";
  }

  if (device_index < 0) {
    EGLDisplay display = open_surfaceless(&failures);
    if (display != EGL_NO_DISPLAY) return {display, "surfaceless Mesa platform", false};
  }
  throw RenderError(
      "no usable EGL display (install libegl1 libegl-mesa0 libgl1-mesa-dri for the software "
      "renderer, or a GPU driver with EGL):" +
      failures);
}

using DisplayKey = std::pair<int, DisplayKind>;

// Takes a reference on the display a new context should use: the chosen device, or, for the
// automatically chosen software device, whichever of it and the surfaceless platform holds
// fewer contexts.
DisplayKey acquire_display(int device_index, bool allow_second_screen) {
  std::lock_guard<std::mutex> lock(display_mutex());
  const DisplayKey chosen_key{device_index, DisplayKind::kChosen};
  SharedDisplay& chosen = displays()[chosen_key];
  if (chosen.references == 0) {
    DeviceChoice choice = open_display(device_index);
    chosen.display = choice.display;
    chosen.description = choice.description;
    chosen.software_device = choice.software_device;
  }
  if (allow_second_screen && device_index < 0 && chosen.software_device &&
      !second_screen_refused()) {
    const DisplayKey second_key{device_index, DisplayKind::kSurfacelessSoftware};
    SharedDisplay& second = displays()[second_key];
    if (second.references < chosen.references) {
      if (second.references == 0) {
        std::string failures;
        second.display = open_surfaceless(&failures);
        second.description = "surfaceless Mesa platform (second software screen)";
      }
      if (second.display != EGL_NO_DISPLAY) {
        ++second.references;
        return second_key;
      }
      second_screen_refused() = true;
    }
  }
  ++chosen.references;
  return chosen_key;
}

void release_display(const DisplayKey& key) {
  std::lock_guard<std::mutex> lock(display_mutex());
  SharedDisplay& shared = displays()[key];
  if (--shared.references == 0) {
    eglTerminate(shared.display);
    shared.display = EGL_NO_DISPLAY;
  }
}

SharedDisplay display_of(const DisplayKey& key) {
  std::lock_guard<std::mutex> lock(display_mutex());
  return displays()[key];
}

void refuse_second_screen() {
  std::lock_guard<std::mutex> lock(display_mutex());
  second_screen_refused() = true;
}

std::string gl_string(GLenum name) {
  const GLubyte* text = glGetString(name);
  return text != nullptr ? reinterpret_cast<const char*>(text) : "";
}

// The device index of CLUTTERSCOPE_EGL_DEVICE (unset or empty: -1, the automatic choice).
int device_index_from_environment() {
  const char* text = std::getenv("CLUTTERSCOPE_EGL_DEVICE");
  if (text == nullptr || *text == '\0') return -1;
  char* end = nullptr;
  errno = 0;
  const long value = std::strtol(text, &end, 10);
  if (*text < '0' || *text > '9' || *end != '\0' || errno == ERANGE || value > INT_MAX) {
    throw RenderError(std::string("CLUTTERSCOPE_EGL_DEVICE must be an EGL device index (an "
                                  "integer >= 0), got '") +
                      text + "'");
  }
  return static_cast<int>(value);
}

// GL_RENDERER (GL_VERSION) of the first context of the process, for renderer_in_use().
std::mutex& renderer_mutex() {
  static std::mutex mutex;
  return mutex;
}

std::string& first_renderer() {
  static std::string name;
  return name;
}

void record_renderer(const std::string& name) {
  const std::lock_guard<std::mutex> lock(renderer_mutex());
  if (first_renderer().empty()) first_renderer() = name;
}

}  // namespace

struct EglContext::State {
  DisplayKey key;
  EGLDisplay display = EGL_NO_DISPLAY;
  std::string display_description;
  EGLContext context = EGL_NO_CONTEXT;
  std::string renderer;
  std::string version;
};

EglContext::EglContext(std::unique_ptr<State> state) : state_(std::move(state)) {}
EglContext::EglContext(EglContext&&) noexcept = default;
EglContext& EglContext::operator=(EglContext&& other) noexcept {
  if (this != &other) {
    EglContext discarded(std::move(*this));
    state_ = std::move(other.state_);
  }
  return *this;
}

EglContext::~EglContext() {
  if (!state_) return;
  if (eglGetCurrentContext() == state_->context) {
    eglMakeCurrent(state_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  }
  eglDestroyContext(state_->display, state_->context);
  eglReleaseThread();
  release_display(state_->key);
}

EglContext EglContext::create(const EglOptions& options) {
  if (options.device_index < -1) {
    throw RenderError("EglOptions::device_index must be >= -1, got " +
                      std::to_string(options.device_index));
  }
  const int device_index =
      options.device_index == -1 ? device_index_from_environment() : options.device_index;
  for (bool allow_second = true;; allow_second = false) {
    try {
      EglContext context = create_on_display(device_index, allow_second);
      // The surfaceless platform may pick a GPU render node: the second screen must be the
      // same software renderer, or workers would not give identical results.
      if (context.state_->key.second == DisplayKind::kChosen || context.is_software()) {
        return context;
      }
    } catch (const RenderError&) {
      if (!allow_second) throw;
    }
    refuse_second_screen();
  }
}

EglContext EglContext::create_on_display(int device_index, bool allow_second_screen) {
  auto state = std::make_unique<State>();
  state->key = acquire_display(device_index, allow_second_screen);
  const SharedDisplay shared = display_of(state->key);
  state->display = shared.display;
  state->display_description = shared.description;
  struct DisplayGuard {  // gives the display reference back if creation fails below
    State* state;
    ~DisplayGuard() {
      if (state != nullptr) release_display(state->key);
    }
  } guard{state.get()};

  if (eglBindAPI(EGL_OPENGL_API) != EGL_TRUE) {  // per thread
    throw RenderError("eglBindAPI(EGL_OPENGL_API) failed: " + egl_error_name(eglGetError()));
  }
  const char* display_extensions = eglQueryString(state->display, EGL_EXTENSIONS);
  if (!has_extension(display_extensions, "EGL_KHR_surfaceless_context")) {
    throw RenderError("EGL display lacks EGL_KHR_surfaceless_context");
  }

  EGLConfig config = nullptr;
  EGLint config_count = 0;
  for (const EGLint surface_type : {EGLint{EGL_PBUFFER_BIT}, EGLint{EGL_DONT_CARE}}) {
    const EGLint attributes[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE,
                                 surface_type, EGL_NONE};
    if (eglChooseConfig(state->display, attributes, &config, 1, &config_count) == EGL_TRUE &&
        config_count > 0) {
      break;
    }
  }
  if (config_count == 0) {
    if (!has_extension(display_extensions, "EGL_KHR_no_config_context")) {
      throw RenderError("no EGL config with desktop OpenGL support");
    }
    config = EGL_NO_CONFIG_KHR;
  }

  // Desktop GL core, newest first (llvmpipe refuses 4.6).
  const std::pair<int, int> versions[] = {{4, 6}, {4, 5}, {4, 3}, {3, 3}};
  std::string tried;
  for (const auto& [major, minor] : versions) {
    const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                 major,
                                 EGL_CONTEXT_MINOR_VERSION,
                                 minor,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                 EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                 EGL_NONE};
    state->context = eglCreateContext(state->display, config, EGL_NO_CONTEXT, attributes);
    if (state->context != EGL_NO_CONTEXT) break;
    tried += " " + std::to_string(major) + "." + std::to_string(minor) + " (" +
             egl_error_name(eglGetError()) + ")";
  }
  if (state->context == EGL_NO_CONTEXT) {
    throw RenderError("cannot create a desktop OpenGL core context; tried" + tried);
  }
  if (eglMakeCurrent(state->display, EGL_NO_SURFACE, EGL_NO_SURFACE, state->context) != EGL_TRUE) {
    const std::string error = egl_error_name(eglGetError());
    eglDestroyContext(state->display, state->context);
    throw RenderError("eglMakeCurrent failed: " + error);
  }
  state->renderer = gl_string(GL_RENDERER);
  state->version = gl_string(GL_VERSION);
  record_renderer(state->renderer + " (" + state->version + ")");
  guard.state = nullptr;
  return EglContext(std::move(state));
}

void EglContext::make_current() const {
  if (!state_) throw RenderError("make_current on a moved-from EglContext");
  eglBindAPI(EGL_OPENGL_API);
  if (eglMakeCurrent(state_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, state_->context) !=
      EGL_TRUE) {
    throw RenderError("eglMakeCurrent failed: " + egl_error_name(eglGetError()));
  }
}

std::string renderer_in_use() {
  const std::lock_guard<std::mutex> lock(renderer_mutex());
  return first_renderer();
}

std::string EglContext::renderer() const { return state_ ? state_->renderer : ""; }
std::string EglContext::version() const { return state_ ? state_->version : ""; }
std::string EglContext::display_description() const {
  return state_ ? state_->display_description : "";
}

bool EglContext::is_software() const {
  const std::string& name = renderer();
  for (const char* software : {"llvmpipe", "softpipe", "swrast", "SWR", "lavapipe"}) {
    if (name.find(software) != std::string::npos) return true;
  }
  return false;
}

bool egl_available(std::string* why_not) {
  try {
    release_display(acquire_display(-1, false));
    return true;
  } catch (const RenderError& error) {
    if (why_not != nullptr) *why_not = error.what();
    return false;
  }
}

WorkerRasterisationScope::WorkerRasterisationScope() {
  if (std::getenv("LP_NUM_THREADS") == nullptr) {
    set_ = ::setenv("LP_NUM_THREADS", "0", 1) == 0;
  }
}

WorkerRasterisationScope::~WorkerRasterisationScope() {
  if (set_) ::unsetenv("LP_NUM_THREADS");
}

}  // namespace clutterscope::render
